//! The conformance kit for every preset, plus structural validation on the same scenes.

use rt_conformance::SCENES;
use rt_core::{Accel, Sphere, Triangle};
use rt_grid::{Grid, GridParams};

rt_conformance::conformance_tests!(standard, Grid<Triangle>, GridParams::standard());
rt_conformance::conformance_tests!(no_mailbox, Grid<Triangle>, GridParams::no_mailbox());
rt_conformance::conformance_tests!(bbox, Grid<Triangle>, GridParams::bbox_insertion());
rt_conformance::conformance_tests!(
    coarse,
    Grid<Triangle>,
    GridParams {
        density: 0.05,
        ..GridParams::standard()
    }
);
rt_conformance::conformance_tests!(
    fine,
    Grid<Triangle>,
    GridParams {
        density: 64.0,
        ..GridParams::standard()
    }
);

#[test]
fn spheres_standard() {
    rt_conformance::check_random_spheres::<Grid<Sphere>>(&GridParams::standard());
}

#[test]
fn validate_passes_on_every_scene_and_preset() {
    for (name, params) in Grid::<Triangle>::presets() {
        for scene in SCENES {
            let s = rt_conformance::scene(scene);
            let grid = Grid::build(&s.triangles, &params);
            if let Err(e) = grid.validate() {
                panic!("{name} on {scene}: {e}");
            }
        }
    }
}

#[test]
fn parallel_build_gives_the_same_grid() {
    let mesh = rt_scene::scenes::builtin("random-soup").expect("built-in scene");
    let tris = mesh.triangles();
    let seq = Grid::build(
        &tris,
        &GridParams {
            parallel: false,
            ..GridParams::standard()
        },
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap();
    let par = pool.install(|| Grid::build(&tris, &GridParams::standard()));
    assert_eq!(seq.shape(), par.shape());
    assert_eq!(seq.cell_offsets(), par.cell_offsets());
    assert_eq!(seq.references(), par.references());
    assert!(par.validate().is_ok());
}

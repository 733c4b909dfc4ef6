//! The conformance kit for several shapes of hierarchy, plus structural validation.

use rt_conformance::SCENES;
use rt_core::{Accel, Sphere, Triangle};
use rt_hgrid::{HGrid, HGridParams};

rt_conformance::conformance_tests!(standard, HGrid<Triangle>, HGridParams::standard());
rt_conformance::conformance_tests!(lean, HGrid<Triangle>, HGridParams::lean());
rt_conformance::conformance_tests!(deep, HGrid<Triangle>, deep_params());
rt_conformance::conformance_tests!(
    one_level,
    HGrid<Triangle>,
    HGridParams {
        max_levels: 1,
        ..HGridParams::standard()
    }
);
rt_conformance::conformance_tests!(
    no_mailbox,
    HGrid<Triangle>,
    HGridParams {
        mailbox: false,
        ..HGridParams::standard()
    }
);

#[test]
fn spheres_standard() {
    rt_conformance::check_random_spheres::<HGrid<Sphere>>(&HGridParams::standard());
}

/// Four levels, nested grids in every cell of two or more primitives.
fn deep_params() -> HGridParams {
    HGridParams {
        top_density: 0.02,
        density: 8.0,
        split_min: 2,
        max_levels: 4,
        ..HGridParams::standard()
    }
}

#[test]
fn validate_passes_on_every_scene() {
    for params in [HGridParams::standard(), deep_params()] {
        for scene in SCENES {
            let s = rt_conformance::scene(scene);
            let grid = HGrid::build(&s.triangles, &params);
            if let Err(e) = grid.validate() {
                panic!("{params:?} on {scene}: {e}");
            }
        }
    }
}

#[test]
fn deep_hierarchies_nest_and_validate() {
    let mesh = rt_scene::scenes::builtin("random-soup").expect("built-in scene");
    let grid = HGrid::build(&mesh.triangles(), &deep_params());
    assert!(grid.levels().iter().any(|l| l.depth == 3), "four levels");
    assert!(grid.validate().is_ok());
}

#[test]
fn parallel_build_gives_the_same_grids() {
    let mesh = rt_scene::scenes::builtin("random-soup").expect("built-in scene");
    let tris = mesh.triangles();
    let seq = HGrid::build(
        &tris,
        &HGridParams {
            parallel: false,
            ..HGridParams::standard()
        },
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap();
    let par = pool.install(|| HGrid::build(&tris, &HGridParams::standard()));
    assert_eq!(seq.levels(), par.levels());
    assert_eq!(seq.cells(), par.cells());
    assert_eq!(seq.references(), par.references());
}

//! The conformance kit for every preset and both traversals, plus structural validation.

use rt_conformance::SCENES;
use rt_core::{Accel, Sphere, Triangle};
use rt_kdtree::{KdParams, KdTree, Traversal};

rt_conformance::conformance_tests!(sah, KdTree<Triangle>, KdParams::sah());
rt_conformance::conformance_tests!(wald_havran, KdTree<Triangle>, KdParams::wald_havran());
rt_conformance::conformance_tests!(restart, KdTree<Triangle>, KdParams::restart());
rt_conformance::conformance_tests!(noclip, KdTree<Triangle>, KdParams::noclip());
rt_conformance::conformance_tests!(pbrt, KdTree<Triangle>, KdParams::pbrt());
rt_conformance::conformance_tests!(
    pbrt_restart,
    KdTree<Triangle>,
    KdParams {
        traversal: Traversal::Restart,
        ..KdParams::pbrt()
    }
);

#[test]
fn spheres_sah() {
    rt_conformance::check_random_spheres::<KdTree<Sphere>>(&KdParams::sah());
}

#[test]
fn spheres_restart() {
    rt_conformance::check_random_spheres::<KdTree<Sphere>>(&KdParams::restart());
}

#[test]
fn validate_passes_on_every_scene_and_preset() {
    for (name, params) in KdTree::<Triangle>::presets() {
        for scene in SCENES {
            let s = rt_conformance::scene(scene);
            let tree = KdTree::build(&s.triangles, &params);
            if let Err(e) = tree.validate() {
                panic!("{name} on {scene}: {e}");
            }
        }
    }
}

#[test]
fn parallel_build_gives_the_same_tree() {
    // Large enough that subtrees are built with rayon::join (the threshold is 4,096 references).
    let mesh = rt_scene::scenes::builtin("random-soup").expect("built-in scene");
    let tris = mesh.triangles();
    for (name, params) in KdTree::<Triangle>::presets() {
        let seq = KdTree::build(
            &tris,
            &KdParams {
                parallel: false,
                ..params.clone()
            },
        );
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let par = pool.install(|| {
            KdTree::build(
                &tris,
                &KdParams {
                    parallel: true,
                    ..params
                },
            )
        });
        assert_eq!(seq.nodes(), par.nodes(), "{name}: nodes differ");
        assert_eq!(
            seq.references(),
            par.references(),
            "{name}: references differ"
        );
        assert!(par.validate().is_ok());
    }
}

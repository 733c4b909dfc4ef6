//! The conformance kit for several shapes of octree, plus structural validation.

use rt_conformance::SCENES;
use rt_core::{Accel, Sphere, Triangle};
use rt_octree::{Octree, OctreeParams};

rt_conformance::conformance_tests!(standard, Octree<Triangle>, OctreeParams::standard());
rt_conformance::conformance_tests!(lean, Octree<Triangle>, OctreeParams::lean());
rt_conformance::conformance_tests!(deep, Octree<Triangle>, deep_params());
rt_conformance::conformance_tests!(
    no_mailbox,
    Octree<Triangle>,
    OctreeParams {
        mailbox: false,
        ..OctreeParams::standard()
    }
);
rt_conformance::conformance_tests!(
    root_leaf,
    Octree<Triangle>,
    OctreeParams {
        max_depth: 0,
        ..OctreeParams::standard()
    }
);

#[test]
fn spheres_standard() {
    rt_conformance::check_random_spheres::<Octree<Sphere>>(&OctreeParams::standard());
}

#[test]
fn spheres_deep() {
    rt_conformance::check_random_spheres::<Octree<Sphere>>(&deep_params());
}

/// Every node with more than one primitive is cut, down to the deepest level allowed.
fn deep_params() -> OctreeParams {
    OctreeParams {
        max_prims: 1,
        max_depth: rt_octree::MAX_DEPTH,
        ..OctreeParams::standard()
    }
}

#[test]
fn validate_passes_on_every_scene() {
    for params in [OctreeParams::standard(), deep_params()] {
        for scene in SCENES {
            let s = rt_conformance::scene(scene);
            let tree = Octree::build(&s.triangles, &params);
            if let Err(e) = tree.validate() {
                panic!("{params:?} on {scene}: {e}");
            }
        }
    }
}

#[test]
fn parallel_build_gives_the_same_tree() {
    let mesh = rt_scene::scenes::builtin("random-soup").expect("built-in scene");
    let tris = mesh.triangles();
    let seq = Octree::build(
        &tris,
        &OctreeParams {
            parallel: false,
            ..OctreeParams::standard()
        },
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap();
    let par = pool.install(|| Octree::build(&tris, &OctreeParams::standard()));
    assert!(seq.blocks().len() > 100);
    assert_eq!(seq.root(), par.root());
    assert_eq!(seq.blocks(), par.blocks());
    assert_eq!(seq.references(), par.references());
}

//! The parallel build makes the same tree, byte for byte, whatever the number of threads, and
//! the same as the sequential build.

use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, MtTriangle, Primitive, Sphere, Triangle, glam::Vec3};
use rt_scene::scenes;

/// Everything a tree is made of, as bytes.
fn fingerprint<P: Primitive + rt_core::bytemuck::Pod>(b: &Bvh<P>) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(rt_core::bytemuck::cast_slice(b.nodes()));
    out.extend_from_slice(rt_core::bytemuck::cast_slice(b.wide_nodes()));
    out.extend_from_slice(rt_core::bytemuck::cast_slice(b.packs()));
    out.extend_from_slice(rt_core::bytemuck::cast_slice(b.primitives()));
    out.extend_from_slice(rt_core::bytemuck::cast_slice(b.primitive_ids()));
    out
}

fn build_on<P: Primitive>(threads: usize, prims: &[P], params: &BvhParams) -> Bvh<P> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(|| Bvh::build(prims, params))
}

fn check<P: Primitive + rt_core::bytemuck::Pod>(name: &str, prims: &[P]) {
    for (preset, params) in Bvh::<Triangle>::presets() {
        let sequential = Bvh::build(
            prims,
            &BvhParams {
                parallel: false,
                ..params.clone()
            },
        );
        assert_eq!(sequential.validate(), Ok(()), "{name} {preset}");
        let expected = fingerprint(&sequential);
        assert!(!expected.is_empty());
        for threads in [1, 2, 3] {
            let parallel = build_on(threads, prims, &params);
            assert!(
                fingerprint(&parallel) == expected,
                "{name} {preset}: the tree built on {threads} threads differs from the sequential one"
            );
        }
    }
}

#[test]
fn the_tree_does_not_depend_on_threads() {
    // 82k triangles: large enough for chunked binning and partitions, pre-splits and parallel
    // children; a random soup with a different spread; Möller–Trumbore packs; and spheres in
    // primitive leaves.
    let flake = scenes::builtin("sphereflake").unwrap().triangles();
    check("sphereflake", &flake);
    check("random-soup", &scenes::random_soup(40_000, 3).triangles());
    let mt: Vec<MtTriangle> = flake.iter().copied().map(MtTriangle).collect();
    check("sphereflake as MtTriangle", &mt);
    let spheres: Vec<Sphere> = (0..30_000)
        .map(|i| {
            let f = i as f32;
            Sphere::new(
                Vec3::new((f * 0.37).sin(), (f * 0.11).cos(), (f * 0.013).sin()) * 10.0,
                0.05,
            )
        })
        .collect();
    check("spheres", &spheres);
}

//! Degenerate inputs that used to make single rays expensive: many bit-identical triangles.

use rt_bvh::{Bvh, BvhParams};
use rt_core::glam::Vec3;
use rt_core::{Accel, BruteForce, Counters, Hit, Ray, Rng, Triangle};

fn tri(z0: f32, z1: f32, z2: f32) -> Triangle {
    Triangle::new(
        Vec3::new(-1.0, -1.0, z0),
        Vec3::new(1.0, -1.0, z1),
        Vec3::new(0.0, 1.0, z2),
    )
}

/// `copies` copies of a flat and of a slanted triangle, interleaved in the input with a soup of
/// other triangles, so the copies' indices are not contiguous and the smallest is not 0.
fn scene(copies: usize) -> Vec<Triangle> {
    let mut rng = Rng::new(9);
    let (flat, slanted) = (tri(0.5, 0.5, 0.5), tri(-0.2, -0.7, -0.5));
    let mut tris = Vec::new();
    for i in 0..copies {
        if i % 1000 == 0 {
            for _ in 0..50 {
                let c = rng.in_box(Vec3::splat(4.0), Vec3::splat(8.0));
                let s = || Vec3::new(0.1, 0.0, 0.0);
                tris.push(Triangle::new(c, c + s(), c + Vec3::Y * 0.1));
            }
        }
        tris.push(flat);
        tris.push(slanted);
    }
    tris
}

#[test]
fn copies_of_one_triangle_cost_a_ray_a_few_tests() {
    let tris = scene(100_000);
    let first_flat = tris.iter().position(|t| *t == tri(0.5, 0.5, 0.5)).unwrap() as u32;
    let first_slanted = tris
        .iter()
        .position(|t| *t == tri(-0.2, -0.7, -0.5))
        .unwrap() as u32;
    let brute = BruteForce::build(&tris, &());
    let rays = [
        // Down through both copies' triangles: the flat one is nearer.
        (
            Ray::new(Vec3::new(0.1, 0.0, 3.0), Vec3::new(0.01, 0.02, -1.0)),
            first_flat,
        ),
        // Up from below: the slanted one is nearer.
        (
            Ray::new(Vec3::new(0.1, 0.0, -3.0), Vec3::new(0.01, 0.02, 1.0)),
            first_slanted,
        ),
    ];
    for (preset, params) in Bvh::<Triangle>::presets() {
        let bvh = Bvh::build(&tris, &params);
        assert_eq!(bvh.validate(), Ok(()), "{preset}");
        let stats = bvh.build_stats();
        assert_eq!(stats.valid_prims, tris.len(), "{preset}");
        // Each distinct triangle is stored once, but for a few copies that share a small leaf
        // with other triangles (the median split puts up to a leaf's worth together).
        let distinct = tris.len() - 2 * (100_000 - 1);
        assert!(
            (distinct..distinct + 64).contains(&stats.prim_refs),
            "{preset}: {} stored for {distinct} distinct",
            stats.prim_refs
        );
        for (ray, expected) in rays {
            let mut c = Counters::default();
            let hit = bvh.intersect_with(&ray, &mut c);
            assert!(Hit::agree(hit, brute.intersect(&ray)), "{preset}");
            assert_eq!(hit.map(|h| h.prim), Some(expected), "{preset}");
            // Before: 100,000 tests and tens of thousands of visits for one ray.
            assert!(
                c.prim_tests <= 64 && c.node_visits <= 64,
                "{preset}: {c:?} for one ray"
            );
            let mut c = Counters::default();
            assert!(bvh.occluded_with(&ray, &mut c), "{preset}");
            assert!(c.prim_tests <= 64, "{preset}: any hit {c:?}");
        }
    }
}

#[test]
fn the_same_vertices_in_another_order_are_kept() {
    // Not bit-identical copies: their answers may differ in the last bit, so all are kept and
    // the tie rule decides among them, as brute force does.
    let t = tri(0.5, 0.25, 0.75);
    let rotated = Triangle::new(t.v1, t.v2, t.v0);
    let tris: Vec<Triangle> = (0..3000)
        .map(|i| if i % 2 == 0 { t } else { rotated })
        .collect();
    let brute = BruteForce::build(&tris, &());
    let mut rng = Rng::new(2);
    for (preset, params) in Bvh::<Triangle>::presets() {
        let bvh = Bvh::build(&tris, &params);
        assert_eq!(bvh.validate(), Ok(()), "{preset}");
        assert_eq!(
            bvh.build_stats().prim_refs,
            2,
            "{preset}: one of each order"
        );
        for _ in 0..2000 {
            let o = rng.in_box(Vec3::new(-2.0, -2.0, 2.0), Vec3::new(2.0, 2.0, 4.0));
            let target = rng.in_box(Vec3::new(-0.5, -0.5, 0.0), Vec3::new(0.5, 0.5, 0.0));
            let ray = Ray::new(o, target - o);
            assert!(
                Hit::agree(bvh.intersect(&ray), brute.intersect(&ray)),
                "{preset}: {}",
                ray.to_rust()
            );
        }
    }
    // With the default parameters too, as a user would build.
    let bvh = Bvh::build(&tris, &BvhParams::default());
    assert_eq!(bvh.build_stats().prim_refs, 2);
}

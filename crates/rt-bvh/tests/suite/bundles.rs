//! Coherent bundles take each tree's bundle walk (closest and any hit) rather than all falling
//! back to single rays, scattered ones go singly, and all answer as the single rays do, bit for
//! bit: the wide tree's and the binary tree's.

use rt_bvh::{Bvh, BvhParams};
use rt_core::Triangle;

#[test]
fn the_wide_trees_coherent_bundles_walk_together() {
    rt_conformance::check_coherent_bundles::<Bvh<Triangle>>(&BvhParams::wide(), true);
}

#[test]
fn the_binary_trees_coherent_bundles_walk_together() {
    rt_conformance::check_coherent_bundles::<Bvh<Triangle>>(&BvhParams::sah(), true);
}

/// Rays toward one light walk as a bundle from a patch of the floor, and singly from points
/// scattered over it (their origins spread past `MAX_ORIGIN_SPREAD` of the tree's box, though
/// their directions nearly agree), answering as single rays either way, in both trees.
#[test]
fn shadow_rays_from_scattered_points_go_singly() {
    use rt_core::glam::Vec3;
    use rt_core::{Accel, Counters, Ray, Rng};
    // A floor of 20×20 squares over [0, 10]², each two triangles.
    let mut tris = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let p = |a: usize, b: usize| Vec3::new(a as f32 * 0.5, 0.0, b as f32 * 0.5);
            tris.push(Triangle::new(p(i, j), p(i + 1, j), p(i, j + 1)));
            tris.push(Triangle::new(p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)));
        }
    }
    // Two blockers over the floor, so that some rays are blocked from either set of points.
    tris.push(Triangle::new(
        Vec3::new(4.0, 1.0, 4.0),
        Vec3::new(6.0, 1.0, 4.0),
        Vec3::new(5.0, 1.0, 6.0),
    ));
    tris.push(Triangle::new(
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.5, 1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.5),
    ));
    let light = Vec3::new(5.0, 50.0, 5.0);
    let mut rng = Rng::new(5);
    let shadow = |lo: f32, hi: f32, rng: &mut Rng| -> Vec<Ray> {
        (0..64)
            .map(|_| {
                let o = Vec3::new(rng.f32() * (hi - lo) + lo, 0.01, rng.f32() * (hi - lo) + lo);
                Ray::with_interval(o, light - o, 0.0, 1.0)
            })
            .collect()
    };
    // All toward +x and +z: one octant, one bundle.
    let patch = shadow(1.0, 1.7, &mut rng);
    let scattered = shadow(0.0, 10.0, &mut rng);
    for params in [BvhParams::wide(), BvhParams::sah()] {
        let bvh = Bvh::build(&tris, &params);
        for (rays, singly) in [(&patch, 0), (&scattered, 64)] {
            let mut counters = Counters::default();
            let mut out = vec![false; 64];
            bvh.occluded_bundle_with(rays, &mut out, &mut counters);
            assert_eq!(counters.single_rays, singly, "{params:?}");
            let single: Vec<bool> = rays.iter().map(|r| bvh.occluded(r)).collect();
            assert_eq!(out, single, "{params:?}");
            assert!(single.contains(&true) && single.contains(&false));
        }
    }
}

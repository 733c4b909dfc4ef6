//! Input that no subdivision separates must end in leaves with bounded memory, and still be
//! traced exactly: identical triangles, triangles overlapping around a point or a plane, and large
//! triangles crossing every node, built with the most aggressive parameters.

use rt_conformance::check_case;
use rt_core::glam::Vec3;
use rt_core::{Accel, Ray, Rng, Triangle};
use rt_octree::{MAX_DEPTH, Octree, OctreeParams};

/// Cut every node of two or more primitives, as deep as the octree goes.
fn greedy() -> OctreeParams {
    OctreeParams {
        max_prims: 1,
        max_depth: MAX_DEPTH,
        ..OctreeParams::standard()
    }
}

/// Rays at the scene from all around, aimed at points near the origin.
fn rays(rng: &mut Rng, n: usize) -> Vec<Ray> {
    (0..n)
        .map(|_| {
            let target = rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0));
            let dir = rng.unit_vector();
            Ray::new(target - dir * 5.0, dir)
        })
        .collect()
}

/// Builds with [`greedy`] parameters, validates, compares rays with brute force, and returns
/// the tree's node and reference counts.
fn build_and_check(tris: &[Triangle]) -> (usize, usize) {
    let params = greedy();
    let tree = Octree::build(tris, &params);
    tree.validate().unwrap();
    check_case::<Octree<Triangle>>(&params, tris, &rays(&mut Rng::new(3), 300)).unwrap();
    let s = tree.build_stats();
    (s.nodes, s.prim_refs)
}

/// Two small triangles in opposite corners that make the root the cube `[-1, 1]³`, whose
/// mid-planes pass through the origin.
fn pinned() -> Vec<Triangle> {
    vec![
        Triangle::new(
            Vec3::splat(-1.0),
            Vec3::new(-0.9, -1.0, -1.0),
            Vec3::new(-1.0, -0.9, -1.0),
        ),
        Triangle::new(
            Vec3::splat(1.0),
            Vec3::new(0.9, 1.0, 1.0),
            Vec3::new(1.0, 0.9, 1.0),
        ),
    ]
}

#[test]
fn identical_triangles_on_a_mid_plane_stay_in_one_leaf_per_side() {
    // A thousand copies of one triangle crossing all three of the root's mid-planes.
    let mut tris = pinned();
    let t = Triangle::new(
        Vec3::new(-0.1, -0.1, -0.1),
        Vec3::new(0.1, -0.1, 0.1),
        Vec3::new(0.0, 0.1, 0.0),
    );
    tris.extend(std::iter::repeat_n(t, 1000));
    let (nodes, refs) = build_and_check(&tris);
    // Each copy ends up in at most the eight octants around the point it crosses the mid-planes
    // at (without the rule for splits that separate nothing: twice as many, up to the budget).
    assert!(refs <= 8 * 1000 + 2, "{refs} references in {nodes} nodes");
}

#[test]
fn identical_triangles_inside_one_octant_make_a_chain_of_zooms() {
    let mut tris = pinned();
    let c = Vec3::new(0.3337, 0.2791, 0.4123);
    let t = Triangle::new(
        c,
        c + Vec3::new(1e-4, 0.0, 0.0),
        c + Vec3::new(0.0, 1e-4, 0.0),
    );
    tris.extend(std::iter::repeat_n(t, 1000));
    let (nodes, refs) = build_and_check(&tris);
    // At most one block per level on the way down, and each copy referenced at most eight times
    // (without the rule for splits that separate nothing: 16 times, up to the budget).
    assert!(nodes <= 1 + 8 * MAX_DEPTH as usize, "{nodes} nodes");
    assert!(refs <= 8 * 1000 + 2, "{refs} references");
}

#[test]
fn a_fan_around_a_vertex_is_not_cut_forever() {
    // 200 thin triangles around a vertex (a quarter disc, so the vertex is at the root's corner,
    // not on its mid-planes), as at the pole of a surface of revolution.
    let n = 200;
    let tris: Vec<Triangle> = (0..n)
        .map(|i| {
            let a = |k: usize| {
                let phi = k as f32 / n as f32 * std::f32::consts::FRAC_PI_2;
                Vec3::new(phi.cos(), 0.0, phi.sin())
            };
            let apex = Vec3::new(0.1234, 0.01, -0.0771);
            Triangle::new(apex, apex + a(i), apex + a(i + 1))
        })
        .collect();
    let (nodes, refs) = build_and_check(&tris);
    // The fan fills every node around its vertex, so it is not cut. Without the rule for splits
    // that separate nothing, this builds 3,865 nodes and stops only at the reference budget.
    assert!(refs <= 2 * n, "{refs} references in {nodes} nodes");
}

#[test]
fn large_overlapping_triangles_stay_within_the_reference_budget() {
    // 2,000 triangles each spanning most of the box: every node overlaps most of them, so cutting
    // to one primitive per leaf would multiply references without end.
    let mut rng = Rng::new(9);
    let tris: Vec<Triangle> = (0..2000)
        .map(|_| {
            let p = |rng: &mut Rng| rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0));
            Triangle::new(p(&mut rng), p(&mut rng), p(&mut rng))
        })
        .collect();
    let params = greedy();
    let budget = (params.max_refs_per_prim as usize * tris.len()).max(1 << 14);
    let (nodes, refs) = build_and_check(&tris);
    assert!(refs <= budget, "{refs} references, budget {budget}");
    assert!(nodes > 8, "the budget still allows cutting: {nodes} nodes");
}

//! The hardest rays for a parametric walk, on octrees whose planes fall on the lattice: the root
//! is the cube `[0, 4]³` of [`lattice_triangles`], so its mid-planes lie at the integers and,
//! three levels down, at the half-integers where the triangles' vertices are. Lattice rays run
//! along mid-planes of every level and pass exactly through node edges and corners, with `±0`
//! direction components and origins inside, on the faces of, and outside the octree; grazing
//! rays pass within 10⁻⁷ of node edges from up to 10⁴ away.

use proptest::prelude::*;
use rt_conformance::{check_case, edge_grazing_case, lattice_rays, lattice_triangles};
use rt_core::{Accel, Rng, Triangle, glam::Vec3};
use rt_octree::{Octree, OctreeParams};

/// Cut every node of two or more triangles, down to cells of side 1/2 (depth 3) or 1/8 (5).
fn lattice_tree(max_depth: u32) -> OctreeParams {
    OctreeParams {
        max_prims: 1,
        max_depth,
        ..OctreeParams::standard()
    }
}

#[test]
fn the_octree_has_lattice_planes() {
    let tris = lattice_triangles(1, 40);
    let tree = Octree::build(&tris, &lattice_tree(3));
    assert_eq!(tree.bounds().min.to_array(), [0.0; 3]);
    assert_eq!(tree.bounds().max.to_array(), [4.0; 3]);
    let leaves = tree.leaves();
    assert!(leaves.iter().any(|l| l.2 == 3), "cells of side 1/2");
    // Every leaf's box has its corners on the lattice of its depth.
    assert!(leaves.iter().all(|&(_, b, depth)| {
        let scale = (1u32 << depth) as f32 / 4.0;
        (b.min * scale).fract() == Vec3::ZERO && (b.max * scale).fract() == Vec3::ZERO
    }));
    assert!(tree.validate().is_ok());
}

#[test]
fn rays_through_node_edges_and_corners_agree_with_brute_force() {
    for seed in 0..40 {
        let tris = lattice_triangles(seed, 40);
        let rays = lattice_rays(seed, 400);
        for depth in [3, 5] {
            check_case::<Octree<Triangle>>(&lattice_tree(depth), &tris, &rays).unwrap();
        }
    }
}

#[test]
fn rays_grazing_node_edges_from_afar_agree_with_brute_force() {
    let mut rng = Rng::new(5);
    for _ in 0..3000 {
        let (tris, rays) = edge_grazing_case(&mut rng);
        check_case::<Octree<Triangle>>(&lattice_tree(5), &tris, &rays).unwrap();
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn lattice_rays_agree(seed in any::<u64>(), n in 3usize..60) {
        let tris = lattice_triangles(seed, n);
        let rays = lattice_rays(seed, 200);
        for params in [lattice_tree(3), lattice_tree(6), OctreeParams::standard()] {
            if let Err(e) = check_case::<Octree<Triangle>>(&params, &tris, &rays) {
                prop_assert!(false, "{e}");
            }
        }
    }
}

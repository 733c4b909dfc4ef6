//! The uniform grid's hardest rays, on hierarchies whose planes fall on the lattice: a 4³ top
//! grid over the cube `[0, 4]³` with 2³ nested grids (planes at the half-integers, where the
//! lattice triangles' vertices are), so rays run along planes of both levels and pass through
//! their edges and corners, and grazing rays cross between levels.

use proptest::prelude::*;
use rt_conformance::{check_case, edge_grazing_case, lattice_rays, lattice_triangles};
use rt_core::{Accel, Rng, Triangle};
use rt_hgrid::{HGrid, HGridParams};

/// A 4³ top grid for `n` triangles in the cube, and a 2³ nested grid in every cell with at
/// least two triangles.
fn lattice_levels(n: usize) -> HGridParams {
    HGridParams {
        top_density: 64.0 / n as f32,
        density: 8.0 / 3.0,
        split_min: 2,
        max_levels: 2,
        ..HGridParams::standard()
    }
}

#[test]
fn the_hierarchy_has_lattice_planes() {
    let tris = lattice_triangles(1, 40);
    let grid = HGrid::build(&tris, &lattice_levels(tris.len()));
    assert_eq!(grid.levels()[0].shape.resolution_per_axis(), [4, 4, 4]);
    assert!(grid.levels().len() > 1);
    assert!(grid.validate().is_ok());
}

#[test]
fn rays_through_cell_edges_and_corners_agree_with_brute_force() {
    for seed in 0..40 {
        let tris = lattice_triangles(seed, 40);
        let rays = lattice_rays(seed, 400);
        check_case::<rt_hgrid::HGrid<Triangle>>(&lattice_levels(tris.len()), &tris, &rays).unwrap();
    }
}

#[test]
fn rays_grazing_cell_edges_from_afar_agree_with_brute_force() {
    let mut rng = Rng::new(5);
    for _ in 0..3000 {
        let (tris, rays) = edge_grazing_case(&mut rng);
        check_case::<HGrid<Triangle>>(&lattice_levels(tris.len()), &tris, &rays).unwrap();
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn lattice_rays_agree(seed in any::<u64>(), n in 3usize..60) {
        let tris = lattice_triangles(seed, n);
        let rays = lattice_rays(seed, 200);
        for params in [lattice_levels(tris.len()), HGridParams::standard()] {
            if let Err(e) = check_case::<HGrid<Triangle>>(&params, &tris, &rays) {
                prop_assert!(false, "{e}");
            }
        }
    }
}

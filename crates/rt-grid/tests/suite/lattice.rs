//! Rays the DDA finds hardest, against brute force: on a grid whose cell planes are the integers
//! 0..=4, rays start on lattice points (inside, outside and on the grid's faces, edges and
//! corners) and head along small integer directions with `±0` components, so they run along cell
//! planes and pass exactly through cell edges and corners. Triangles sit on the half-integer
//! lattice: lying in cell planes, touching cells at a vertex or edge, and spanning many cells
//! (hits beyond the current cell).

use proptest::prelude::*;
use rt_conformance::{
    check_case, edge_grazing_case, lattice_rays, lattice_triangles as lattice_scene,
};
use rt_core::glam::Vec3;
use rt_core::{Accel, BruteForce, Rng, Triangle};
use rt_grid::{Grid, GridParams};

/// λ such that a scene of `n` triangles in the cube `[0, 4]³` gets 4 × 4 × 4 cells.
fn unit_cells(n: usize) -> GridParams {
    GridParams {
        density: 64.0 / n as f32,
        ..GridParams::standard()
    }
}

#[test]
fn the_lattice_grid_has_integer_planes() {
    let tris = lattice_scene(1, 40);
    let grid = Grid::build(&tris, &unit_cells(tris.len()));
    assert_eq!(grid.shape().resolution_per_axis(), [4, 4, 4]);
    for a in 0..3 {
        for k in 0..=4 {
            assert_eq!(grid.shape().plane(a, k), k as f32);
        }
    }
}

#[test]
fn rays_through_cell_edges_and_corners_agree_with_brute_force() {
    for seed in 0..40 {
        let tris = lattice_scene(seed, 40);
        let rays = lattice_rays(seed, 400);
        for params in [unit_cells(tris.len()), GridParams::no_mailbox()] {
            check_case::<Grid<Triangle>>(&params, &tris, &rays).unwrap();
        }
    }
}

#[test]
fn a_ray_along_a_cell_edge_finds_the_triangle_touching_it() {
    // The triangle lies in the plane y = 2 and touches the cell edge x = 2, z = 1 with one
    // vertex only; the ray runs along that edge and meets the vertex.
    let mut tris = lattice_scene(3, 2);
    tris.push(Triangle::new(
        Vec3::new(2.0, 2.0, 1.0),
        Vec3::new(1.0, 2.0, 0.5),
        Vec3::new(1.5, 2.0, 0.0),
    ));
    let params = GridParams {
        density: 64.0 / 3.0,
        ..GridParams::standard()
    };
    let grid = Grid::build(&tris, &params);
    assert_eq!(grid.shape().resolution_per_axis(), [4, 4, 4]);
    let brute = BruteForce::build(&tris, &());
    for d in [Vec3::new(0.0, 1.0, 0.0), Vec3::new(-0.0, 1.0, -0.0)] {
        let ray = rt_core::Ray::new(Vec3::new(2.0, -1.0, 1.0), d);
        let expected = brute.intersect(&ray).expect("brute force hits the vertex");
        assert_eq!((expected.prim, expected.t), (2, 3.0));
        let hit = grid.intersect(&ray).expect("the grid hits the vertex");
        assert_eq!((hit.prim, hit.t), (2, 3.0));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random lattice scenes and rays, on the 4³ grid and on a finer one whose planes fall
    /// between the lattice's.
    #[test]
    fn lattice_rays_agree(seed in any::<u64>(), n in 3usize..60) {
        let tris = lattice_scene(seed, n);
        let rays = lattice_rays(seed, 200);
        for params in [unit_cells(tris.len()), GridParams { density: 8.0, ..GridParams::standard() }] {
            if let Err(e) = check_case::<Grid<Triangle>>(&params, &tris, &rays) {
                prop_assert!(false, "{e}");
            }
        }
    }
}

/// Tiny triangles hugging a cell edge, one in each of the four cells around it, hit by rays
/// from up to 10⁴ away ([`edge_grazing_case`]): the DDA must also test the cells beside its path
/// where two boundaries are crossed within rounding of each other. (Without that, 10 of these
/// 3,000 scenes fail.)
#[test]
fn rays_grazing_cell_edges_from_afar_agree_with_brute_force() {
    let mut rng = Rng::new(5);
    for _ in 0..3000 {
        let (tris, rays) = edge_grazing_case(&mut rng);
        check_case::<Grid<Triangle>>(&unit_cells(tris.len()), &tris, &rays).unwrap();
    }
}

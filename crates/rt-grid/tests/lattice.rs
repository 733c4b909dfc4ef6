//! Rays the DDA finds hardest, against brute force: on a grid whose cell planes are the integers
//! 0..=4, rays start on lattice points (inside, outside and on the grid's faces, edges and
//! corners) and head along small integer directions with `±0` components, so they run along cell
//! planes and pass exactly through cell edges and corners. Triangles sit on the half-integer
//! lattice: lying in cell planes, touching cells at a vertex or edge, and spanning many cells
//! (hits beyond the current cell).

use proptest::prelude::*;
use rt_core::conformance::check_case;
use rt_core::glam::Vec3;
use rt_core::{Accel, BruteForce, Rng, Triangle};
use rt_grid::{Grid, GridParams};

/// Triangles in `[0, 4]³` on the half-integer lattice; the first two pin the box to the full
/// cube.
fn lattice_scene(seed: u64, count: usize) -> Vec<Triangle> {
    let mut rng = Rng::new(seed);
    let mut tris = vec![
        Triangle::new(
            Vec3::ZERO,
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.0, 0.5, 0.0),
        ),
        Triangle::new(
            Vec3::splat(4.0),
            Vec3::new(3.5, 4.0, 4.0),
            Vec3::new(4.0, 3.5, 4.0),
        ),
    ];
    let point = |rng: &mut Rng| {
        Vec3::new(
            (rng.f32() * 9.0).floor() * 0.5,
            (rng.f32() * 9.0).floor() * 0.5,
            (rng.f32() * 9.0).floor() * 0.5,
        )
    };
    while tris.len() < count {
        let a = point(&mut rng);
        let mut b = point(&mut rng);
        let mut c = point(&mut rng);
        // A third of the triangles lie in an axis plane through `a` (often a cell plane).
        if rng.f32() < 0.33 {
            let axis = (rng.f32() * 3.0) as usize % 3;
            b[axis] = a[axis];
            c[axis] = a[axis];
        }
        let t = Triangle::new(a, b, c);
        if t.normal() != Vec3::ZERO {
            tris.push(t);
        }
    }
    tris
}

fn component(rng: &mut Rng) -> f32 {
    [-2.0, -1.0, -0.0, 0.0, 1.0, 2.0][(rng.f32() * 6.0) as usize % 6]
}

/// Rays from lattice points in `[-1, 5]³` (some on the grid's faces) along small integer
/// directions.
fn lattice_rays(seed: u64, count: usize) -> Vec<rt_core::Ray> {
    let mut rng = Rng::new(seed ^ 0xdda);
    let mut rays = Vec::with_capacity(count);
    while rays.len() < count {
        let o = Vec3::new(
            (rng.f32() * 7.0).floor() - 1.0,
            (rng.f32() * 7.0).floor() - 1.0,
            (rng.f32() * 7.0).floor() - 1.0,
        );
        let d = Vec3::new(
            component(&mut rng),
            component(&mut rng),
            component(&mut rng),
        );
        if d.abs() != Vec3::ZERO {
            rays.push(rt_core::Ray::new(o, d));
        }
    }
    rays
}

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
/// from up to 10⁴ away. Rounding moves such a ray's computed path across the edge by more than
/// the triangles' distance to it, so the DDA must also test the cells beside its path where two
/// boundaries are crossed within rounding of each other. (Without that, 10 of these 3,000 scenes
/// fail.)
#[test]
fn rays_grazing_cell_edges_from_afar_agree_with_brute_force() {
    let mut rng = Rng::new(5);
    for _ in 0..3000 {
        let mut tris = lattice_scene(0, 2);
        let (i, j) = (
            (1 + (rng.f32() * 3.0) as u32) as f32,
            (1 + (rng.f32() * 3.0) as u32) as f32,
        );
        let eps = 10f32.powf(-3.0 - rng.f32() * 4.0);
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            let c = Vec3::new(i + sx * eps, j + sy * eps, 2.0 + rng.f32());
            let s = eps * 0.5;
            tris.push(Triangle::new(
                c + Vec3::new(-s, -s, 0.0),
                c + Vec3::new(s, -s, 0.0),
                c + Vec3::new(0.0, s, 0.01),
            ));
        }
        let rays: Vec<_> = (0..200)
            .map(|_| {
                let target = Vec3::new(
                    i + (rng.f32() - 0.5) * eps * 4.0,
                    j + (rng.f32() - 0.5) * eps * 4.0,
                    2.0 + rng.f32(),
                );
                let dist = 10f32.powf(rng.f32() * 4.0);
                let dir = rng.unit_vector();
                rt_core::Ray::new(target - dir * dist, dir)
            })
            .collect();
        check_case::<Grid<Triangle>>(&unit_cells(tris.len()), &tris, &rays).unwrap();
    }
}

//! Signed distances, inside tests and winding numbers in batches: every point answered on the
//! current rayon pool's threads, in the Morton order that shares the cache
//! ([`rt_core::batch::in_morton_order`]), each answer written to the caller's slot and equal to
//! the single query's. As in [`rt_core::batch`], run inside a rayon pool of `n` threads to use
//! `n`.
//!
//! ```
//! use rt_core::{Accel, BruteForce, Mesh, glam::Vec3};
//! use rt_sdf::{WindingTree, batch};
//! let cube = Mesh::cuboid(Vec3::ZERO, Vec3::ONE);
//! let accel = BruteForce::build_from(&cube, &());
//! let sign = WindingTree::build_from(&cube).unwrap();
//! let points = [Vec3::splat(0.25), Vec3::new(0.5, 0.5, 3.0)];
//! let mut sd = [None; 2];
//! batch::signed_distances(&accel, &sign, &points, f32::INFINITY, &mut sd);
//! assert_eq!(sd.map(|s| s.unwrap().distance), [-0.25, 2.0]);
//! ```

use crate::{SignedDistance, SignedPoint, WindingTree};
use rt_core::Accel;
use rt_core::batch::in_morton_order;
use rt_core::glam::Vec3;

/// [`SignedDistance::signed_distance`] of every point within `max_distance` into the same slot
/// of `out` (as many as both have). `sign` must be built over the primitives `accel` was.
pub fn signed_distances<A: Accel>(
    accel: &A,
    sign: &WindingTree,
    points: &[Vec3],
    max_distance: f32,
    out: &mut [Option<SignedPoint>],
) {
    in_morton_order(points, out, |p| {
        accel.signed_distance(sign, p, max_distance)
    });
}

/// [`WindingTree::is_inside`] of every point into the same slot of `out` (as many as both
/// have).
pub fn inside(sign: &WindingTree, points: &[Vec3], out: &mut [bool]) {
    in_morton_order(points, out, |p| sign.is_inside(p));
}

/// [`WindingTree::winding_number`]'s value at every point, within `tolerance`, into the same
/// slot of `out` (as many as both have).
pub fn winding_numbers(sign: &WindingTree, points: &[Vec3], tolerance: f64, out: &mut [f64]) {
    in_morton_order(points, out, |p| sign.winding_number(p, tolerance).value);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::{BruteForce, Rng};

    /// Each batch answers every point as the single query does, in the caller's slots, with
    /// points inside and outside, a non-finite one, and a slot past the points left alone.
    #[test]
    fn batches_answer_as_one_at_a_time() {
        let tris = crate::test_meshes::sphere(Vec3::ZERO, 1.0, 8, 12);
        let accel = BruteForce::build(&tris, &());
        let sign = WindingTree::build(&tris).unwrap();
        let mut rng = Rng::new(3);
        let mut points: Vec<Vec3> = (0..2000)
            .map(|_| Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - Vec3::splat(1.5))
            .collect();
        points[11] = Vec3::NAN;
        let n = points.len();
        for max in [f32::INFINITY, 0.2] {
            let mut sd = vec![None; n + 1];
            signed_distances(&accel, &sign, &points, max, &mut sd);
            assert_eq!(sd[n], None, "the slot past the points is left alone");
            for (i, &p) in points.iter().enumerate() {
                assert_eq!(sd[i], accel.signed_distance(&sign, p, max), "point {i}");
            }
        }
        let mut ins = vec![false; n];
        inside(&sign, &points, &mut ins);
        assert!(
            ins.iter()
                .zip(&points)
                .all(|(i, &p)| *i == sign.is_inside(p))
        );
        assert!(ins.contains(&true) && ins.contains(&false));
        let mut w = vec![0.0; n];
        winding_numbers(&sign, &points, 1e-6, &mut w);
        for (w, &p) in w.iter().zip(&points) {
            let single = sign.winding_number(p, 1e-6).value;
            assert!(w.to_bits() == single.to_bits(), "{w} != {single} at {p}");
        }
    }
}

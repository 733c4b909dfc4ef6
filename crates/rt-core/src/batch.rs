//! Point queries in batches: many points answered together, in an order that shares the
//! cache, on every thread of the current rayon pool.
//!
//! Points close in space walk the same nodes and test the same primitives, so answering them
//! one after another finds those in the cache. [`morton_order`] sorts points along the Z-order
//! curve over their bounding box; [`closest_points`] answers in that order, chunk by chunk on
//! the pool's threads (`rt_core::par`: in order on the calling thread without the `parallel`
//! feature or in a pool of one), and writes each answer to its point's own slot. The answers
//! are [`Accel::closest_point`]'s, whatever the order.
//!
//! To run on fewer threads, call it inside a rayon pool of that many
//! (`rayon::ThreadPoolBuilder::new().num_threads(n).build()?.install(|| ...)`).
//!
//! ```
//! use rt_core::{Accel, BruteForce, Triangle, batch, glam::Vec3};
//! let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
//! let accel = BruteForce::build(&tris, &());
//! let points = [Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.2, 0.2, -3.0)];
//! let mut out = [None; 2];
//! batch::closest_points(&accel, &points, f32::INFINITY, &mut out);
//! assert_eq!(out.map(|h| h.unwrap().distance), [1.0, 3.0]);
//! ```

use crate::{Accel, PointHit, par};
use glam::Vec3;

/// Points a thread answers at a time.
const CHUNK: usize = 256;

/// The indices of `points` sorted by their Morton code (21 bits per axis over the box of the
/// finite points), ties by index; points with a non-finite coordinate last, by index.
pub fn morton_order(points: &[Vec3]) -> Vec<u32> {
    let (lo, hi) = points
        .iter()
        .filter(|p| p.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let scale = ((1u32 << 21) - 1) as f32 / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let mut keyed: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let code = if p.is_finite() {
                let cell =
                    ((p - lo) * scale).clamp(Vec3::ZERO, Vec3::splat(((1 << 21) - 1) as f32));
                spread(cell.x as u32) | spread(cell.y as u32) << 1 | spread(cell.z as u32) << 2
            } else {
                u64::MAX
            };
            (code, i as u32)
        })
        .collect();
    par::sort_unstable(&mut keyed);
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// The low 21 bits of `x`, two zero bits after each.
fn spread(x: u32) -> u64 {
    let mut v = u64::from(x) & 0x1f_ffff;
    v = (v | v << 32) & 0x001f_0000_0000_ffff;
    v = (v | v << 16) & 0x001f_0000_ff00_00ff;
    v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
    v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
    (v | v << 2) & 0x1249_2492_4924_9249
}

/// [`Accel::closest_point`] for every point within `max_distance`, into the same slot of `out`
/// (as many as both have), answered in [`morton_order`] on the current pool's threads.
pub fn closest_points<A: Accel + Sync>(
    accel: &A,
    points: &[Vec3],
    max_distance: f32,
    out: &mut [Option<PointHit>],
) {
    // PERF: on one thread (AMD Zen 3, 200,000 points, half in the box grown by a quarter and
    // half near the surface, wide BVH), Morton order ran 1.22–1.39× as fast as the caller's
    // random order on the bunny, spot, the rocker arm and the teapot (a scratch harness).
    let n = points.len().min(out.len());
    let order = morton_order(&points[..n]);
    let mut sorted = vec![None; n];
    par::zip_chunks_mut(&order, &mut sorted, CHUNK, |order, sorted| {
        for (o, &i) in sorted.iter_mut().zip(order) {
            *o = accel.closest_point(points[i as usize], max_distance);
        }
    });
    for (&i, hit) in order.iter().zip(sorted) {
        out[i as usize] = hit;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BruteForce, Rng, Triangle};

    #[test]
    fn spread_puts_two_zero_bits_after_each_bit() {
        assert_eq!(spread(0b1011), 0b001_000_001_001);
        assert_eq!(spread(0x1f_ffff), 0x1249_2492_4924_9249);
    }

    #[test]
    fn morton_order_is_a_permutation_with_neighbours_together_and_bad_points_last() {
        let points = [
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::NAN,
            Vec3::ZERO,
            Vec3::new(0.9, 1.0, 1.0),
            Vec3::new(0.0, 0.0, 0.1),
        ];
        assert_eq!(morton_order(&points), [2, 4, 3, 0, 1]);
        assert!(morton_order(&[]).is_empty());
        assert_eq!(morton_order(&[Vec3::ONE, Vec3::ONE]), [0, 1]);
    }

    /// The batch answers each point as the single query does, in the caller's order.
    #[test]
    fn closest_points_answer_as_one_at_a_time() {
        let mut rng = Rng::new(9);
        let mut p = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 4.0 - Vec3::splat(2.0);
        let tris: Vec<Triangle> = (0..200).map(|_| Triangle::new(p(), p(), p())).collect();
        let accel = BruteForce::build(&tris, &());
        let mut points: Vec<Vec3> = (0..3000).map(|_| p()).collect();
        points[17] = Vec3::NAN;
        for max in [f32::INFINITY, 0.1] {
            let mut out = vec![None; points.len() + 1];
            batch_then_check(&accel, &points, max, &mut out);
        }
    }

    fn batch_then_check(
        accel: &BruteForce<Triangle>,
        points: &[Vec3],
        max: f32,
        out: &mut [Option<PointHit>],
    ) {
        closest_points(accel, points, max, out);
        for (i, &p) in points.iter().enumerate() {
            assert_eq!(out[i], accel.closest_point(p, max), "point {i}");
        }
        assert_eq!(
            out[points.len()],
            None,
            "the slot past the points is left alone"
        );
    }
}

//! Every query in batches: many rays, points or boxes answered together on every thread of
//! the current rayon pool, each answer written to the caller's slot and equal to the single
//! query's.
//!
//! - Rays: [`intersect`], [`occluded`], [`count_hits`] and [`all_hits`] read rays from any
//!   [`RaySource`]: a slice of [`Ray`]s, or [`FlatRays`], rows of six numbers (origin then
//!   direction) as numpy arrays and files hold them, made into rays a chunk at a time on the
//!   stack. Runs of rays go through the structure's bundles ([`Accel::intersect_bundle`]):
//!   coherent ones (a camera's, in order) walk together, scattered ones singly.
//! - Points: [`closest_points`] answers in [`morton_order`]. Points close in space walk the same
//!   nodes and test the same primitives, so answering them one after another finds those in
//!   the cache; [`in_morton_order`] does the same for any point query (rt-sdf's signed
//!   distances use it).
//! - Boxes: [`overlapping`].
//! - Answers laid out as a caller wants them (one array per field, say): [`for_each_ray_chunk`]
//!   and [`for_each_chunk`] hand each thread a chunk of the input and its own slots of up to
//!   six output slices ([`Slots`]).
//!
//! The work runs in chunks of [`CHUNK`] items on the current rayon pool (through
//! [`par`]; in order on the calling thread without the `parallel` feature or in a
//! pool of one thread). To run on fewer threads, call it inside a pool of that many:
//!
//! ```
//! use rt_core::{Accel, BruteForce, Triangle, batch, glam::Vec3};
//! let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
//! let accel = BruteForce::build(&tris, &());
//! // Two rays down the z axis as flat rows: origin x y z, direction x y z.
//! let rows = [0.2, 0.2, 1.0, 0.0, 0.0, -1.0, 5.0, 5.0, 1.0, 0.0, 0.0, -1.0];
//! let rays = batch::FlatRays::new(&rows, 0.0, f32::INFINITY).unwrap();
//! let mut hits = [None; 2];
//! let two_threads = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
//! two_threads.install(|| batch::intersect(&accel, &rays, &mut hits));
//! assert_eq!(hits.map(|h| h.map(|h| h.t)), [Some(1.0), None]);
//!
//! let points = [Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.2, 0.2, -3.0)];
//! let mut near = [None; 2];
//! batch::closest_points(&accel, &points, f32::INFINITY, &mut near);
//! assert_eq!(near.map(|h| h.unwrap().distance), [1.0, 3.0]);
//! ```

use crate::{Aabb, Accel, Hit, PointHit, Ray, RayFault, par};
use glam::Vec3;
use std::ops::Range;

pub use crate::par::Slots;

/// Items (rays, points, boxes) a thread answers at a time: four full bundles of 64 rays, and
/// few enough rays (11 KiB) to make on the stack.
pub const CHUNK: usize = 256;

/// Rays a batch reads: a slice of [`Ray`]s, or [`FlatRays`].
pub trait RaySource: Sync {
    /// How many rays there are.
    fn len(&self) -> usize;

    /// Whether there are none.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The rays of `range`, made in `buf` if they are not stored as rays. The batches ask for
    /// at most [`CHUNK`] at a time; a longer range may panic.
    fn chunk<'a>(&'a self, range: Range<usize>, buf: &'a mut [Ray; CHUNK]) -> &'a [Ray];
}

impl RaySource for [Ray] {
    fn len(&self) -> usize {
        <[Ray]>::len(self)
    }

    #[inline]
    fn chunk<'a>(&'a self, range: Range<usize>, _: &'a mut [Ray; CHUNK]) -> &'a [Ray] {
        &self[range]
    }
}

/// Rays as flat rows of six `f32`, origin `x y z` then direction `x y z` (numpy's `(n, 6)`
/// arrays, Open3D's layout), all over one interval `[t_min, t_max]`, checked once and made
/// into [`Ray`]s a chunk at a time on the stack: a batch over them allocates nothing per ray.
#[derive(Clone, Copy, Debug)]
pub struct FlatRays<'a> {
    rows: &'a [f32],
    t_min: f32,
    t_max: f32,
}

/// Why [`FlatRays::new`] refused its rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlatRaysError {
    /// The number of values is not a multiple of six.
    Ragged {
        /// How many values there are.
        values: usize,
    },
    /// A row is not a valid ray ([`Ray::is_valid`]).
    Invalid {
        /// The first such row.
        row: usize,
        /// Why.
        fault: RayFault,
    },
}

impl std::fmt::Display for FlatRaysError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Ragged { values } => {
                write!(f, "{values} values are not rows of six (origin, direction)")
            }
            Self::Invalid { row, fault } => write!(f, "ray {row} {fault}"),
        }
    }
}

impl std::error::Error for FlatRaysError {}

impl<'a> FlatRays<'a> {
    /// The rays of `rows` over `[t_min, t_max]`.
    ///
    /// # Errors
    /// [`FlatRaysError::Ragged`] when `rows.len()` is not a multiple of six, and
    /// [`FlatRaysError::Invalid`] naming the first row that is not a valid ray (checked on the
    /// pool's threads).
    pub fn new(rows: &'a [f32], t_min: f32, t_max: f32) -> Result<Self, FlatRaysError> {
        if !rows.len().is_multiple_of(6) {
            return Err(FlatRaysError::Ragged { values: rows.len() });
        }
        let rays = Self { rows, t_min, t_max };
        let first_bad = par::map_chunks(rows, 6 * CHUNK, |c| {
            c.chunks_exact(6).position(|r| !rays.make(r).is_valid())
        });
        match first_bad
            .iter()
            .enumerate()
            .find_map(|(c, i)| Some(c * CHUNK + (*i)?))
        {
            Some(row) => Err(FlatRaysError::Invalid {
                row,
                fault: rays.ray(row).fault().unwrap_or(RayFault::Interval),
            }),
            None => Ok(rays),
        }
    }

    /// How many rays there are.
    pub fn len(&self) -> usize {
        self.rows.len() / 6
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Ray `i`.
    ///
    /// # Panics
    /// If `i >= self.len()`.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        self.make(&self.rows[6 * i..6 * i + 6])
    }

    #[inline(always)]
    fn make(&self, r: &[f32]) -> Ray {
        Ray::with_interval(
            Vec3::new(r[0], r[1], r[2]),
            Vec3::new(r[3], r[4], r[5]),
            self.t_min,
            self.t_max,
        )
    }
}

impl RaySource for FlatRays<'_> {
    fn len(&self) -> usize {
        FlatRays::len(self)
    }

    #[inline]
    fn chunk<'a>(&'a self, range: Range<usize>, buf: &'a mut [Ray; CHUNK]) -> &'a [Ray] {
        let rows = self.rows[6 * range.start..6 * range.end].chunks_exact(6);
        for (b, r) in buf.iter_mut().zip(rows) {
            *b = self.make(r);
        }
        &buf[..range.len()]
    }
}

/// `f(rays, slots)` for consecutive chunks of up to [`CHUNK`] rays of `rays` (starting at
/// multiples of it), each with its own slots of `out`, on the current pool's threads: the
/// core of the ray batches, for answers laid out as the caller wants them. Covers as many rays
/// as both have.
pub fn for_each_ray_chunk<R: RaySource + ?Sized, S: Slots>(
    rays: &R,
    out: S,
    f: impl Fn(&[Ray], S) + Sync + Send,
) {
    let n = rays.len().min(out.slots());
    let (out, _) = out.split_at(n);
    par::split_slots(out, CHUNK, |range, out| {
        let mut buf = [Ray::new(Vec3::ZERO, Vec3::X); CHUNK];
        f(rays.chunk(range, &mut buf), out);
    });
}

/// `f(items, slots)` for consecutive chunks of up to [`CHUNK`] items, each with its own slots
/// of `out`, on the current pool's threads, as [`for_each_ray_chunk`] does for rays.
pub fn for_each_chunk<T: Sync, S: Slots>(items: &[T], out: S, f: impl Fn(&[T], S) + Sync + Send) {
    let n = items.len().min(out.slots());
    let (out, _) = out.split_at(n);
    par::split_slots(out, CHUNK, |range, out| f(&items[range], out));
}

/// [`Accel::intersect`] of every ray into the same slot of `out` (as many as both have),
/// traced as the structure's bundles ([`Accel::intersect_bundle`]).
pub fn intersect<A: Accel, R: RaySource + ?Sized>(accel: &A, rays: &R, out: &mut [Option<Hit>]) {
    for_each_ray_chunk(rays, out, |r, o| accel.intersect_bundle(r, o));
}

/// [`Accel::occluded`] of every ray into the same slot of `out` (as many as both have), traced
/// as the structure's bundles ([`Accel::occluded_bundle`]).
pub fn occluded<A: Accel, R: RaySource + ?Sized>(accel: &A, rays: &R, out: &mut [bool]) {
    for_each_ray_chunk(rays, out, |r, o| accel.occluded_bundle(r, o));
}

/// [`Accel::count_hits`] of every ray into the same slot of `out` (as many as both have).
pub fn count_hits<A: Accel, R: RaySource + ?Sized>(accel: &A, rays: &R, out: &mut [usize]) {
    for_each_ray_chunk(rays, out, |r, o| {
        for (o, r) in o.iter_mut().zip(r) {
            *o = accel.count_hits(r);
        }
    });
}

/// [`Accel::all_hits`] of every ray (sorted by `t`, then primitive) into the same slot of
/// `out` (as many as both have).
pub fn all_hits<A: Accel, R: RaySource + ?Sized>(accel: &A, rays: &R, out: &mut [Vec<Hit>]) {
    for_each_ray_chunk(rays, out, |r, o| {
        for (o, r) in o.iter_mut().zip(r) {
            *o = accel.all_hits(r);
        }
    });
}

/// [`Accel::overlapping`] of every box (the primitives meeting it, ascending) into the same
/// slot of `out` (as many as both have).
pub fn overlapping<A: Accel>(accel: &A, boxes: &[Aabb], out: &mut [Vec<u32>]) {
    for_each_chunk(boxes, out, |b, o| {
        for (o, b) in o.iter_mut().zip(b) {
            *o = accel.overlapping(b);
        }
    });
}

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
/// (as many as both have), answered in [`morton_order`].
pub fn closest_points<A: Accel>(
    accel: &A,
    points: &[Vec3],
    max_distance: f32,
    out: &mut [Option<PointHit>],
) {
    in_morton_order(points, out, |p| accel.closest_point(p, max_distance));
}

/// `f(point)` for every point into the same slot of `out` (as many as both have), called in
/// [`morton_order`] on the current pool's threads: for any point query, the order that shares
/// the cache.
pub fn in_morton_order<T: Send>(
    points: &[Vec3],
    out: &mut [T],
    f: impl Fn(Vec3) -> T + Sync + Send,
) {
    // PERF: closest points on one thread (AMD Zen 3, 200,000 points, half in the box grown by
    // a quarter and half near the surface, wide BVH): Morton order ran 1.22–1.39× as fast as
    // the caller's random order on the bunny, spot, the rocker arm and the teapot (a scratch
    // harness).
    let n = points.len().min(out.len());
    let order = morton_order(&points[..n]);
    let sorted = par::map_range(0..n, |k| f(points[order[k] as usize]));
    for (&i, answer) in order.iter().zip(sorted) {
        out[i as usize] = answer;
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

    /// Every ray batch answers each ray as the single query does, from a slice of rays and
    /// from flat rows alike, in the caller's slots, on a pool of two threads and of one.
    #[test]
    fn ray_batches_answer_as_one_at_a_time() {
        let mut rng = Rng::new(5);
        let mut p = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 4.0 - Vec3::splat(2.0);
        let tris: Vec<Triangle> = (0..300).map(|_| Triangle::new(p(), p(), p())).collect();
        let accel = BruteForce::build(&tris, &());
        let rows: Vec<f32> = (0..1500)
            .flat_map(|_| [p(), p()])
            .flat_map(|v| v.to_array())
            .collect();
        let flat = FlatRays::new(&rows, 0.0, 3.0).unwrap();
        let rays: Vec<Ray> = (0..flat.len()).map(|i| flat.ray(i)).collect();
        let n = rays.len();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let (mut a, mut b) = (vec![None; n + 1], vec![None; n]);
                intersect(&accel, &flat, &mut a);
                intersect(&accel, &rays[..], &mut b);
                assert_eq!(a[n], None, "the slot past the rays is left alone");
                let single: Vec<_> = rays.iter().map(|r| accel.intersect(r)).collect();
                assert_eq!((&a[..n], &b[..]), (&single[..], &single[..]));
                assert!(single.iter().any(Option::is_some) && single.iter().any(Option::is_none));
                let mut o = vec![false; n];
                occluded(&accel, &flat, &mut o);
                assert!(o.iter().zip(&single).all(|(o, h)| *o == h.is_some()));
                let mut c = vec![0; n];
                count_hits(&accel, &flat, &mut c);
                assert!(c.iter().zip(&rays).all(|(c, r)| *c == accel.count_hits(r)));
                let mut all = vec![Vec::new(); n];
                all_hits(&accel, &flat, &mut all);
                assert!(all.iter().zip(&rays).all(|(a, r)| *a == accel.all_hits(r)));
                assert!(c.iter().any(|&c| c > 1));
            });
        }
        let boxes: Vec<Aabb> = (0..700).map(|_| Aabb::from_points(&[p(), p()])).collect();
        let mut found = vec![Vec::new(); boxes.len()];
        overlapping(&accel, &boxes, &mut found);
        assert!(
            found
                .iter()
                .zip(&boxes)
                .all(|(f, b)| *f == accel.overlapping(b))
        );
        assert!(found.iter().any(Vec::is_empty) && found.iter().any(|f| !f.is_empty()));
    }

    /// Flat rows that are not rays are refused, naming the first bad row and why.
    #[test]
    fn flat_rays_name_the_first_bad_row() {
        let mut rows = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0].repeat(1000);
        assert!(FlatRays::new(&rows, 0.0, f32::INFINITY).is_ok());
        assert_eq!(
            FlatRays::new(&rows[1..], 0.0, 1.0).unwrap_err(),
            FlatRaysError::Ragged { values: 5999 }
        );
        rows[6 * 700 + 1] = f32::NAN;
        rows[6 * 900 + 3] = 0.0;
        let err = FlatRays::new(&rows, 0.0, 1.0).unwrap_err();
        assert_eq!(
            err,
            FlatRaysError::Invalid {
                row: 700,
                fault: RayFault::NonFinite
            }
        );
        assert_eq!(err.to_string(), "ray 700 has a non-finite coordinate");
        rows[6 * 700 + 1] = 0.0;
        let err = FlatRays::new(&rows, 0.0, 1.0).unwrap_err();
        assert_eq!(
            err,
            FlatRaysError::Invalid {
                row: 900,
                fault: RayFault::ZeroDirection
            }
        );
        let err = FlatRays::new(&rows[..6], 2.0, 1.0).unwrap_err();
        assert_eq!(
            err,
            FlatRaysError::Invalid {
                row: 0,
                fault: RayFault::Interval
            }
        );
    }
}

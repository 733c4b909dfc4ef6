//! Inside, outside and signed distance over any rt-accel structure.
//!
//! - [`WindingTree`] answers whether a point is inside a triangle mesh by its generalised
//!   winding number, robust to holes and cracks: counted exactly by the crossings of one ray
//!   with the mesh and caps over its holes (the [`crossing`] module), or evaluated fast
//!   through Barill et al.'s cluster expansion with a stated error bound, and summed exactly
//!   where that bound cannot decide (the [`winding`] module). [`winding_number_exact`] is the
//!   reference sum.
//! - [`SignedDistance`], implemented for every [`Accel`], puts that sign on the structure's
//!   closest-point distance ([`SignedDistance::signed_distance`]), and offers the simple
//!   alternative that counts the crossings of rays ([`SignedDistance::inside_by_parity`]).
//! - [`batch`] answers many points at once, on every thread of the current rayon pool: signed
//!   distances, inside tests and winding numbers.
//!
//! The distance comes from the structure's [`Accel::closest_point`], exactly brute force's; the
//! sign comes from the winding number, which is the same for every structure.
//!
//! ```
//! use rt_core::{Accel, BruteForce, Triangle, glam::Vec3};
//! use rt_sdf::{SignedDistance, WindingTree};
//! // A tetrahedron with its faces turned outwards.
//! let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
//! let tris = [
//!     Triangle::new(p[0], p[2], p[1]),
//!     Triangle::new(p[0], p[1], p[3]),
//!     Triangle::new(p[0], p[3], p[2]),
//!     Triangle::new(p[1], p[2], p[3]),
//! ];
//! let accel = BruteForce::build(&tris, &()); // any structure: rt_bvh::Bvh, ...
//! let sign = WindingTree::build(&tris).unwrap();
//! let inside = Vec3::splat(0.1);
//! assert!((sign.winding_number(inside, 0.0).value - 1.0).abs() < 1e-12);
//! let sd = accel.signed_distance(&sign, inside, f32::INFINITY).unwrap();
//! assert_eq!(sd.distance, -0.1);
//! let outside = accel.signed_distance(&sign, Vec3::new(0.0, 0.0, -2.0), f32::INFINITY).unwrap();
//! assert_eq!(outside.distance, 2.0);
//! assert!(accel.inside_by_parity(inside) && !accel.inside_by_parity(Vec3::splat(0.5)));
//! ```
#![warn(missing_docs)]

pub mod batch;
pub mod crossing;
pub mod winding;

#[cfg(test)]
mod test_meshes;

pub use winding::{NotATriangle, Winding, WindingTree, solid_angle, winding_number_exact};

use rt_core::glam::Vec3;
use rt_core::{Accel, Counters, DynAccel, NoStats, PointHit, Primitive, Ray, Stats};

/// The answer to a signed-distance query ([`SignedDistance::signed_distance`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SignedPoint {
    /// The closest point: exactly [`Accel::closest_point`]'s answer.
    pub near: PointHit,
    /// Whether the query point is inside ([`WindingTree::is_inside`]).
    pub inside: bool,
    /// `near.distance`, negative when inside.
    pub distance: f32,
}

impl SignedPoint {
    /// The closest point `near`, signed: its distance negated when `inside`.
    pub fn signed(near: PointHit, inside: bool) -> Self {
        let distance = if inside {
            -near.distance
        } else {
            near.distance
        };
        Self {
            near,
            inside,
            distance,
        }
    }
}

/// Inside, outside and signed distance, for every [`Accel`]: the structure's closest point
/// and ray counts with the winding number's sign. Nothing here is the structure's to
/// implement; the conformance kit checks the answers against brute force's.
pub trait SignedDistance: Accel {
    /// The distance from `point` to the nearest primitive no farther than `max_distance`,
    /// negative when `point` is inside the mesh by `sign`'s winding number
    /// ([`WindingTree::is_inside`]), reporting the closest-point walk's events to `stats`.
    ///
    /// `sign` must be built over the primitives this structure was built from. `None` when
    /// nothing lies that near, and for an invalid query (see
    /// [`ClosestPointQuery::new`](rt_core::ClosestPointQuery::new)).
    #[inline]
    fn signed_distance_with<S: Stats>(
        &self,
        sign: &WindingTree,
        point: Vec3,
        max_distance: f32,
        stats: &mut S,
    ) -> Option<SignedPoint> {
        let near = self.closest_point_with(point, max_distance, stats)?;
        Some(SignedPoint::signed(near, sign.is_inside(point)))
    }

    /// The signed distance from `point`: see
    /// [`signed_distance_with`](SignedDistance::signed_distance_with).
    #[inline]
    fn signed_distance(
        &self,
        sign: &WindingTree,
        point: Vec3,
        max_distance: f32,
    ) -> Option<SignedPoint> {
        self.signed_distance_with(sign, point, max_distance, &mut NoStats)
    }

    /// Whether `point` is inside by counting crossings: a ray from `point` that crosses the
    /// surface an odd number of times ([`Accel::count_hits`]) starts inside, and the majority
    /// of three rays in fixed directions (not along any axis) decides.
    ///
    /// The simple alternative to the winding number ([`WindingTree::is_inside`]), and with no
    /// tree to build: right for a closed mesh, except that a ray through a shared edge or
    /// vertex may count the crossing on both triangles, which the vote outweighs only when the
    /// other two rays are clean. A mesh with holes answers by where the rays happen to leave.
    /// A point with a non-finite coordinate is outside.
    fn inside_by_parity(&self, point: Vec3) -> bool {
        // Three unit vectors with exact f32 coordinates, pairwise perpendicular.
        const DIRECTIONS: [Vec3; 3] = [
            Vec3::new(0.6, 0.48, 0.64),
            Vec3::new(-0.48, 0.64, -0.6),
            Vec3::new(0.64, -0.6, -0.48),
        ];
        if !point.is_finite() {
            return false;
        }
        let odd = DIRECTIONS
            .iter()
            .filter(|&&d| self.count_hits(&Ray::new(point, d)) % 2 == 1)
            .count();
        odd >= 2
    }
}

impl<A: Accel> SignedDistance for A {}

/// [`SignedDistance::signed_distance`] for each `(point, max_distance)` into the same slot of
/// `out` (as many as both have), over a structure behind [`DynAccel`] (a structure chosen at
/// run time), the closest-point walks counted into `counters` if given: its
/// [`closest_points_all`](DynAccel::closest_points_all), signed by [`WindingTree::is_inside`].
pub fn signed_distances<P: Primitive, A: DynAccel<P> + ?Sized>(
    accel: &A,
    sign: &WindingTree,
    points: &[(Vec3, f32)],
    out: &mut [Option<SignedPoint>],
    mut counters: Option<&mut Counters>,
) {
    // In chunks through a buffer on the stack: no allocation per call.
    const CHUNK: usize = 64;
    let n = points.len().min(out.len());
    for (points, out) in points[..n].chunks(CHUNK).zip(out[..n].chunks_mut(CHUNK)) {
        let mut near = [None; CHUNK];
        let near = &mut near[..points.len()];
        accel.closest_points_all(points, near, counters.as_deref_mut());
        for ((o, &(p, _)), near) in out.iter_mut().zip(points).zip(near.iter()) {
            *o = near.map(|near| SignedPoint::signed(near, sign.is_inside(p)));
        }
    }
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

//! Closest-point queries: the point of a scene nearest to a given point.
//!
//! A structure answers them through one traversal, [`Accel::ball_query`](crate::Accel), which
//! walks a ball around the query point that shrinks as primitives are found: it offers every
//! primitive that may lie in the ball to a [`BallQuery`] and prunes every box farther away than
//! the ball's radius. [`ClosestPointQuery`] is the query behind
//! [`Accel::closest_point`](crate::Accel::closest_point); other queries (within a transformed
//! instance, or every primitive within a fixed radius) use the same traversal.
//!
//! # Exactness
//! Every structure reports exactly what [`BruteForce`](crate::BruteForce) reports: the same
//! primitive, point and distance. That holds because the answer depends only on each
//! primitive's own [`Primitive::closest_point`], compared with one rule ([`PointHit::beats`]),
//! and because pruning is conservative: a box is skipped only when it lies farther than the best
//! distance so far widened by more than any rounding in a primitive's computed distance (see
//! [`ClosestPointQuery`]).

use crate::{Aabb, Feature, PointHit, Primitive, Ray, closest_feature_on_triangle, point_distance};
use glam::Vec3;

/// What a closest-point traversal ([`Accel::ball_query`](crate::Accel::ball_query)) works
/// for: a ball around [`center`](BallQuery::center) whose radius may shrink with every
/// primitive [`test`](BallQuery::test)ed.
///
/// A structure offers every primitive it holds that may lie within the ball, and may skip a
/// box (or cell) only when its [`Aabb::distance_squared`] from the centre is greater than
/// [`radius_sq`](BallQuery::radius_sq), read again after each test.
pub trait BallQuery<P> {
    /// The ball's centre.
    fn center(&self) -> Vec3;

    /// The ball's squared radius: boxes farther than this hold nothing the query wants. A
    /// negative value (an invalid query) prunes everything.
    fn radius_sq(&self) -> f32;

    /// Offers primitive `id` of the build input. A structure calls it for each primitive it
    /// reaches (possibly more than once for the same one) and reports it to its
    /// [`Stats`](crate::Stats) as a primitive test.
    fn test(&mut self, prim: &P, id: u32);

    /// Offers primitive `id` as the triangle `(v0, v0 + e1, v0 + e2)` (edges exactly as
    /// [`Triangle::closest_point`](crate::Triangle) computes them): what a structure that keeps
    /// triangles pre-processed in its own layout calls instead of [`test`](BallQuery::test),
    /// for primitives whose [`Primitive::as_triangle`] is `Some`.
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32);
}

/// A query behind a mutable reference (`&mut dyn BallQuery<P>` included) is a query, so a
/// structure known only as a trait object can still run a caller's query.
impl<P, Q: BallQuery<P> + ?Sized> BallQuery<P> for &mut Q {
    #[inline(always)]
    fn center(&self) -> Vec3 {
        (**self).center()
    }
    #[inline(always)]
    fn radius_sq(&self) -> f32 {
        (**self).radius_sq()
    }
    #[inline(always)]
    fn test(&mut self, prim: &P, id: u32) {
        (**self).test(prim, id);
    }
    #[inline(always)]
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        (**self).test_triangle(v0, e1, e2, id);
    }
}

/// The closest-point query: the nearest primitive to a point within a maximum distance, ties
/// to the smallest index ([`PointHit::beats`]).
///
/// Its ball's radius is the best distance so far (at first the maximum distance), widened by a
/// relative `2⁻¹⁶` and an absolute `2⁻¹⁶·(|p|∞ + |scene|∞)`. A primitive's computed distance
/// is off by at most a few units in the last place of those magnitudes (its closest point is
/// computed in `f64` and rounded once, then measured in `f64`), so the widening keeps every
/// box that could hold a primitive tying with or beating the best, and every structure finds
/// exactly the answer brute force finds.
///
/// ```
/// use rt_core::{Aabb, BallQuery, ClosestPointQuery, Triangle, glam::Vec3};
/// let tri = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
/// let mut q = ClosestPointQuery::new(Vec3::new(0.2, 0.2, 3.0), f32::INFINITY, &Aabb::EMPTY);
/// q.test(&tri, 0);
/// let hit = q.best().unwrap();
/// assert_eq!((hit.prim, hit.distance), (0, 3.0));
/// assert!(q.radius_sq() >= 9.0);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct ClosestPointQuery {
    center: Vec3,
    max_distance: f32,
    slack: f32,
    radius_sq: f32,
    best: Option<PointHit>,
}

impl ClosestPointQuery {
    /// Relative widening of the pruning radius.
    const WIDEN: f32 = 1.0 + 1.0 / 65536.0;

    /// A query for the primitive nearest to `point` no farther than `max_distance` (inclusive;
    /// `f32::INFINITY` for no limit), among primitives inside `scene` (the structure's
    /// [`Accel::bounds`](crate::Accel::bounds), which sets the rounding margin).
    ///
    /// An invalid query, one whose point has a non-finite coordinate or one beyond
    /// [`Ray::MAX_ORIGIN`], or whose `max_distance` is negative or NaN, finds nothing.
    pub fn new(point: Vec3, max_distance: f32, scene: &Aabb) -> Self {
        let valid = point.is_finite()
            && point.abs().max_element() <= Ray::MAX_ORIGIN
            && max_distance >= 0.0;
        if !valid {
            return Self {
                center: Vec3::ZERO,
                max_distance: -1.0,
                slack: 0.0,
                radius_sq: -1.0,
                best: None,
            };
        }
        let scene_size = if scene.is_empty() {
            0.0
        } else {
            scene.min.abs().max(scene.max.abs()).max_element()
        };
        let slack = (point.abs().max_element() + scene_size) / 65536.0;
        let mut q = Self {
            center: point,
            max_distance,
            slack,
            radius_sq: 0.0,
            best: None,
        };
        q.set_radius(max_distance);
        q
    }

    /// The ball's centre: the query point.
    #[inline(always)]
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// The squared pruning radius (negative for an invalid query).
    #[inline(always)]
    pub fn radius_sq(&self) -> f32 {
        self.radius_sq
    }

    fn set_radius(&mut self, distance: f32) {
        let r = distance * Self::WIDEN + self.slack;
        self.radius_sq = r * r;
    }

    /// The best answer so far (after the traversal, the answer).
    pub fn best(&self) -> Option<PointHit> {
        self.best
    }
}

impl<P: Primitive> BallQuery<P> for ClosestPointQuery {
    #[inline(always)]
    fn center(&self) -> Vec3 {
        self.center
    }

    #[inline(always)]
    fn radius_sq(&self) -> f32 {
        self.radius_sq
    }

    #[inline]
    fn test(&mut self, prim: &P, id: u32) {
        self.offer(prim.closest_feature(self.center), id);
    }

    #[inline]
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        self.offer(closest_feature_on_triangle(v0, e1, e2, self.center), id);
    }
}

impl ClosestPointQuery {
    /// Keeps primitive `id`'s nearest point if it is within the maximum distance and beats the
    /// best so far, and shrinks the ball to it.
    #[inline]
    fn offer(&mut self, (point, feature): (Vec3, Feature), id: u32) {
        let distance = point_distance(self.center, point);
        let better = match self.best {
            None => true,
            Some(b) => PointHit::beats(distance, id, b.distance, b.prim),
        };
        if distance <= self.max_distance && better {
            self.best = Some(PointHit {
                prim: id,
                point,
                distance,
                feature,
            });
            self.set_radius(distance);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Triangle;

    #[test]
    fn the_query_keeps_the_nearest_and_breaks_ties_by_index() {
        let a = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let scene = a.bounds();
        let p = Vec3::new(0.25, 0.25, 1.0);
        let mut q = ClosestPointQuery::new(p, f32::INFINITY, &scene);
        BallQuery::<Triangle>::test(&mut q, &a, 5);
        BallQuery::<Triangle>::test(&mut q, &a, 3); // same distance, smaller index
        BallQuery::<Triangle>::test(&mut q, &a, 4);
        assert_eq!(q.best().map(|h| h.prim), Some(3));
        // Nothing within a maximum distance below the answer.
        let mut q = ClosestPointQuery::new(p, 0.999, &scene);
        BallQuery::<Triangle>::test(&mut q, &a, 0);
        assert_eq!(q.best(), None);
        // Exactly at the maximum distance counts.
        let mut q = ClosestPointQuery::new(p, 1.0, &scene);
        BallQuery::<Triangle>::test(&mut q, &a, 0);
        assert_eq!(q.best().map(|h| h.distance), Some(1.0));
    }

    #[test]
    fn invalid_queries_prune_everything_and_find_nothing() {
        let a = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        for (p, max) in [
            (Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
            (Vec3::new(0.0, f32::INFINITY, 0.0), 1.0),
            (Vec3::splat(2.0 * Ray::MAX_ORIGIN), f32::INFINITY),
            (Vec3::ZERO, -1.0),
            (Vec3::ZERO, f32::NAN),
        ] {
            let mut q = ClosestPointQuery::new(p, max, &a.bounds());
            assert!(q.radius_sq() < 0.0);
            BallQuery::<Triangle>::test(&mut q, &a, 0);
            assert_eq!(q.best(), None, "{p} {max}");
        }
    }
}

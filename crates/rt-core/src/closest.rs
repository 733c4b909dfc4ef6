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

use crate::{Aabb, Primitive, Ray};
use glam::{DVec3, Vec3};

/// The answer to a closest-point query: which primitive, the point on it nearest to the query
/// point, and their distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointHit {
    /// Index of the primitive in the build input.
    pub prim: u32,
    /// The point of the primitive nearest to the query point.
    pub point: Vec3,
    /// The distance from the query point to `point` ([`point_distance`]).
    pub distance: f32,
    /// The part of the primitive `point` lies on ([`Primitive::closest_feature`]): a
    /// triangle's face, one of its edges or one of its vertices. A signed distance takes its
    /// sign from the normal of this feature (Bærentzen & Aanæs 2005: a vertex's or an edge's
    /// normal is the angle-weighted mean of the faces around it).
    pub feature: Feature,
}

/// The part of a primitive a closest point lies on: its face (the interior of a triangle, and
/// all of a smooth surface such as a sphere), an edge or a vertex.
///
/// A triangle numbers its vertices as it stores them (`v0`, `v1`, `v2`) and its edges by their
/// first vertex: edge 0 is `v0 v1`, edge 1 is `v1 v2`, edge 2 is `v2 v0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Feature {
    /// The interior of the surface.
    Face,
    /// Edge `k` (0, 1 or 2).
    Edge(u8),
    /// Vertex `k` (0, 1 or 2).
    Vertex(u8),
}

impl PointHit {
    /// The tie rule every structure follows: a primitive at `distance` replaces the best so far
    /// when it is strictly nearer, or equally near with a smaller index, so the answer is unique.
    #[inline(always)]
    pub fn beats(distance: f32, prim: u32, best_distance: f32, best_prim: u32) -> bool {
        distance < best_distance || (distance == best_distance && prim < best_prim)
    }

    /// Whether two answers agree: both none, or the same primitive and feature at distances
    /// equal or within a relative `1e-5`. The equality the conformance kit and `compare` use.
    pub fn agree(a: Option<PointHit>, b: Option<PointHit>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                let scale = a.distance.abs().max(b.distance.abs());
                a.prim == b.prim
                    && a.feature == b.feature
                    && (a.distance == b.distance || (a.distance - b.distance).abs() <= 1e-5 * scale)
            }
            _ => false,
        }
    }
}

/// The distance between two points, computed in `f64` and rounded once, so it neither
/// overflows nor loses the small distances of nearby points. Every closest-point query measures
/// with it.
#[inline]
pub fn point_distance(a: Vec3, b: Vec3) -> f32 {
    (a.as_dvec3() - b.as_dvec3()).length() as f32
}

/// The point of the triangle `(v0, v0 + e1, v0 + e2)` nearest to `p`.
///
/// Voronoi regions in the order of Ericson, *Real-Time Collision Detection* §5.1.5: the three
/// vertex regions, the three edge regions, then the face, each decided by dot products of the
/// edges with `p`'s offsets from the vertices. The work is done in `f64` (the inputs convert
/// exactly, and no product of `f32` coordinates overflows there) and rounded once at the end.
///
/// Robust where the textbook version is not:
/// - a degenerate triangle (zero area: collinear or coincident vertices) gets the nearest point
///   of its three edges instead of a division by zero;
/// - the face region's barycentric weights are clamped to the triangle, so rounding in a
///   sliver can move the answer along the triangle but never off it.
///
/// The triangle is given by a vertex and two edges because that is how rt-bvh's SIMD packs
/// store a Möller–Trumbore triangle; [`Triangle::closest_point`](crate::Triangle) passes
/// `v1 - v0` and `v2 - v0` rounded to `f32`, so both give the same bits.
///
/// ```
/// use rt_core::{closest_point_on_triangle, glam::Vec3};
/// let q = closest_point_on_triangle(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.25, 0.25, 2.0));
/// assert_eq!(q, Vec3::new(0.25, 0.25, 0.0));
/// let q = closest_point_on_triangle(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(5.0, 5.0, 0.0));
/// assert_eq!(q, Vec3::new(0.5, 0.5, 0.0)); // on the long edge
/// ```
pub fn closest_point_on_triangle(v0: Vec3, e1: Vec3, e2: Vec3, p: Vec3) -> Vec3 {
    closest_feature_on_triangle(v0, e1, e2, p).0
}

/// [`closest_point_on_triangle`], with the [`Feature`] of the triangle the point lies on: the
/// Voronoi region the point fell in (a degenerate triangle's answer is always on an edge).
///
/// ```
/// use rt_core::{Feature, closest_feature_on_triangle, glam::Vec3};
/// let (v0, e1, e2) = (Vec3::ZERO, Vec3::X, Vec3::Y);
/// let face = closest_feature_on_triangle(v0, e1, e2, Vec3::new(0.25, 0.25, 2.0));
/// assert_eq!(face, (Vec3::new(0.25, 0.25, 0.0), Feature::Face));
/// let long_edge = closest_feature_on_triangle(v0, e1, e2, Vec3::new(5.0, 5.0, 0.0));
/// assert_eq!(long_edge, (Vec3::new(0.5, 0.5, 0.0), Feature::Edge(1)));
/// let corner = closest_feature_on_triangle(v0, e1, e2, Vec3::new(-1.0, -1.0, 0.0));
/// assert_eq!(corner, (Vec3::ZERO, Feature::Vertex(0)));
/// ```
pub fn closest_feature_on_triangle(v0: Vec3, e1: Vec3, e2: Vec3, p: Vec3) -> (Vec3, Feature) {
    let (a, ab, ac) = (v0.as_dvec3(), e1.as_dvec3(), e2.as_dvec3());
    let ap = p.as_dvec3() - a;
    let ratio = |num: f64, den: f64| {
        if den > 0.0 {
            (num / den).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    // Products of two `f32` values are exact in `f64`, so the normal is zero exactly when the
    // edges are parallel (or one is zero): then the Voronoi regions below are not defined.
    let segment = |s: DVec3, d: DVec3| s + ratio((ap - s).dot(d), d.dot(d)) * d;
    let edges = || {
        [
            (segment(DVec3::ZERO, ab), Feature::Edge(0)),
            (segment(DVec3::ZERO, ac), Feature::Edge(2)),
            (segment(ab, ac - ab), Feature::Edge(1)),
        ]
        .into_iter()
        .min_by(|(x, _), (y, _)| {
            (ap - *x)
                .length_squared()
                .total_cmp(&(ap - *y).length_squared())
        })
        .map_or((v0, Feature::Edge(0)), |(q, f)| ((a + q).as_vec3(), f))
    };
    if ab.cross(ac) == DVec3::ZERO {
        return edges();
    }
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (v0, Feature::Vertex(0)); // vertex region of v0
    }
    let bp = ap - ab;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return ((a + ab).as_vec3(), Feature::Vertex(1)); // vertex region of v1
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return ((a + ratio(d1, d1 - d3) * ab).as_vec3(), Feature::Edge(0)); // edge v0 v1
    }
    let cp = ap - ac;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return ((a + ac).as_vec3(), Feature::Vertex(2)); // vertex region of v2
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return ((a + ratio(d2, d2 - d6) * ac).as_vec3(), Feature::Edge(2)); // edge v0 v2
    }
    let va = d3 * d6 - d5 * d4;
    let (e, f) = (d4 - d3, d5 - d6);
    if va <= 0.0 && e >= 0.0 && f >= 0.0 {
        return (
            (a + ab + ratio(e, e + f) * (ac - ab)).as_vec3(),
            Feature::Edge(1),
        ); // edge v1 v2
    }
    let denom = va + vb + vc;
    if !(denom > 0.0 && denom.is_finite()) {
        // Rounding left no area to divide by: the edges again.
        return edges();
    }
    let v = (vb / denom).clamp(0.0, 1.0);
    let w = (vc / denom).clamp(0.0, 1.0 - v);
    ((a + v * ab + w * ac).as_vec3(), Feature::Face)
}

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

    #[test]
    fn each_voronoi_region_names_its_feature() {
        let (v0, v1, v2) = (
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        );
        let f = |p: Vec3| closest_feature_on_triangle(v0, v1 - v0, v2 - v0, p);
        let lift = Vec3::new(0.0, 0.0, 3.0);
        assert_eq!(
            f(Vec3::new(0.5, 0.5, 0.0) + lift),
            (Vec3::new(0.5, 0.5, 0.0), Feature::Face)
        );
        assert_eq!(f(Vec3::new(-1.0, -1.0, 1.0)), (v0, Feature::Vertex(0)));
        assert_eq!(f(Vec3::new(3.0, -1.0, 1.0)), (v1, Feature::Vertex(1)));
        assert_eq!(f(Vec3::new(-1.0, 3.0, 1.0)), (v2, Feature::Vertex(2)));
        let on = |p: Vec3, feature| (p, feature);
        assert_eq!(f(Vec3::new(1.0, -1.0, 1.0)), on(Vec3::X, Feature::Edge(0)));
        assert_eq!(
            f(Vec3::new(2.0, 2.0, 0.0)),
            on(Vec3::new(1.0, 1.0, 0.0), Feature::Edge(1))
        );
        assert_eq!(f(Vec3::new(-1.0, 1.0, 1.0)), on(Vec3::Y, Feature::Edge(2)));
        // A degenerate (collinear) triangle answers on an edge.
        let (_, feature) = closest_feature_on_triangle(v0, Vec3::X, Vec3::X * 2.0, Vec3::Y);
        assert!(matches!(feature, Feature::Edge(_)), "{feature:?}");
    }
    use crate::{Rng, Triangle};

    /// The nearest of many points sampled on the triangle: an upper bound the exact answer must
    /// reach, and nearly attain.
    fn sampled(v0: Vec3, v1: Vec3, v2: Vec3, p: Vec3) -> f32 {
        let mut best = f32::INFINITY;
        let n = 200;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                let q = v0 + u * (v1 - v0) + v * (v2 - v0);
                best = best.min(point_distance(p, q));
            }
        }
        best
    }

    #[test]
    fn every_region_matches_dense_sampling() {
        let mut rng = Rng::new(5);
        let mut v = || {
            Vec3::new(
                rng.f32() * 4.0 - 2.0,
                rng.f32() * 4.0 - 2.0,
                rng.f32() - 0.5,
            )
        };
        for _ in 0..300 {
            let (v0, v1, v2, p) = (v(), v(), v(), v() * 2.0);
            let t = Triangle::new(v0, v1, v2);
            let q = t.closest_point(p);
            let d = point_distance(p, q);
            let s = sampled(v0, v1, v2, p);
            // The exact answer is never beaten by a sample, and the samples come within their
            // spacing of it.
            assert!(d <= s * (1.0 + 1e-5) + 1e-6, "{d} > sampled {s}");
            assert!(s - d <= 0.05, "{d} far below sampled {s}");
            // And the point lies on the triangle's plane, inside its box.
            assert!(t.bounds().distance_squared(q) <= 1e-10);
        }
    }

    #[test]
    fn degenerate_triangles_get_their_nearest_edge_point() {
        let p = Vec3::new(1.0, 2.0, 0.0);
        // Collinear: the segment from 0 to 4 along x.
        let q = closest_point_on_triangle(Vec3::ZERO, Vec3::X * 2.0, Vec3::X * 4.0, p);
        assert_eq!(q, Vec3::new(1.0, 0.0, 0.0));
        // All three vertices at one point.
        let c = Vec3::new(3.0, 3.0, 3.0);
        assert_eq!(closest_point_on_triangle(c, Vec3::ZERO, Vec3::ZERO, p), c);
        // A zero edge and a real one.
        let q = closest_point_on_triangle(Vec3::ZERO, Vec3::ZERO, Vec3::Y * 4.0, p);
        assert_eq!(q, Vec3::new(0.0, 2.0, 0.0));
    }

    #[test]
    fn far_points_and_huge_triangles_stay_finite() {
        let big = 1e30;
        let q = closest_point_on_triangle(
            Vec3::splat(-big),
            Vec3::new(2.0 * big, 0.0, 0.0),
            Vec3::new(0.0, 2.0 * big, 0.0),
            Vec3::new(0.0, 0.0, Ray::MAX_ORIGIN),
        );
        assert!(q.is_finite());
        assert_eq!(q.z, -big);
        let q = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y).closest_point(Vec3::splat(1e12));
        assert_eq!(q, Vec3::new(0.5, 0.5, 0.0));
    }

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

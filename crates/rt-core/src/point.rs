//! Points and the parts of primitives they lie on: the answer of a closest-point query
//! ([`PointHit`], [`Feature`]) and the exact geometry it is computed with ([`point_distance`],
//! the nearest point and feature of a triangle).

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
    /// The part of the primitive `point` lies on ([`Primitive::closest_feature`](crate::Primitive::closest_feature)): a
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
    use crate::{Primitive, Ray, Rng, Triangle};

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
}

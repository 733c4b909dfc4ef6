//! The small trait that makes structures generic over what they store.

use crate::{Aabb, MtTriangle, PrimHit, Ray, SurfacePoint, Triangle};
use glam::Vec3;
use std::fmt::Debug;

/// The ray–triangle test a triangle primitive runs (see [`Primitive::as_triangle`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TriangleTest {
    /// [`Triangle::intersect_watertight`](crate::Triangle::intersect_watertight).
    Watertight,
    /// [`Triangle::intersect_moller_trumbore`](crate::Triangle::intersect_moller_trumbore).
    MollerTrumbore,
}

/// A geometric primitive that acceleration structures can store and intersect.
///
/// Structures use [`bounds`](Primitive::bounds) and [`centroid`](Primitive::centroid) while
/// building and [`intersect`](Primitive::intersect) while tracing; the intersect call is the
/// "primitive test" that [`Stats`](crate::Stats) counts.
pub trait Primitive: Clone + Send + Sync + Debug + 'static {
    /// The smallest axis-aligned box holding the primitive.
    fn bounds(&self) -> Aabb;

    /// A representative point used to sort primitives into halves; the box centre by default.
    #[inline]
    fn centroid(&self) -> Vec3 {
        self.bounds().center()
    }

    /// Whether the primitive can ever be hit: finite coordinates and a non-degenerate shape.
    ///
    /// Every structure, and [`BruteForce`](crate::BruteForce), leaves invalid primitives out at
    /// build time, so a triangle with a NaN vertex is never reported and never widens a box.
    fn is_valid(&self) -> bool;

    /// Bounds of the part of the primitive inside the closed box `cell`, or `None` if the
    /// primitive does not meet it. Spatial subdivisions use this to reference a primitive only
    /// from cells it really overlaps, and kd-tree builders for "perfect splits".
    ///
    /// The result must contain every point of the primitive in `cell` and lie inside `cell`. The
    /// default, the primitive's bounds cut to the cell, is always correct but loose; [`Triangle`]
    /// clips exactly.
    ///
    /// [`Triangle`]: crate::Triangle
    #[inline]
    fn clip_bounds(&self, cell: &Aabb) -> Option<Aabb> {
        let b = self.bounds();
        b.overlaps(cell).then(|| b.intersection(cell))
    }

    /// [`clip_bounds`](Primitive::clip_bounds) for both halves of `cell` split at
    /// `x[axis] = pos`: left `x[axis] <= pos`, right `x[axis] >= pos`.
    ///
    /// The default clips twice; [`Triangle`](crate::Triangle) clips once and splits the polygon.
    #[inline]
    fn split_bounds(&self, cell: &Aabb, axis: usize, pos: f32) -> (Option<Aabb>, Option<Aabb>) {
        let mut left = *cell;
        left.max[axis] = pos;
        let mut right = *cell;
        right.min[axis] = pos;
        (self.clip_bounds(&left), self.clip_bounds(&right))
    }

    /// Whether the primitive meets the closed box `b`: what box overlap queries
    /// ([`Accel::overlapping`](crate::Accel::overlapping)) report.
    ///
    /// The default asks [`clip_bounds`](Primitive::clip_bounds), which clips a
    /// [`Triangle`](crate::Triangle) to the box in `f64` (a triangle beside the box, whose
    /// bounding box meets it, is not reported) and falls back to the bounding box for types that do not clip.
    /// [`Sphere`](crate::Sphere) measures its distance from the box. Structures prune with
    /// boxes that contain each primitive's [`clip_bounds`](Primitive::clip_bounds) within them,
    /// so the answer must imply that `clip_bounds(b)` is `Some`.
    #[inline]
    fn overlaps_box(&self, b: &Aabb) -> bool {
        self.clip_bounds(b).is_some()
    }

    /// The hit with `ray.t_min <= t <= t_max`, if any. Both ends are inclusive so that a structure
    /// that shrinks `t_max` to the closest hit so far still finds an equally close hit on a
    /// primitive with a smaller index (the tie rule of [`Accel`](crate::Accel)).
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit>;

    /// The point of the primitive's surface nearest to `p`: what closest-point queries
    /// ([`Accel::closest_point`](crate::Accel::closest_point)) compare, by
    /// [`point_distance`](crate::point_distance) from `p`.
    ///
    /// It must be a deterministic function of the primitive and `p`, and lie within a few units
    /// in the last place of the primitive's largest coordinate from the true nearest point (the
    /// margin [`ClosestPointQuery`](crate::ClosestPointQuery) prunes with). [`Triangle`] and
    /// [`Sphere`](crate::Sphere) compute it in `f64` and round once.
    ///
    /// [`Triangle`]: crate::Triangle
    fn closest_point(&self, p: Vec3) -> Vec3;

    /// [`closest_point`](Primitive::closest_point), with the part of the primitive the point
    /// lies on: what [`PointHit::feature`](crate::PointHit) reports. The default calls every
    /// point a [`Feature::Face`](crate::Feature), right for smooth surfaces;
    /// [`Triangle`](crate::Triangle) names its edges and vertices.
    #[inline]
    fn closest_feature(&self, p: Vec3) -> (Vec3, crate::Feature) {
        (self.closest_point(p), crate::Feature::Face)
    }

    /// The primitive as a plain triangle and the test its [`intersect`](Primitive::intersect)
    /// runs, if it is one; `None` (the default) otherwise.
    ///
    /// Structures with SIMD triangle kernels (rt-bvh's wide layout) store such primitives
    /// pre-processed in packs and run that test themselves, bit for bit as the scalar function
    /// does, instead of calling `intersect`. Return `Some` only when `intersect` and `occludes`
    /// answer exactly as that test on that triangle does, and `closest_point` and
    /// `overlaps_box` as [`Triangle`](crate::Triangle)'s (for the Möller–Trumbore test, as
    /// [`MtTriangle`](crate::MtTriangle)'s).
    #[inline]
    fn as_triangle(&self) -> Option<(crate::Triangle, TriangleTest)> {
        None
    }

    /// Whether the ray meets the primitive within `ray.t_min ..= t_max`. Defaults to
    /// [`intersect`](Primitive::intersect); primitives may skip computing surface coordinates.
    #[inline]
    fn occludes(&self, ray: &Ray, t_max: f32) -> bool {
        self.intersect(ray, t_max).is_some()
    }

    /// The surface at a hit this primitive reported for `ray` (`t`, `u`, `v` as in its
    /// [`PrimHit`]): the point, the geometric normal and an error bound, from which
    /// [`SurfacePoint::spawn_ray`] starts shadow, reflection and refraction rays that cannot
    /// hit this surface again at their origin.
    ///
    /// The default knows nothing of the shape: it takes `ray.at(t)`, a normal facing back along
    /// the ray, and an error bound of [`OFFSET_ULPS`](crate::OFFSET_ULPS) relative units of the
    /// coordinates involved, doubled for the unknown error of `t`. That is right for rays
    /// leaving towards the side the ray came from, which is all a shadow ray towards a light in
    /// front of the surface needs; primitives that can be refracted through or lit from behind
    /// should override it, as [`Triangle`](crate::Triangle) and [`Sphere`](crate::Sphere) do.
    fn surface(&self, ray: &Ray, t: f32, _u: f32, _v: f32) -> SurfacePoint {
        let point = ray.at(t);
        let magnitude = point.abs().max_element() + ray.origin.abs().max_element();
        SurfacePoint {
            point,
            normal: -ray.dir().normalize_or(Vec3::Z),
            error: 2.0 * crate::surface::error_bound(magnitude),
        }
    }
}

impl Primitive for Triangle {
    #[inline]
    fn bounds(&self) -> Aabb {
        Aabb::new(
            self.v0.min(self.v1).min(self.v2),
            self.v0.max(self.v1).max(self.v2),
        )
    }

    #[inline]
    fn centroid(&self) -> Vec3 {
        (self.v0 + self.v1 + self.v2) * (1.0 / 3.0)
    }

    fn is_valid(&self) -> bool {
        self.v0.is_finite()
            && self.v1.is_finite()
            && self.v2.is_finite()
            && self.normal() != Vec3::ZERO
    }

    #[inline]
    fn clip_bounds(&self, cell: &Aabb) -> Option<Aabb> {
        crate::clip_triangle_bounds([self.v0, self.v1, self.v2], cell)
    }

    #[inline]
    fn split_bounds(&self, cell: &Aabb, axis: usize, pos: f32) -> (Option<Aabb>, Option<Aabb>) {
        crate::split_triangle_bounds([self.v0, self.v1, self.v2], cell, axis, pos)
    }

    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        self.intersect_watertight(ray, t_max)
    }

    #[inline]
    fn as_triangle(&self) -> Option<(Triangle, TriangleTest)> {
        Some((*self, TriangleTest::Watertight))
    }

    /// [`closest_point_on_triangle`](crate::closest_point_on_triangle) with the edges
    /// `v1 - v0` and `v2 - v0`.
    #[inline]
    fn closest_point(&self, p: Vec3) -> Vec3 {
        self.closest_feature(p).0
    }

    #[inline]
    fn closest_feature(&self, p: Vec3) -> (Vec3, crate::Feature) {
        crate::closest_feature_on_triangle(self.v0, self.v1 - self.v0, self.v2 - self.v0, p)
    }

    /// The point interpolated from the vertices with the barycentrics `u`, `v` (not
    /// `ray.at(t)`, whose error grows with the distance travelled), the unit normal of the
    /// winding, and an error bound relative to the largest vertex coordinate.
    #[inline]
    fn surface(&self, _ray: &Ray, _t: f32, u: f32, v: f32) -> SurfacePoint {
        self.surface_at(u, v)
    }
}

impl Primitive for MtTriangle {
    /// The box around both the vertices and their [`edge_form`](MtTriangle::edge_form), so
    /// that a box overlap found on the edge form lies in every box built around the triangle.
    #[inline]
    fn bounds(&self) -> Aabb {
        self.0.bounds().union(Aabb::from_points(&self.edge_form()))
    }
    #[inline]
    fn centroid(&self) -> Vec3 {
        self.0.centroid()
    }
    fn is_valid(&self) -> bool {
        self.0.is_valid()
    }
    #[inline]
    fn clip_bounds(&self, cell: &Aabb) -> Option<Aabb> {
        crate::clip_triangle_bounds(self.edge_form(), cell)
    }
    #[inline]
    fn split_bounds(&self, cell: &Aabb, axis: usize, pos: f32) -> (Option<Aabb>, Option<Aabb>) {
        crate::split_triangle_bounds(self.edge_form(), cell, axis, pos)
    }
    /// Clips the [`edge_form`](MtTriangle::edge_form), as rt-bvh's packs do.
    #[inline]
    fn overlaps_box(&self, b: &Aabb) -> bool {
        crate::clip_triangle_bounds(self.edge_form(), b).is_some()
    }
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        self.0.intersect_moller_trumbore(ray, t_max)
    }
    #[inline]
    fn as_triangle(&self) -> Option<(Triangle, TriangleTest)> {
        Some((self.0, TriangleTest::MollerTrumbore))
    }
    #[inline]
    fn closest_point(&self, p: Vec3) -> Vec3 {
        self.0.closest_point(p)
    }
    #[inline]
    fn closest_feature(&self, p: Vec3) -> (Vec3, crate::Feature) {
        self.0.closest_feature(p)
    }
    #[inline]
    fn surface(&self, _ray: &Ray, _t: f32, u: f32, v: f32) -> SurfacePoint {
        self.0.surface_at(u, v)
    }
}

/// The union of the bounds of the valid primitives (see [`Primitive::is_valid`]) among `prims`,
/// [`Aabb::EMPTY`](crate::Aabb::EMPTY) if none: the box a camera frames or a query is measured
/// in.
///
/// ```
/// use rt_core::{Aabb, Triangle, glam::Vec3, valid_bounds};
/// let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y), Triangle::new(Vec3::NAN, Vec3::X, Vec3::Y)];
/// assert_eq!(valid_bounds(&tris), Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
/// ```
pub fn valid_bounds<'a, P: Primitive + 'a>(prims: impl IntoIterator<Item = &'a P>) -> crate::Aabb {
    prims
        .into_iter()
        .filter(|p| p.is_valid())
        .fold(crate::Aabb::EMPTY, |b, p| b.union(p.bounds()))
}

/// The indices of the valid primitives (see [`Primitive::is_valid`]) among the first 2³² - 1 of
/// `prims`, in increasing order, and the union of their bounds ([`Aabb::EMPTY`] if none): what
/// every builder starts from.
pub fn valid_primitives<P: Primitive>(prims: &[P]) -> (Vec<u32>, crate::Aabb) {
    let ids: Vec<u32> = (0..prims.len().min(u32::MAX as usize))
        .filter(|&i| prims[i].is_valid())
        .map(|i| i as u32)
        .collect();
    let bounds = ids.iter().fold(crate::Aabb::EMPTY, |b, &i| {
        b.union(prims[i as usize].bounds())
    });
    (ids, bounds)
}

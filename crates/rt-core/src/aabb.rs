//! Axis-aligned bounding boxes and the slab test.

use crate::Ray;
use glam::Vec3;

/// Relative widening of the far end of a slab interval (`2⁻¹⁶`), so that rounding never makes a
/// structure cull a box while a primitive inside it reports a hit within the ray's interval.
///
/// The slab distances themselves are off by at most `2γ₃ ≈ 3.6e-7` relative (pbrt-v3 §3.9.2), and
/// a triangle's computed `t` is off by a few units in the last place for well-conditioned hits;
/// a hit lying exactly on a box face (a shared vertex, an axis-aligned triangle, a tie between
/// identical triangles) needs both covered, or the box of the tie-winning primitive is culled.
/// The margin costs a negligible number of extra box visits.
pub const SLAB_FAR_SCALE: f32 = 1.0 + 1.0 / 65536.0;

/// Two plane crossings whose ray parameters lie within this factor of each other (`1 + 2⁻²⁰`,
/// sixteen units in the last place) count as simultaneous: spatial subdivisions (grids, octrees)
/// then also visit the cells beside their computed path, since rounding may have put the true
/// path through them. It is several times the error of a crossing's computed `t` (about 1.5 ulp:
/// one subtraction and one multiplication by the reciprocal direction), and well below
/// [`SLAB_FAR_SCALE`], so a walk that stops at a cell starting beyond `best.t · SLAB_FAR_SCALE`
/// never stops before such a side cell. (A test of tiny triangles hugging cell edges, hit from
/// 10⁴ away, fails without the side cells.)
pub const NEAR_TIE: f32 = 1.0 + 1.0 / 1_048_576.0;

crate::pod_struct! {
    /// An axis-aligned box `[min, max]`. The empty box has `min = +inf`, `max = -inf`.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Aabb {
        /// The lower corner.
        pub min: Vec3,
        /// The upper corner.
        pub max: Vec3,
    }
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: growing it by anything gives that thing's box.
    pub const EMPTY: Self = Self {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// The box with corners `min` and `max`.
    #[inline]
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding every point.
    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    /// The box grown to hold `p`.
    #[inline]
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box holding both boxes.
    #[inline]
    pub fn union(self, o: Self) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// The box grown by `pad` on every side (what pads against rounding use).
    #[inline(always)]
    pub fn padded(self, pad: f32) -> Self {
        Self {
            min: self.min - Vec3::splat(pad),
            max: self.max + Vec3::splat(pad),
        }
    }

    /// Whether the box holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// `max - min`, or zero for the empty box.
    #[inline]
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// The centre point.
    #[inline]
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Half the surface area (`xy + yz + zx`), the quantity the surface area heuristic compares;
    /// zero for the empty box.
    #[inline]
    pub fn half_area(&self) -> f32 {
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// The full surface area.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        2.0 * self.half_area()
    }

    /// The index (0, 1, 2) of the longest axis.
    #[inline]
    pub fn largest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// Whether `o` lies inside this box (boundaries included).
    #[inline]
    pub fn contains(&self, o: &Self) -> bool {
        o.is_empty() || (self.min.cmple(o.min).all() && o.max.cmple(self.max).all())
    }

    /// True if the closed boxes share at least one point (touching counts).
    #[inline]
    pub fn overlaps(&self, o: &Self) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// The common part of two boxes; empty (see [`Aabb::is_empty`]) if they do not overlap.
    #[inline]
    pub fn intersection(&self, o: &Self) -> Self {
        Self {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    /// Whether the point lies inside this box (boundaries included).
    #[inline]
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// The squared distance from `p` to the nearest point of the box: 0 inside it, `+inf` for the
    /// empty box. Closest-point traversals prune a box whose distance exceeds the best found.
    ///
    /// Rounding is monotone, so a box inside another never gets a smaller computed distance.
    ///
    /// ```
    /// use rt_core::{Aabb, glam::Vec3};
    /// let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
    /// assert_eq!(b.distance_squared(Vec3::new(0.5, 0.5, 0.5)), 0.0);
    /// assert_eq!(b.distance_squared(Vec3::new(3.0, 1.0, -2.0)), 8.0);
    /// ```
    #[inline(always)]
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3::ZERO);
        d.dot(d)
    }

    /// The slab test: the parameter interval `[t_near, t_far]` in which the ray is inside the box,
    /// clipped to `[ray.t_min, t_max]`, or `None` if that interval is empty.
    ///
    /// The box is the intersection of three slabs, so the interval is the intersection of the
    /// three slab intervals. Correct in the cases where a naive `min`/`max` formulation is not:
    ///
    /// - A zero direction component (`+0.0` or `-0.0`) gives an infinite reciprocal. The near
    ///   plane is chosen by the reciprocal's sign, so `(min - o) * inf` is `-inf` (inside the slab),
    ///   `+inf` (outside) or, when the origin lies exactly in the plane, `0 * inf = NaN`.
    /// - Such a NaN never decides the answer: the interval is narrowed only by comparisons that are
    ///   false for NaN, so a ray lying exactly in a face plane of the box (and flat, zero-thickness
    ///   boxes) count as inside that slab, consistent with the closed box.
    /// - The far end of the interval (`min(far, t_max)`) is widened by [`SLAB_FAR_SCALE`] so
    ///   rounding never rejects a box that a primitive hit on its boundary lies in; the returned
    ///   far value is the widened one.
    ///
    /// `t_max` is passed separately so that traversal can shrink it to the closest hit so far.
    ///
    /// ```
    /// use rt_core::{Aabb, Ray, glam::Vec3};
    /// let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
    /// // A ray lying in the face plane x = 0, travelling along +y with dir.x = -0.0.
    /// let r = Ray::new(Vec3::new(0.0, -1.0, 0.5), Vec3::new(-0.0, 1.0, 0.0));
    /// let (near, far) = b.intersect(&r, r.t_max).unwrap();
    /// assert_eq!(near, 1.0);
    /// assert!(far >= 2.0);
    /// ```
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
        let (near, far) = self.slab_distances(ray);
        let mut t0 = ray.t_min;
        let mut t1 = t_max;
        for a in 0..3 {
            // Written as `if` so that a NaN distance (origin in the plane, zero direction) is
            // ignored instead of overwriting the interval.
            if near[a] > t0 {
                t0 = near[a];
            }
            if far[a] < t1 {
                t1 = far[a];
            }
        }
        let t1 = t1 * SLAB_FAR_SCALE;
        if t0 <= t1 { Some((t0, t1)) } else { None }
    }

    /// The entry distance if the ray meets the box within `[ray.t_min, t_max]`, else `+inf`.
    ///
    /// The same test as [`Aabb::intersect`], shaped for traversal loops that sort children by
    /// entry distance.
    #[inline(always)]
    pub fn entry(&self, ray: &Ray, t_max: f32) -> f32 {
        match self.intersect(ray, t_max) {
            Some((t0, _)) => t0,
            None => f32::INFINITY,
        }
    }

    /// Distances to the near and far planes of each slab, chosen by the sign of the reciprocal
    /// direction (so `-0.0` is handled like any negative direction).
    #[inline(always)]
    fn slab_distances(&self, ray: &Ray) -> ([f32; 3], [f32; 3]) {
        let mut near = [0.0; 3];
        let mut far = [0.0; 3];
        for a in 0..3 {
            let inv = ray.inv_dir()[a];
            let (lo, hi) = if inv.is_sign_negative() {
                (self.max[a], self.min[a])
            } else {
                (self.min[a], self.max[a])
            };
            near[a] = (lo - ray.origin[a]) * inv;
            far[a] = (hi - ray.origin[a]) * inv;
        }
        (near, far)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn basic_hit_and_miss() {
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(unit().intersect(&r, f32::INFINITY).map(|h| h.0), Some(1.0));
        let r = Ray::new(Vec3::new(2.0, 0.5, -1.0), Vec3::Z);
        assert!(unit().intersect(&r, f32::INFINITY).is_none());
        // Behind the origin.
        let r = Ray::new(Vec3::new(0.5, 0.5, 2.0), Vec3::Z);
        assert!(unit().intersect(&r, f32::INFINITY).is_none());
    }

    #[test]
    fn signed_zero_directions_in_every_face_plane() {
        // For every face plane, a ray lying in that plane and travelling along another axis, with
        // the plane axis' direction component +0.0 and -0.0: always a hit.
        for axis in 0..3 {
            for &plane in &[0.0f32, 1.0] {
                for &zero in &[0.0f32, -0.0] {
                    let along = (axis + 1) % 3;
                    let mut o = Vec3::splat(0.5);
                    o[axis] = plane;
                    o[along] = -3.0;
                    let mut d = Vec3::ZERO;
                    d[axis] = zero;
                    d[along] = 1.0;
                    let third = 3 - axis - along;
                    d[third] = if zero.is_sign_negative() { -0.0 } else { 0.0 };
                    let r = Ray::new(o, d);
                    let hit = unit().intersect(&r, f32::INFINITY);
                    assert_eq!(
                        hit.map(|h| h.0),
                        Some(3.0),
                        "axis {axis} plane {plane} zero {zero:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn parallel_ray_outside_slab_misses() {
        for &zero in &[0.0f32, -0.0] {
            let r = Ray::new(Vec3::new(1.0 + 1e-6, -1.0, 0.5), Vec3::new(zero, 1.0, zero));
            assert!(unit().intersect(&r, f32::INFINITY).is_none());
            let r = Ray::new(Vec3::new(-1e-6, -1.0, 0.5), Vec3::new(zero, 1.0, zero));
            assert!(unit().intersect(&r, f32::INFINITY).is_none());
        }
    }

    #[test]
    fn flat_box_is_hit_by_ray_in_its_plane_and_through_it() {
        let flat = Aabb::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0));
        let through = Ray::new(Vec3::new(0.5, 0.5, 0.0), Vec3::Z);
        assert_eq!(
            flat.intersect(&through, f32::INFINITY).map(|h| h.0),
            Some(1.0)
        );
        let within = Ray::new(Vec3::new(-1.0, 0.5, 1.0), Vec3::new(1.0, 0.0, -0.0));
        assert!(flat.intersect(&within, f32::INFINITY).is_some());
        let degenerate_point = Aabb::new(Vec3::ONE, Vec3::ONE);
        let at_point = Ray::new(Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, -0.0, 1.0));
        assert!(
            degenerate_point
                .intersect(&at_point, f32::INFINITY)
                .is_some()
        );
    }

    #[test]
    fn origin_inside_and_t_max_clipping() {
        let r = Ray::new(Vec3::splat(0.5), Vec3::X);
        let (t0, t1) = unit().intersect(&r, f32::INFINITY).unwrap();
        assert_eq!(t0, 0.0);
        assert!(
            t1 >= 0.5 && t1 - 0.5 < 1e-4,
            "far end is widened, never narrowed"
        );
        let r = Ray::new(Vec3::new(-2.0, 0.5, 0.5), Vec3::X);
        assert!(unit().intersect(&r, 1.5).is_none());
        assert!(unit().intersect(&r, 2.0).is_some());
    }

    #[test]
    fn empty_box_is_never_hit() {
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert!(Aabb::EMPTY.intersect(&r, f32::INFINITY).is_none());
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.half_area(), 0.0);
    }
}

//! Spheres as an implicit surface.

use crate::{Aabb, PrimHit, Primitive, Ray, SurfacePoint};
use glam::Vec3;

crate::pod_struct! {
    /// A sphere `|p - center| = radius`.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Sphere {
        /// The centre.
        pub center: Vec3,
        /// The radius; must be positive and finite for the sphere to be valid.
        pub radius: f32,
    }
}

impl Sphere {
    /// The sphere with this centre and radius.
    #[inline]
    pub const fn new(center: Vec3, radius: f32) -> Self {
        Self { center, radius }
    }

    /// Both roots of `|o + t·d - c|² = r²`, ascending, or `None` if the line misses.
    ///
    /// Numerically stable in the two places the textbook formula is not (Haines et al., *Ray
    /// Tracing Gems*, ch. 7):
    /// - the discriminant is `r² - |f - (f·d / d·d)·d|²`, the squared distance from the centre to
    ///   the line, instead of `b² - 4ac`, which cancels catastrophically when the origin is far
    ///   away compared with the radius;
    /// - the two roots come from `q = -(b + sign(b)·√disc)` as `c / q` and `q / a`, which never
    ///   subtracts two nearly equal numbers.
    #[inline]
    pub fn roots(&self, ray: &Ray) -> Option<(f32, f32)> {
        let f = ray.origin - self.center;
        let a = ray.dir().length_squared();
        let b = f.dot(ray.dir()); // half of the textbook b
        let l = f - (b / a) * ray.dir();
        let r2 = self.radius * self.radius;
        let disc = r2 - l.length_squared();
        if disc < 0.0 || disc.is_nan() {
            return None;
        }
        let c = f.length_squared() - r2;
        let q = -(b + (a * disc).sqrt().copysign(b));
        let (t0, t1) = if q == 0.0 {
            // Only when b = 0 and disc = 0: a tangent ray whose closest point is the origin.
            (0.0, 0.0)
        } else {
            (c / q, q / a)
        };
        Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
    }
}

impl Primitive for Sphere {
    #[inline]
    fn bounds(&self) -> Aabb {
        let r = Vec3::splat(self.radius);
        Aabb::new(self.center - r, self.center + r)
    }

    #[inline]
    fn centroid(&self) -> Vec3 {
        self.center
    }

    fn is_valid(&self) -> bool {
        self.center.is_finite() && self.radius.is_finite() && self.radius > 0.0
    }

    /// Whether the box meets the ball: the box's nearest point lies within the radius (computed
    /// in `f64`, where the squares of `f32` coordinates neither overflow nor round), and the box
    /// meets the sphere's bounding box, which keeps the answer within the cells structures store
    /// the sphere under.
    #[inline]
    fn overlaps_box(&self, b: &Aabb) -> bool {
        let c = self.center.as_dvec3();
        let gap = (b.min.as_dvec3() - c)
            .max(c - b.max.as_dvec3())
            .max(glam::DVec3::ZERO);
        let r = f64::from(self.radius);
        !b.is_empty() && self.bounds().overlaps(b) && gap.length_squared() <= r * r
    }

    /// The point `center + radius·(p - center)/|p - center|`, computed in `f64`; from the centre
    /// itself, the sphere's top (`+y`).
    fn closest_point(&self, p: Vec3) -> Vec3 {
        let c = self.center.as_dvec3();
        let dir = (p.as_dvec3() - c).try_normalize().unwrap_or(glam::DVec3::Y);
        (c + f64::from(self.radius) * dir).as_vec3()
    }

    /// The nearer root inside the interval; from inside the sphere that is the far root.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let (t0, t1) = self.roots(ray)?;
        let t = if t0 >= ray.t_min && t0 <= t_max {
            t0
        } else if t1 >= ray.t_min && t1 <= t_max {
            t1
        } else {
            return None;
        };
        let n = (ray.at(t) - self.center) / self.radius;
        let u = 0.5 + n.z.atan2(n.x) * (0.5 / std::f32::consts::PI);
        let v = n.y.clamp(-1.0, 1.0).acos() * std::f32::consts::FRAC_1_PI;
        Some(PrimHit { t, u, v })
    }

    #[inline]
    fn occludes(&self, ray: &Ray, t_max: f32) -> bool {
        match self.roots(ray) {
            Some((t0, t1)) => (t0 >= ray.t_min && t0 <= t_max) || (t1 >= ray.t_min && t1 <= t_max),
            None => false,
        }
    }

    /// The point `ray.at(t)` projected back onto the sphere, the outward normal, and an error
    /// bound relative to the centre's largest coordinate plus the radius.
    #[inline]
    fn surface(&self, ray: &Ray, t: f32, _u: f32, _v: f32) -> SurfacePoint {
        let normal = (ray.at(t) - self.center).normalize_or(Vec3::Y);
        SurfacePoint {
            point: self.center + self.radius * normal,
            normal,
            error: crate::surface::error_bound(self.center.abs().max_element() + self.radius),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hit_from_outside_takes_near_root() {
        let s = Sphere::new(Vec3::ZERO, 1.0);
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert_eq!(s.intersect(&r, f32::INFINITY).unwrap().t, 4.0);
    }

    #[test]
    fn origin_inside_takes_far_root() {
        let s = Sphere::new(Vec3::ZERO, 2.0);
        let r = Ray::new(Vec3::new(0.5, 0.0, 0.0), Vec3::X);
        let h = s.intersect(&r, f32::INFINITY).unwrap();
        assert!((h.t - 1.5).abs() < 1e-6);
    }

    #[test]
    fn far_origin_is_stable() {
        // A unit sphere seen from 1e5 units away: the naive discriminant b² - ac loses every
        // significant digit here (b² ≈ 1e10, so its rounding error exceeds r² = 1).
        let s = Sphere::new(Vec3::new(0.0, 0.0, 1.0e5), 1.0);
        let r = Ray::new(Vec3::new(0.5, 0.0, 0.0), Vec3::Z);
        let h = s.intersect(&r, f32::INFINITY).expect("must hit");
        let exact = 1.0e5 - (0.75f64).sqrt();
        assert!(((h.t as f64) - exact).abs() / exact < 1e-6, "t = {}", h.t);
        let miss = Ray::new(Vec3::new(1.01, 0.0, 0.0), Vec3::Z);
        assert!(s.intersect(&miss, f32::INFINITY).is_none());
    }

    #[test]
    fn behind_and_outside_interval_misses() {
        let s = Sphere::new(Vec3::ZERO, 1.0);
        let r = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
        assert!(s.intersect(&r, f32::INFINITY).is_none());
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert!(s.intersect(&r, 3.9).is_none());
        assert!(!s.occludes(&r, 3.9));
        assert!(s.occludes(&r, 4.0));
    }

    #[test]
    fn invalid_spheres() {
        assert!(!Sphere::new(Vec3::ZERO, 0.0).is_valid());
        assert!(!Sphere::new(Vec3::ZERO, -1.0).is_valid());
        assert!(!Sphere::new(Vec3::splat(f32::NAN), 1.0).is_valid());
        assert!(!Sphere::new(Vec3::ZERO, f32::INFINITY).is_valid());
    }
}

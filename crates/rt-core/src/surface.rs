//! Points on surfaces, and spawning secondary rays from them without hitting the surface again.
//!
//! A hit point is only known to within rounding error, so a shadow or reflection ray started
//! exactly there meets its own surface again at a tiny `t` about half the time ("shadow acne").
//! The usual cure, an epsilon added to `t_min` or to the origin, is tuned per scene and fails at
//! other scales. [`offset_origin`] instead moves the origin off the surface by a bound on the
//! error, which the primitive computes from its own coordinates (the approach of Pharr, Jakob &
//! Humphreys, *Physically Based Rendering*, 3rd ed., §3.9, in the spirit of Wächter & Binder,
//! "A Fast and Robust Method for Avoiding Self-Intersection", *Ray Tracing Gems* ch. 6): the
//! bound scales with the geometry, so the same scene scaled by 10⁻³ or 10³ behaves the same.

use crate::Ray;
use glam::Vec3;

/// How many units of `f32::EPSILON`, relative to the magnitude of the coordinates involved, a
/// surface point is moved off its surface.
///
/// The hit point of a triangle interpolated from its vertices is within a few units of rounding
/// of the largest vertex coordinate, and a ray test started near a surface decides the side of the
/// plane within about ten such units of the coordinates relative to the ray origin, which are at
/// most twice as large. 64 covers both with room to spare, and is still a tiny distance: a
/// millimetre on a floor 240 metres wide. The tests in `surface.rs` and rt-render's acne tests
/// (every lit pixel of the bunny and the built-in scenes, at scales 10⁻³, 1 and 10³) would fail
/// if it were too small.
pub const OFFSET_ULPS: f32 = 64.0;

/// A point on a primitive, as a renderer needs it to continue a path: where, which way the
/// surface faces, and how far off the computed point may be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The point on the surface (for triangles interpolated from the vertices, not
    /// `ray.at(t)`, which carries the error of `t`).
    pub point: Vec3,
    /// The unit geometric normal, oriented as the primitive defines it (for triangles by the
    /// winding `(v1 - v0) × (v2 - v0)`, for spheres outwards), not towards the ray.
    pub normal: Vec3,
    /// A bound on the absolute error of every coordinate of `point` and of ray tests started
    /// there; see [`offset_origin`].
    pub error: f32,
}

impl SurfacePoint {
    /// The origin for a ray leaving the surface in direction `dir`: [`offset_origin`] to the side
    /// `dir` points to.
    #[inline]
    pub fn offset_origin(&self, dir: Vec3) -> Vec3 {
        offset_origin(self.point, self.normal, self.error, dir)
    }

    /// A ray leaving the surface in direction `dir` (reflection, refraction), over `[0, inf]`,
    /// that cannot hit this surface at its own origin.
    #[inline]
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        Ray::new(self.offset_origin(dir), dir)
    }

    /// A ray from the surface to `target` (a point light), over `t` in `[0, 1]` of the way there:
    /// [`Accel::occluded`](crate::Accel::occluded) on it says whether `target` is hidden.
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> Ray {
        let origin = self.offset_origin(target - self.point);
        Ray::with_interval(origin, target - origin, 0.0, 1.0)
    }
}

/// Moves `p`, a point on a surface with unit normal `n` known to within `error` in every
/// coordinate, off the surface to the side that `dir` points to, so that a ray from the result
/// in direction `dir` cannot hit that surface at its start.
///
/// The point moves along the normal by `error · (|n.x| + |n.y| + |n.z|)`, the largest distance
/// an error box of half-width `error` reaches along `n`, and each coordinate is then rounded one
/// more step away from the surface, so the rounding of the addition cannot undo the move. A
/// non-finite input comes back non-finite, and the ray made from it is invalid
/// ([`Ray::is_valid`]), so no structure walks it.
///
/// ```
/// use rt_core::{Accel, BruteForce, Primitive, Ray, Triangle, glam::Vec3};
/// let floor = [Triangle::new(Vec3::new(-1e3, 0.0, -1e3), Vec3::new(0.0, 0.0, 1e3), Vec3::new(1e3, 0.0, -1e3))];
/// let accel = BruteForce::build(&floor, &Default::default());
/// let eye = Ray::new(Vec3::new(0.3, 5.0, 0.1), Vec3::new(0.2, -1.0, 0.1));
/// let hit = accel.intersect(&eye).unwrap();
/// let surface = floor[0].surface(&eye, hit.t, hit.u, hit.v);
/// // A shadow ray grazing along the floor towards a light does not see the floor itself.
/// let shadow = surface.spawn_ray_to(Vec3::new(500.0, 0.01, 3.0));
/// assert!(!accel.occluded(&shadow));
/// ```
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3, error: f32, dir: Vec3) -> Vec3 {
    let d = error * n.abs().dot(Vec3::ONE);
    let side = if n.dot(dir) < 0.0 { -n } else { n };
    let mut o = p + d * side;
    for axis in 0..3 {
        if side[axis] > 0.0 {
            o[axis] = o[axis].next_up();
        } else if side[axis] < 0.0 {
            o[axis] = o[axis].next_down();
        }
    }
    o
}

/// The error bound [`SurfacePoint::error`] for a point computed from coordinates of magnitude up
/// to `magnitude` (the largest absolute coordinate of the primitive's defining points):
/// [`OFFSET_ULPS`] relative units of it.
#[inline]
pub fn error_bound(magnitude: f32) -> f32 {
    OFFSET_ULPS * f32::EPSILON * magnitude
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Primitive, Sphere, Triangle};

    #[test]
    fn offset_moves_to_the_side_of_the_direction() {
        let n = Vec3::Y;
        let up = offset_origin(Vec3::ZERO, n, 1e-3, Vec3::new(1.0, 0.5, 0.0));
        assert!(up.y > 0.0 && up.x == 0.0 && up.z == 0.0);
        let down = offset_origin(Vec3::ZERO, n, 1e-3, Vec3::new(1.0, -0.5, 0.0));
        assert!(down.y < 0.0);
        // With no error at all the point still moves one step.
        let p = Vec3::new(1.0, 1.0, 1.0);
        assert_eq!(offset_origin(p, n, 0.0, Vec3::Y).y, 1.0f32.next_up());
    }

    /// Rays leaving a triangle towards points on its front side, from points spread over the
    /// triangle, at scales from 10⁻⁴ to 10⁴ and far from the origin: none hits the triangle
    /// again, and rays pushed through to the back side do (a surface the offset overshot would
    /// be missed, a light leak).
    #[test]
    fn no_self_hits_at_any_scale() {
        let mut rng = crate::Rng::new(5);
        for scale in [1e-4f32, 1e-3, 1.0, 1e3, 1e4] {
            for shift in [0.0f32, 3.0, 1e3] {
                for _ in 0..200 {
                    let base = rng.in_box(Vec3::splat(-1.0), Vec3::ONE) * shift;
                    let v =
                        [0; 3].map(|_| (base + rng.in_box(Vec3::splat(-1.0), Vec3::ONE)) * scale);
                    let tri = Triangle::new(v[0], v[1], v[2]);
                    if !tri.is_valid() {
                        continue;
                    }
                    let n = tri.normal().normalize();
                    for _ in 0..20 {
                        let (a, b) = (rng.range(0.0, 1.0), rng.range(0.0, 1.0));
                        let (u, v) = if a + b > 1.0 {
                            (1.0 - a, 1.0 - b)
                        } else {
                            (a, b)
                        };
                        let eye_dir = rng.unit_vector();
                        let eye = Ray::new(tri.v0 - eye_dir, eye_dir);
                        let s = tri.surface(&eye, 1.0, u, v);
                        // Any direction not parallel to the plane, on both sides.
                        let dir = rng.unit_vector();
                        if dir.dot(n).abs() < 1e-3 {
                            continue;
                        }
                        let ray = s.spawn_ray(dir);
                        assert!(
                            tri.intersect(&ray, f32::INFINITY).is_none(),
                            "self-hit at scale {scale}, shift {shift}: {tri:?} {}",
                            ray.to_rust()
                        );
                        // Pointed straight back at the surface, the same origin sees it: the
                        // offset did not overshoot into a gap.
                        let back = Ray::new(ray.origin, if dir.dot(n) > 0.0 { -n } else { n });
                        if u > 1e-3 && v > 1e-3 && u + v < 1.0 - 1e-3 {
                            assert!(tri.intersect(&back, f32::INFINITY).is_some());
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn sphere_rays_leave_cleanly_both_ways() {
        let mut rng = crate::Rng::new(9);
        for scale in [1e-3f32, 1.0, 1e3] {
            let sphere = Sphere::new(Vec3::new(3.0, -2.0, 7.0) * scale, 0.8 * scale);
            for _ in 0..2000 {
                let eye = Ray::new(
                    sphere.center + rng.unit_vector() * 5.0 * scale,
                    rng.unit_vector(),
                );
                let to_center = (sphere.center - eye.origin).normalize();
                let ray = Ray::new(
                    eye.origin,
                    (to_center + 0.1 * rng.unit_vector()).normalize(),
                );
                let Some(h) = sphere.intersect(&ray, f32::INFINITY) else {
                    continue;
                };
                let s = sphere.surface(&ray, h.t, h.u, h.v);
                // Leaving outwards: no hit at all (a sphere is convex).
                let out = s.spawn_ray((s.normal + 0.5 * rng.unit_vector()).normalize());
                if out.dir().dot(s.normal) > 0.0 {
                    assert!(
                        sphere.intersect(&out, f32::INFINITY).is_none(),
                        "{}",
                        out.to_rust()
                    );
                }
                // Entering (refraction): the next hit is the far side, not the entry point.
                let dir = (-s.normal + 0.5 * rng.unit_vector()).normalize();
                if dir.dot(s.normal) < -0.05 {
                    let inside = s.spawn_ray(dir);
                    let far = sphere.intersect(&inside, f32::INFINITY).expect("far side");
                    assert!(far.t > 0.01 * sphere.radius, "t = {}", far.t);
                }
            }
        }
    }
}

//! One primitive type for scenes that mix triangles and spheres.

use crate::{Aabb, PrimHit, Primitive, Ray, Sphere, SurfacePoint, Triangle, TriangleTest};
use glam::Vec3;

/// A triangle or a sphere: the primitive of scenes that hold both, so that one structure of any
/// kind can store them all (`Bvh<Shape>`, `KdTree<Shape>`, ...).
///
/// Each variant answers exactly as the type it wraps. Structures that pack triangles for SIMD
/// (rt-bvh's wide layout) do so only when every primitive is a triangle; a scene with spheres
/// runs each primitive's own test.
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Shape, Sphere, Triangle, glam::Vec3};
/// let scene = [
///     Shape::Sphere(Sphere::new(Vec3::new(0.0, 1.0, 0.0), 1.0)),
///     Shape::Triangle(Triangle::new(Vec3::new(-5.0, 0.0, 5.0), Vec3::new(5.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -5.0))),
/// ];
/// let accel = BruteForce::build(&scene, &Default::default());
/// let down = Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y);
/// assert_eq!(accel.intersect(&down).unwrap().prim, 0);
/// let beside = Ray::new(Vec3::new(2.0, 5.0, 0.0), -Vec3::Y);
/// assert_eq!(accel.intersect(&beside).unwrap().prim, 1);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A triangle, with the watertight test.
    Triangle(Triangle),
    /// A sphere.
    Sphere(Sphere),
}

impl From<Triangle> for Shape {
    fn from(t: Triangle) -> Self {
        Shape::Triangle(t)
    }
}

impl From<Sphere> for Shape {
    fn from(s: Sphere) -> Self {
        Shape::Sphere(s)
    }
}

impl Primitive for Shape {
    #[inline]
    fn bounds(&self) -> Aabb {
        match self {
            Shape::Triangle(t) => t.bounds(),
            Shape::Sphere(s) => s.bounds(),
        }
    }

    #[inline]
    fn centroid(&self) -> Vec3 {
        match self {
            Shape::Triangle(t) => t.centroid(),
            Shape::Sphere(s) => s.centroid(),
        }
    }

    fn is_valid(&self) -> bool {
        match self {
            Shape::Triangle(t) => t.is_valid(),
            Shape::Sphere(s) => s.is_valid(),
        }
    }

    #[inline]
    fn clip_bounds(&self, cell: &Aabb) -> Option<Aabb> {
        match self {
            Shape::Triangle(t) => t.clip_bounds(cell),
            Shape::Sphere(s) => s.clip_bounds(cell),
        }
    }

    #[inline]
    fn overlaps_box(&self, b: &Aabb) -> bool {
        match self {
            Shape::Triangle(t) => t.overlaps_box(b),
            Shape::Sphere(s) => s.overlaps_box(b),
        }
    }

    #[inline]
    fn split_bounds(&self, cell: &Aabb, axis: usize, pos: f32) -> (Option<Aabb>, Option<Aabb>) {
        match self {
            Shape::Triangle(t) => t.split_bounds(cell, axis, pos),
            Shape::Sphere(s) => s.split_bounds(cell, axis, pos),
        }
    }

    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        match self {
            Shape::Triangle(t) => t.intersect(ray, t_max),
            Shape::Sphere(s) => s.intersect(ray, t_max),
        }
    }

    #[inline]
    fn closest_point(&self, p: Vec3) -> Vec3 {
        match self {
            Shape::Triangle(t) => t.closest_point(p),
            Shape::Sphere(s) => s.closest_point(p),
        }
    }

    #[inline]
    fn closest_feature(&self, p: Vec3) -> (Vec3, crate::Feature) {
        match self {
            Shape::Triangle(t) => t.closest_feature(p),
            Shape::Sphere(s) => s.closest_feature(p),
        }
    }

    #[inline]
    fn as_triangle(&self) -> Option<(Triangle, TriangleTest)> {
        match self {
            Shape::Triangle(t) => t.as_triangle(),
            Shape::Sphere(_) => None,
        }
    }

    #[inline]
    fn occludes(&self, ray: &Ray, t_max: f32) -> bool {
        match self {
            Shape::Triangle(t) => t.occludes(ray, t_max),
            Shape::Sphere(s) => s.occludes(ray, t_max),
        }
    }

    #[inline]
    fn surface(&self, ray: &Ray, t: f32, u: f32, v: f32) -> SurfacePoint {
        match self {
            Shape::Triangle(tri) => tri.surface(ray, t, u, v),
            Shape::Sphere(s) => s.surface(ray, t, u, v),
        }
    }
}

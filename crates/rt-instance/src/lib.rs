//! Two-level scenes: built structures placed many times with affine transforms, without copying
//! their geometry.
//!
//! An [`Instance`] is a bottom-level structure (any [`Accel`](rt_core::Accel), behind the object-safe
//! [`DynAccel`] trait, so a kd-tree and a grid can sit side by side), an
//! [`InstanceTransform`] from its object space to the world, and the caller's id. A two-level
//! scene ([`TwoLevel`]) answers rays and closest-point queries over all its instances:
//! rt-bvh's `Instances` with a BVH over the instances' world boxes, [`LinearInstances`] by
//! visiting every instance (the reference, as [`BruteForce`](rt_core::BruteForce) is for
//! primitives).
//!
//! # What an instance answers
//! - **Rays** are carried into object space ([`InstanceTransform::ray_to_object`]: the inverse
//!   transform applied to the origin and the direction, the interval unchanged). An affine map
//!   keeps the ray parameter, so the bottom level's `t` is the world `t`, and its barycentric
//!   `u`, `v` hold in the world too. Ties between instances go to the smaller instance index,
//!   then the smaller primitive index ([`InstanceHit::beats`]), as in the flattened list of
//!   every instance's primitives in order.
//! - **Closest points** are measured in the world, where a non-uniform scale changes distances:
//!   each primitive the bottom level offers is carried into the world
//!   ([`TransformPrimitive`]) and its nearest point found there. The bottom level walks a ball in
//!   object space that holds the world ball's preimage (its radius times the transform's
//!   [`stretch`](InstanceTransform::stretch)).
//! - **Surface points** for the next ray are found in object space and carried to the world
//!   ([`Instance::surface`], [`InstanceTransform::surface_to_world`]), their error bound grown
//!   by the transform's rounding both ways, so a ray spawned from one clears its surface when
//!   the walk carries it back into the instance.
//!
//! # Exactness
//! Every two-level scene answers exactly like [`LinearInstances`] over the same instances: the
//! same instance, primitive, `t` and barycentrics, or the same point and distance. The top level
//! only decides which instances to visit, and it culls conservatively: each world box is padded
//! for the rounding of the corners' transform, and each ray's box tests for the rounding of its
//! transform into object space (see [`InstanceTransform::ray_pad`]).
//!
//! Against the flattened scene, the world-space triangles `to_world · v`, the answers differ
//! only by rounding: transforms round, so `t` differs by a few units in the last place (times
//! the transform's condition number), and a ray within that distance of an edge may be credited
//! to the triangle on the other side of it, or miss at a silhouette. The conformance kit checks
//! both (`rt_conformance::check_two_level_case`).

#![warn(missing_docs)]

use glam::{Affine3A, DMat3, DVec3, Mat3A, Vec3, Vec3A};
use rt_core::batch::{self, RaySource};
use rt_core::{
    Aabb, BallQuery, Counters, DynAccel, Feature, Hit, MtTriangle, NoStats, Primitive, Ray,
    Shading, Stats, SurfacePoint, Triangle, closest_feature_on_triangle, point_distance,
};
use std::fmt::Debug;
use std::sync::Arc;

/// Why an instance could not be made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InstanceError {
    /// A coefficient of the transform is NaN or infinite.
    NonFinite,
    /// The transform's linear part is singular, or its condition number (largest over smallest
    /// singular value) exceeds [`InstanceTransform::MAX_CONDITION`]: rays carried into the
    /// instance would lose most of their precision.
    IllConditioned {
        /// The condition number (infinite for a singular matrix).
        condition: f64,
    },
}

impl std::fmt::Display for InstanceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InstanceError::NonFinite => write!(f, "the instance transform is not finite"),
            InstanceError::IllConditioned { condition } => write!(
                f,
                "the instance transform is singular or ill-conditioned (condition number {condition:.3e}, at most {} allowed)",
                InstanceTransform::MAX_CONDITION
            ),
        }
    }
}

impl std::error::Error for InstanceError {}

/// An affine map from an instance's object space to the world, with its inverse and the figures
/// the two-level traversals prune with.
///
/// ```
/// use rt_core::{Ray, glam::{Affine3A, Vec3}};
/// use rt_instance::InstanceTransform;
/// let xf = InstanceTransform::new(Affine3A::from_scale_rotation_translation(
///     Vec3::new(2.0, 1.0, 1.0), Default::default(), Vec3::new(10.0, 0.0, 0.0))).unwrap();
/// let ray = xf.ray_to_object(&Ray::new(Vec3::new(14.0, 0.0, -5.0), Vec3::Z));
/// assert_eq!(ray.origin, Vec3::new(2.0, 0.0, -5.0));
/// // The smallest scale is 1: object lengths are at most world ones (the bound is rounded up).
/// assert!(xf.stretch() >= 1.0 && xf.stretch() < 1.0001);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceTransform {
    to_world: Affine3A,
    to_object: Affine3A,
    stretch: f32,
    condition: f32,
}

impl InstanceTransform {
    /// The rounding of carrying a point through a transform, in units of `f32::EPSILON`
    /// relative to the magnitudes summed (three products and three sums: at most about three
    /// units, with fused multiply-adds or without).
    pub const TRANSFORM_ULPS: f32 = 4.0;

    /// The largest condition number accepted: 2¹⁶. A ray carried into object space keeps about
    /// `24 - log2(condition)` bits of its direction, so 2¹⁶ leaves 8.
    pub const MAX_CONDITION: f64 = 65536.0;

    /// The transform `to_world` (object space to world), checked and inverted (in `f64`).
    ///
    /// # Errors
    /// [`InstanceError::NonFinite`] for a NaN or infinite coefficient;
    /// [`InstanceError::IllConditioned`] for a singular linear part or one whose condition
    /// number exceeds [`MAX_CONDITION`](Self::MAX_CONDITION). Mirrors (a negative determinant)
    /// and non-uniform scales are fine.
    pub fn new(to_world: Affine3A) -> Result<Self, InstanceError> {
        if !to_world.is_finite() {
            return Err(InstanceError::NonFinite);
        }
        let m = to_world.matrix3;
        let l = DMat3::from_cols(
            m.x_axis.as_dvec3(),
            m.y_axis.as_dvec3(),
            m.z_axis.as_dvec3(),
        );
        let det = l.determinant();
        let singular = InstanceError::IllConditioned {
            condition: f64::INFINITY,
        };
        if det == 0.0 || !det.is_finite() {
            return Err(singular);
        }
        let inv = l.inverse();
        // Largest singular values of L and of its inverse: their product is the condition number.
        let s_max = largest_eigenvalue(l.transpose() * l).sqrt();
        let s_inv = largest_eigenvalue(inv.transpose() * inv).sqrt();
        let condition = s_max * s_inv;
        if condition.is_nan() || condition > Self::MAX_CONDITION {
            return Err(InstanceError::IllConditioned { condition });
        }
        let t = to_world.translation.as_dvec3();
        let inv_t = -(inv * t);
        let to_object = Affine3A::from_mat3_translation(inv.as_mat3(), inv_t.as_vec3());
        Ok(Self {
            to_world,
            to_object,
            // Rounded up, and widened by far more than the eigenvalue's error.
            stretch: (s_inv * (1.0 + 1e-6)) as f32,
            condition: (condition * (1.0 + 1e-6)) as f32,
        })
    }

    /// The map from object space to the world.
    #[inline]
    pub fn to_world(&self) -> &Affine3A {
        &self.to_world
    }

    /// The map from the world to object space (the inverse, computed in `f64`).
    #[inline]
    pub fn to_object(&self) -> &Affine3A {
        &self.to_object
    }

    /// An upper bound on how much the inverse lengthens a vector: the largest singular value
    /// of the inverse's linear part (one over the smallest scale of the transform).
    #[inline]
    pub fn stretch(&self) -> f32 {
        self.stretch
    }

    /// The linear part's condition number, rounded up (1 for rotations and uniform scales).
    #[inline]
    pub fn condition(&self) -> f32 {
        self.condition
    }

    /// The ray in object space: origin and direction carried by the inverse, the interval
    /// unchanged (an affine map keeps the ray parameter, so `t` means the same point in both
    /// spaces).
    #[inline]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        self.ray_to_object_until(ray, ray.t_max)
    }

    /// [`ray_to_object`](Self::ray_to_object) with the interval cut at `t_max`.
    #[inline]
    pub fn ray_to_object_until(&self, ray: &Ray, t_max: f32) -> Ray {
        Ray::with_interval(
            self.to_object.transform_point3(ray.origin),
            self.to_object.transform_vector3(ray.dir()),
            ray.t_min,
            t_max,
        )
    }

    /// A surface point of a hit in this instance, found in object space (from the bottom
    /// level's primitive: [`Primitive::surface`] with the hit's `t`, `u`, `v`), carried to the
    /// world: the point by the transform, the normal by its inverse transpose (unit; the same
    /// side of the surface as in object space, so a mirror keeps a sphere's outward normal
    /// outward), and the error bound grown to cover the transform's rounding both ways. A ray
    /// spawned from the result ([`SurfacePoint::spawn_ray`], `spawn_ray_to`) and traced in the
    /// world is carried back into this instance by [`ray_to_object`](Self::ray_to_object), and
    /// the bound keeps its origin off the surface there too.
    ///
    /// The bound: a world offset `d` along the world normal moves the object-space origin at
    /// least `d / σ` along the object normal (`σ` the transform's largest singular value), and
    /// that must exceed what the object point's own bound asks for (the same offset in object
    /// space), the world point's rounding carried back (lengthened at most
    /// [`stretch`](Self::stretch) times), and the rounding of the ray's origin on its way back
    /// ([`TRANSFORM_ULPS`](Self::TRANSFORM_ULPS) of the magnitudes each transform involves):
    /// `√3 · σ · (object bound + stretch · forward rounding + backward rounding)`.
    ///
    /// ```
    /// use rt_core::{Primitive, Ray, Triangle, glam::{Affine3A, Vec3}};
    /// use rt_instance::InstanceTransform;
    /// let floor = Triangle::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, -1.0));
    /// // Stood up on its side, stretched and moved.
    /// let xf = InstanceTransform::new(
    ///     Affine3A::from_translation(Vec3::new(5.0, 0.0, 0.0))
    ///         * Affine3A::from_rotation_z(std::f32::consts::FRAC_PI_2)
    ///         * Affine3A::from_scale(Vec3::new(1.0, 1.0, 4.0)),
    /// )
    /// .unwrap();
    /// let world_ray = Ray::new(Vec3::new(9.0, 0.1, 0.2), -Vec3::X);
    /// let object_ray = xf.ray_to_object(&world_ray);
    /// let hit = floor.intersect(&object_ray, f32::INFINITY).unwrap();
    /// let surface = xf.surface_to_world(floor.surface(&object_ray, hit.t, hit.u, hit.v));
    /// assert!((surface.point - world_ray.at(hit.t)).length() < 1e-5);
    /// assert!(surface.normal.abs().abs_diff_eq(Vec3::X, 1e-6));
    /// // The bounce leaves the wall without seeing it again.
    /// let bounce = surface.spawn_ray(Vec3::new(1.0, 0.3, 0.0));
    /// assert!(floor.intersect(&xf.ray_to_object(&bounce), f32::INFINITY).is_none());
    /// ```
    pub fn surface_to_world(&self, s: SurfacePoint) -> SurfacePoint {
        let (a, b) = (self.to_world.matrix3, self.to_world.translation);
        let (inv, c) = (self.to_object.matrix3, self.to_object.translation);
        let point = self.to_world.transform_point3(s.point);
        let rounding = |m: f32| Self::TRANSFORM_ULPS * f32::EPSILON * m;
        let forward = rounding(norm_inf(a) * s.point.abs().max_element() + b.abs().max_element());
        let back = rounding(norm_inf(inv) * point.abs().max_element() + c.abs().max_element());
        // Both factors are rounded up by a millionth: their quotient may fall short of σ by
        // about that much, which the hundredth of a percent covers.
        let sigma = self.condition / self.stretch * 1.0001;
        SurfacePoint {
            point,
            normal: self.normal_to_world(s.normal).unwrap_or(s.normal),
            error: 3f32.sqrt() * sigma * (s.error + self.stretch * forward + back),
        }
    }

    /// A hit's [`Shading`] (of a [`rt_core::Mesh`] in object space) in the world: the surface
    /// by [`surface_to_world`](Self::surface_to_world), the shading normal by the inverse
    /// transpose, the texture coordinates as they are.
    pub fn shading_to_world(&self, s: Shading) -> Shading {
        let surface = self.surface_to_world(s.surface);
        Shading {
            surface,
            normal: self.normal_to_world(s.normal).unwrap_or(surface.normal),
            uv: s.uv,
        }
    }

    /// The object-space normal `n` in the world, unit length: the inverse transpose's image.
    fn normal_to_world(&self, n: Vec3) -> Option<Vec3> {
        (self.to_object.matrix3.transpose() * Vec3A::from(n))
            .try_normalize()
            .map(Vec3::from)
    }

    /// The box around the world image of the object-space box `b`, padded by 2⁻¹⁸ of the
    /// magnitudes involved so that it holds the image of every point of `b` however the
    /// transform rounds ([`Aabb::EMPTY`] for an empty `b`); and that magnitude, the instance's
    /// reach (the largest world coordinate its computations touch).
    pub fn world_bounds(&self, b: &Aabb) -> (Aabb, f32) {
        if b.is_empty() {
            return (Aabb::EMPTY, 0.0);
        }
        let mut out = Aabb::EMPTY;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            out = out.grow(self.to_world.transform_point3(corner));
        }
        let m = abs_matrix(&self.to_world.matrix3);
        let object = b.min.abs().max(b.max.abs());
        let reach =
            (m * Vec3A::from(object)).max_element() + self.to_world.translation.abs().max_element();
        (out.padded(reach / 262_144.0), reach)
    }

    /// How far a ray's box tests at the top level must reach beyond the instances' world boxes,
    /// for instances of condition at most `condition` and reach at most `reach`
    /// ([`world_bounds`](Self::world_bounds)): `2⁻¹⁶ · condition · (|origin|∞ + reach)`.
    ///
    /// Carrying a ray into object space rounds its origin by about `2⁻²⁴` of `|origin|` and its
    /// direction by as much of each step; mapped back to the world, that is at most a few times
    /// `2⁻²⁴ · condition · (|origin| + reach)` off the world ray. An object-space hit at `t` then
    /// lies within this pad of the world ray's point at `t`, so a top-level box test with the
    /// pad never culls an instance that holds a hit: the 2⁸ to spare covers every rounding
    /// step many times over.
    #[inline]
    pub fn ray_pad(ray: &Ray, condition: f32, reach: f32) -> f32 {
        Self::point_pad(ray.origin, condition, reach)
    }

    /// The same pad for computations about the point `p` (a ray's origin, a closest-point
    /// query's centre): `2⁻¹⁶ · condition · (|p|∞ + reach)`.
    #[inline]
    pub fn point_pad(p: Vec3, condition: f32, reach: f32) -> f32 {
        condition * (p.abs().max_element() + reach) / 65536.0
    }
}

/// `|M|` element by element.
fn abs_matrix(m: &Mat3A) -> Mat3A {
    Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
}

/// The largest eigenvalue of a symmetric 3×3 matrix (the trigonometric method of Smith 1961).
fn largest_eigenvalue(a: DMat3) -> f64 {
    let (a00, a11, a22) = (a.x_axis.x, a.y_axis.y, a.z_axis.z);
    let (a01, a02, a12) = (a.y_axis.x, a.z_axis.x, a.z_axis.y);
    let p1 = a01 * a01 + a02 * a02 + a12 * a12;
    let q = (a00 + a11 + a22) / 3.0;
    let p2 = (a00 - q).powi(2) + (a11 - q).powi(2) + (a22 - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if p == 0.0 {
        return q;
    }
    let b = (a - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    q + 2.0 * p * phi.cos()
}

/// The triangle `(v0, v0 + e1, v0 + e2)` of object space carried into the world as
/// `(to_world · v0, L · e1, L · e2)` (`L` the linear part), and its point nearest to `p` there.
///
/// This is the one definition of an instanced triangle's world shape for closest-point
/// queries: a bottom level's packed triangles (a vertex and two edges) and [`Triangle`]s (whose
/// edges are `v1 - v0` and `v2 - v0` rounded to `f32`) both reach it, bit for bit.
#[inline]
pub fn closest_point_on_transformed_triangle(
    to_world: &Affine3A,
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    p: Vec3,
) -> Vec3 {
    closest_feature_on_transformed_triangle(to_world, v0, e1, e2, p).0
}

/// [`closest_point_on_transformed_triangle`], with the [`Feature`] the point lies on (an affine
/// map keeps a triangle's faces, edges and vertices).
#[inline]
pub fn closest_feature_on_transformed_triangle(
    to_world: &Affine3A,
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    p: Vec3,
) -> (Vec3, Feature) {
    closest_feature_on_triangle(
        to_world.transform_point3(v0),
        to_world.transform_vector3(e1),
        to_world.transform_vector3(e2),
        p,
    )
}

/// A primitive whose nearest point can be found after an affine map to the world: what
/// closest-point queries through instances need ([`Instance`]).
///
/// Triangles qualify (an affine image of a triangle is a triangle); spheres do not, since a
/// non-uniform scale makes them ellipsoids.
pub trait TransformPrimitive: Primitive {
    /// The point nearest to the world point `p` on the primitive carried into the world by
    /// `to_world`. It must agree bit for bit with what [`BallQuery::test_triangle`] computes
    /// through [`closest_point_on_transformed_triangle`] for primitives whose
    /// [`Primitive::as_triangle`] is `Some`.
    fn closest_point_transformed(&self, to_world: &Affine3A, p: Vec3) -> Vec3;

    /// [`closest_point_transformed`](TransformPrimitive::closest_point_transformed), with the
    /// feature the point lies on; the default calls it the face.
    #[inline]
    fn closest_feature_transformed(&self, to_world: &Affine3A, p: Vec3) -> (Vec3, Feature) {
        (self.closest_point_transformed(to_world, p), Feature::Face)
    }
}

impl TransformPrimitive for Triangle {
    #[inline]
    fn closest_point_transformed(&self, to_world: &Affine3A, p: Vec3) -> Vec3 {
        self.closest_feature_transformed(to_world, p).0
    }
    #[inline]
    fn closest_feature_transformed(&self, to_world: &Affine3A, p: Vec3) -> (Vec3, Feature) {
        closest_feature_on_transformed_triangle(
            to_world,
            self.v0,
            self.v1 - self.v0,
            self.v2 - self.v0,
            p,
        )
    }
}

impl TransformPrimitive for MtTriangle {
    #[inline]
    fn closest_point_transformed(&self, to_world: &Affine3A, p: Vec3) -> Vec3 {
        self.0.closest_point_transformed(to_world, p)
    }
    #[inline]
    fn closest_feature_transformed(&self, to_world: &Affine3A, p: Vec3) -> (Vec3, Feature) {
        self.0.closest_feature_transformed(to_world, p)
    }
}

/// Runs `f` with counters when `S` records anything, and adds them to `stats`.
#[inline(always)]
fn counted<S: Stats, R>(stats: &mut S, f: impl FnOnce(Option<&mut Counters>) -> R) -> R {
    if S::COUNTS {
        let mut c = Counters::default();
        let r = f(Some(&mut c));
        stats.add(&c);
        r
    } else {
        f(None)
    }
}

/// One placement of a bottom-level structure: the structure (shared, never copied), its
/// transform to the world and the caller's id.
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::{Affine3A, Vec3}};
/// use rt_instance::Instance;
/// use std::sync::Arc;
/// let tri = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
/// let mesh = Arc::new(BruteForce::build(&tri, &()));
/// let moved = Instance::new(mesh, Affine3A::from_translation(Vec3::new(0.0, 0.0, 5.0)), 7).unwrap();
/// let ray = Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::Z);
/// let hit = moved.intersect(&ray, ray.t_max).unwrap();
/// assert_eq!(hit.prim, 0);
/// assert!((hit.t - 5.0).abs() < 1e-5); // t is the world's: the ray met the moved triangle at z = 5
/// ```
#[derive(Clone)]
pub struct Instance<P> {
    bottom: Arc<dyn DynAccel<P>>,
    transform: InstanceTransform,
    world_bounds: Aabb,
    reach: f32,
    id: u32,
}

// Two affine maps (64 bytes each, SIMD-aligned) with the stretch and condition number, the world
// box, the reach, the id and the shared structure's pointer: what each instance costs.
const _: () = assert!(size_of::<Instance<Triangle>>() == 192);

impl<P> Debug for Instance<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Instance")
            .field("bottom", &self.bottom.name())
            .field("transform", &self.transform)
            .field("world_bounds", &self.world_bounds)
            .field("id", &self.id)
            .finish()
    }
}

impl<P: Primitive> Instance<P> {
    /// `bottom` placed by `to_world` (object space to world), reported in hits as `id`.
    ///
    /// # Errors
    /// As [`InstanceTransform::new`]: a non-finite, singular or badly conditioned transform.
    pub fn new(
        bottom: Arc<dyn DynAccel<P>>,
        to_world: Affine3A,
        id: u32,
    ) -> Result<Self, InstanceError> {
        let transform = InstanceTransform::new(to_world)?;
        let (world_bounds, reach) = transform.world_bounds(&bottom.bounds_dyn());
        Ok(Self {
            bottom,
            transform,
            world_bounds,
            reach,
            id,
        })
    }

    /// The caller's id.
    #[inline]
    pub fn id(&self) -> u32 {
        self.id
    }

    /// The transform.
    #[inline]
    pub fn transform(&self) -> &InstanceTransform {
        &self.transform
    }

    /// The bottom-level structure.
    #[inline]
    pub fn bottom(&self) -> &Arc<dyn DynAccel<P>> {
        &self.bottom
    }

    /// The box around the instance in the world, padded for rounding; empty when the bottom
    /// level holds no valid primitive.
    #[inline]
    pub fn world_bounds(&self) -> Aabb {
        self.world_bounds
    }

    /// The largest world coordinate the instance's computations touch (see
    /// [`InstanceTransform::world_bounds`]).
    #[inline]
    pub fn reach(&self) -> f32 {
        self.reach
    }

    /// The world surface point of `hit`, a hit of the world ray `ray` on this instance's
    /// primitive `prim` (the one `hit.prim` names in the bottom level's input): `prim`'s
    /// surface in object space carried to the world
    /// ([`InstanceTransform::surface_to_world`]). Spawn the next ray from it as from a
    /// one-level hit's.
    pub fn surface(&self, prim: &P, ray: &Ray, hit: &InstanceHit) -> SurfacePoint {
        let object = self.transform.ray_to_object(ray);
        self.transform
            .surface_to_world(prim.surface(&object, hit.t, hit.u, hit.v))
    }

    /// The closest hit of the world ray in this instance up to `t_max`: the bottom level's hit
    /// (primitive index in its own input, `t` valid in the world, barycentrics).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_with(ray, t_max, &mut NoStats)
    }

    /// [`intersect`](Self::intersect), counting into `stats`.
    #[inline]
    pub fn intersect_with<S: Stats>(&self, ray: &Ray, t_max: f32, stats: &mut S) -> Option<Hit> {
        let object = self.transform.ray_to_object_until(ray, t_max);
        counted(stats, |c| self.bottom.intersect_dyn(&object, c))
    }

    /// Whether the world ray hits anything of this instance in its interval, counting into
    /// `stats`.
    #[inline]
    pub fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        let object = self.transform.ray_to_object(ray);
        counted(stats, |c| self.bottom.occluded_dyn(&object, c))
    }

    /// Offers this instance's primitives to the world query `query` as instance number
    /// `index`: the bottom level walks a ball in object space that holds the preimage of the
    /// query's world ball (padded for rounding), and each primitive it offers is measured in the
    /// world ([`TransformPrimitive`]).
    pub fn ball_query<S: Stats>(&self, index: u32, query: &mut InstancePointQuery, stats: &mut S)
    where
        P: TransformPrimitive,
    {
        if query.radius_sq() < 0.0 {
            return;
        }
        let center = query.center;
        let pad = InstanceTransform::point_pad(center, query.condition, self.reach);
        let mut ball = ObjectBall {
            query,
            to_world: self.transform.to_world,
            center: self.transform.to_object.transform_point3(center),
            stretch: self.transform.stretch,
            pad,
            index,
            radius_sq: 0.0,
            _prim: std::marker::PhantomData,
        };
        ball.update();
        counted(stats, |c| self.bottom.ball_query_dyn(&mut ball, c));
    }
}

/// The closest hit of a ray in a two-level scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceHit {
    /// The instance's index in the scene (its position in the list the scene was built from).
    pub instance: u32,
    /// The instance's id ([`Instance::id`]).
    pub id: u32,
    /// The primitive's index in its bottom level's build input.
    pub prim: u32,
    /// Ray parameter of the hit (the same in the world and in object space).
    pub t: f32,
    /// First surface coordinate (barycentric weight of `v1` for triangles).
    pub u: f32,
    /// Second surface coordinate.
    pub v: f32,
}

impl InstanceHit {
    /// The tie rule: a hit at `t` on `(instance, prim)` beats the best so far when it is
    /// strictly closer, or equally close on a smaller instance index, or the same instance and
    /// a smaller primitive index: the order of the flattened list of every instance's
    /// primitives.
    #[inline(always)]
    pub fn beats(t: f32, instance: u32, prim: u32, best: &InstanceHit) -> bool {
        t < best.t || (t == best.t && (instance, prim) < (best.instance, best.prim))
    }

    /// Whether two answers agree: both miss, or the same instance and primitive with `t` as
    /// [`Hit::agree`] allows.
    pub fn agree(a: Option<InstanceHit>, b: Option<InstanceHit>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                a.instance == b.instance && Hit::agree(Some(a.hit()), Some(b.hit()))
            }
            _ => false,
        }
    }

    /// The hit as a one-level [`Hit`] on the bottom level's primitive.
    #[inline]
    pub fn hit(&self) -> Hit {
        Hit {
            prim: self.prim,
            t: self.t,
            u: self.u,
            v: self.v,
        }
    }
}

/// The answer to a closest-point query in a two-level scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstancePointHit {
    /// The instance's index in the scene.
    pub instance: u32,
    /// The instance's id.
    pub id: u32,
    /// The primitive's index in its bottom level's build input.
    pub prim: u32,
    /// The nearest point, in the world.
    pub point: Vec3,
    /// Its distance from the query point ([`point_distance`]).
    pub distance: f32,
    /// The part of the primitive it lies on ([`PointHit::feature`](rt_core::PointHit)).
    pub feature: Feature,
}

impl InstancePointHit {
    /// Whether two answers agree: both none, or the same instance and primitive at distances
    /// as [`PointHit::agree`](rt_core::PointHit::agree) allows.
    pub fn agree(a: Option<InstancePointHit>, b: Option<InstancePointHit>) -> bool {
        let one = |h: InstancePointHit| rt_core::PointHit {
            prim: h.prim,
            point: h.point,
            distance: h.distance,
            feature: h.feature,
        };
        match (a, b) {
            (None, None) => true,
            (Some(x), Some(y)) => {
                x.instance == y.instance && rt_core::PointHit::agree(Some(one(x)), Some(one(y)))
            }
            _ => false,
        }
    }
}

/// A closest-point query over a two-level scene: the world ball around the query point, which
/// shrinks as instances offer primitives, and the best answer so far. Ties go to the smaller
/// instance index, then the smaller primitive index.
///
/// The pruning radius is widened as [`ClosestPointQuery`](rt_core::ClosestPointQuery)'s is, with
/// the rounding margin scaled by the scene's largest condition number.
#[derive(Clone, Copy, Debug)]
pub struct InstancePointQuery {
    center: Vec3,
    max_distance: f32,
    condition: f32,
    slack: f32,
    radius_sq: f32,
    best: Option<InstancePointHit>,
}

impl InstancePointQuery {
    /// A query for the point nearest to `point` no farther than `max_distance` (inclusive),
    /// among instances whose reach is at most `reach` and condition number at most `condition`.
    /// An invalid query (a non-finite point or one beyond [`Ray::MAX_ORIGIN`], a negative or NaN
    /// distance) finds nothing.
    pub fn new(point: Vec3, max_distance: f32, reach: f32, condition: f32) -> Self {
        let valid = point.is_finite()
            && point.abs().max_element() <= Ray::MAX_ORIGIN
            && max_distance >= 0.0;
        let mut q = Self {
            center: point,
            max_distance,
            condition: condition.max(1.0),
            slack: InstanceTransform::point_pad(point, condition.max(1.0), reach),
            radius_sq: -1.0,
            best: None,
        };
        if valid {
            q.set_radius(max_distance);
        }
        q
    }

    /// The query point.
    #[inline]
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// The squared pruning radius in the world (negative for an invalid query).
    #[inline]
    pub fn radius_sq(&self) -> f32 {
        self.radius_sq
    }

    /// The best answer so far (after the traversal, the answer); its `id` is filled in by the
    /// scene.
    #[inline]
    pub fn best(&self) -> Option<InstancePointHit> {
        self.best
    }

    fn set_radius(&mut self, distance: f32) {
        let r = distance * (1.0 + 1.0 / 65536.0) + self.slack;
        self.radius_sq = r * r;
    }

    /// Keeps `point` of primitive `prim` of instance `instance` if it is near enough and beats
    /// the best so far.
    #[inline]
    fn offer(&mut self, (point, feature): (Vec3, Feature), instance: u32, prim: u32) {
        let distance = point_distance(self.center, point);
        let better = self.best.is_none_or(|b| {
            distance < b.distance
                || (distance == b.distance && (instance, prim) < (b.instance, b.prim))
        });
        if distance <= self.max_distance && better {
            self.best = Some(InstancePointHit {
                instance,
                id: 0,
                prim,
                point,
                distance,
                feature,
            });
            self.set_radius(distance);
        }
    }
}

/// The world query seen from one instance's object space.
struct ObjectBall<'a, P> {
    query: &'a mut InstancePointQuery,
    to_world: Affine3A,
    center: Vec3,
    stretch: f32,
    pad: f32,
    index: u32,
    radius_sq: f32,
    _prim: std::marker::PhantomData<fn(&P)>,
}

impl<P> ObjectBall<'_, P> {
    /// The object-space radius: the world radius, padded for the rounding of the world
    /// computations and of the centre, times the stretch of the inverse.
    #[inline]
    fn update(&mut self) {
        let r = self.query.radius_sq;
        self.radius_sq = if r < 0.0 {
            -1.0
        } else {
            let obj = (r.sqrt() + self.pad) * self.stretch;
            obj * obj
        };
    }
}

impl<P: TransformPrimitive> BallQuery<P> for ObjectBall<'_, P> {
    #[inline]
    fn center(&self) -> Vec3 {
        self.center
    }
    #[inline]
    fn radius_sq(&self) -> f32 {
        self.radius_sq
    }
    #[inline]
    fn test(&mut self, prim: &P, id: u32) {
        let point = prim.closest_feature_transformed(&self.to_world, self.query.center);
        self.query.offer(point, self.index, id);
        self.update();
    }
    #[inline]
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        let point =
            closest_feature_on_transformed_triangle(&self.to_world, v0, e1, e2, self.query.center);
        self.query.offer(point, self.index, id);
        self.update();
    }
}

/// A two-level scene: instances of bottom-level structures, answered as one scene.
///
/// Contract, checked by the conformance kit (`rt_conformance::check_two_level_case`): every query
/// answers exactly as [`LinearInstances`] over the same instances does.
pub trait TwoLevel<P: Primitive>: Sized + Send + Sync {
    /// Short name for reports.
    const NAME: &'static str;

    /// The scene over `instances`; hits name instances by their position in this list.
    fn build(instances: Vec<Instance<P>>) -> Self;

    /// The instances, in build order.
    fn instances(&self) -> &[Instance<P>];

    /// The closest hit, reporting events (the top level's and every bottom level's) to
    /// `stats`.
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<InstanceHit>;

    /// Whether anything is hit in the ray's interval, reporting events to `stats`.
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool;

    /// The nearest point within `max_distance` (inclusive), reporting events to `stats`.
    fn closest_point_with<S: Stats>(
        &self,
        point: Vec3,
        max_distance: f32,
        stats: &mut S,
    ) -> Option<InstancePointHit>
    where
        P: TransformPrimitive;

    /// The closest hit.
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<InstanceHit> {
        self.intersect_with(ray, &mut NoStats)
    }

    /// [`intersect_with`](Self::intersect_with) of every ray into the same slot of `out` (as
    /// many as both have), on this thread, counting into `stats`: rays that travel together
    /// (a camera's tile, shadow rays from nearby points toward one light) may be traced
    /// together, and every answer is the single query's, bit for bit, whatever rays come
    /// along with it (the conformance kit checks it). The default, which every scene of this
    /// workspace uses today, traces the rays one by one.
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<InstanceHit>],
        stats: &mut S,
    ) {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = self.intersect_with(r, stats);
        }
    }

    /// [`occluded_with`](Self::occluded_with) of every ray into the same slot of `out`, as
    /// [`intersect_bundle_with`](Self::intersect_bundle_with) traces them.
    fn occluded_bundle_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = self.occluded_with(r, stats);
        }
    }

    /// [`intersect_bundle_with`](Self::intersect_bundle_with), uncounted.
    #[inline]
    fn intersect_bundle(&self, rays: &[Ray], out: &mut [Option<InstanceHit>]) {
        self.intersect_bundle_with(rays, out, &mut NoStats);
    }

    /// [`occluded_bundle_with`](Self::occluded_bundle_with), uncounted.
    #[inline]
    fn occluded_bundle(&self, rays: &[Ray], out: &mut [bool]) {
        self.occluded_bundle_with(rays, out, &mut NoStats);
    }

    /// The closest hits of rays in any order (a path tracer's bounces, scattered over the
    /// scene), into the same slots of `out`, counting into `stats`: the one-level stream
    /// queries' counterpart ([`Accel::intersect_stream_with`](rt_core::Accel::intersect_stream_with)),
    /// the single query's answers bit for bit. The default is
    /// [`intersect_bundle_with`](Self::intersect_bundle_with), which sends rays that do not
    /// travel together singly.
    #[inline]
    fn intersect_stream_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<InstanceHit>],
        stats: &mut S,
    ) {
        self.intersect_bundle_with(rays, out, stats);
    }

    /// [`occluded_with`](Self::occluded_with) of rays in any order, as
    /// [`intersect_stream_with`](Self::intersect_stream_with) traces them.
    #[inline]
    fn occluded_stream_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        self.occluded_bundle_with(rays, out, stats);
    }

    /// [`intersect_stream_with`](Self::intersect_stream_with), uncounted.
    #[inline]
    fn intersect_stream(&self, rays: &[Ray], out: &mut [Option<InstanceHit>]) {
        self.intersect_stream_with(rays, out, &mut NoStats);
    }

    /// [`occluded_stream_with`](Self::occluded_stream_with), uncounted.
    #[inline]
    fn occluded_stream(&self, rays: &[Ray], out: &mut [bool]) {
        self.occluded_stream_with(rays, out, &mut NoStats);
    }

    /// [`intersect`](Self::intersect) of every ray into the same slot of `out` (as many as
    /// both have), on every thread of the current rayon pool as [`rt_core::batch`] runs its
    /// queries: rays from a slice or from flat rows ([`RaySource`]), each chunk traced by
    /// [`intersect_bundle`](Self::intersect_bundle). A scene may override it, and must then
    /// answer each ray exactly as the single query does (the conformance kit checks it).
    fn intersect_batch<R: RaySource + ?Sized>(&self, rays: &R, out: &mut [Option<InstanceHit>]) {
        batch::for_each_ray_chunk(rays, out, |rays, out| self.intersect_bundle(rays, out));
    }

    /// [`occluded`](Self::occluded) of every ray into the same slot of `out`, as
    /// [`intersect_batch`](Self::intersect_batch) runs.
    fn occluded_batch<R: RaySource + ?Sized>(&self, rays: &R, out: &mut [bool]) {
        batch::for_each_ray_chunk(rays, out, |rays, out| self.occluded_bundle(rays, out));
    }

    /// Whether anything is hit in the ray's interval.
    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_with(ray, &mut NoStats)
    }

    /// The nearest point within `max_distance`.
    #[inline]
    fn closest_point(&self, point: Vec3, max_distance: f32) -> Option<InstancePointHit>
    where
        P: TransformPrimitive,
    {
        self.closest_point_with(point, max_distance, &mut NoStats)
    }

    /// The box around every instance's world box.
    fn bounds(&self) -> Aabb;

    /// Bytes held: the scene's own, plus each distinct bottom level once.
    fn memory_bytes(&self) -> usize;
}

/// Whether `ray` enters `b` grown by `pad` within `[ray.t_min, t_max]`: the top-level cull.
#[inline]
fn reaches(b: &Aabb, pad: f32, ray: &Ray, t_max: f32) -> bool {
    b.padded(pad).intersect(ray, t_max).is_some()
}

/// The bytes of each distinct bottom level among `instances`, counted once.
pub fn bottom_bytes<P>(instances: &[Instance<P>]) -> usize {
    let mut seen = std::collections::HashSet::new();
    instances
        .iter()
        .filter(|i| seen.insert(Arc::as_ptr(&i.bottom) as *const () as usize))
        .map(|i| i.bottom.memory_bytes_dyn())
        .sum()
}

/// The largest reach and condition number among `instances` (see
/// [`InstanceTransform::ray_pad`]).
pub fn scene_margins<P>(instances: &[Instance<P>]) -> (f32, f32) {
    instances.iter().fold((0.0f32, 1.0f32), |(r, c), i| {
        (r.max(i.reach), c.max(i.transform.condition))
    })
}

/// The reference two-level scene: every query visits every instance, in order, with no top
/// level at all, skipping only those whose world box (grown by
/// [`InstanceTransform::ray_pad`]) the ray misses, or that lie farther than the query's ball.
/// What any other [`TwoLevel`] must answer exactly.
#[derive(Clone, Debug)]
pub struct LinearInstances<P> {
    instances: Vec<Instance<P>>,
    bounds: Aabb,
    reach: f32,
    condition: f32,
}

impl<P: Primitive> TwoLevel<P> for LinearInstances<P> {
    const NAME: &'static str = "linear";

    fn build(instances: Vec<Instance<P>>) -> Self {
        let bounds = instances
            .iter()
            .fold(Aabb::EMPTY, |b, i| b.union(i.world_bounds));
        let (reach, condition) = scene_margins(&instances);
        Self {
            instances,
            bounds,
            reach,
            condition,
        }
    }

    fn instances(&self) -> &[Instance<P>] {
        &self.instances
    }

    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<InstanceHit> {
        if !ray.is_valid() {
            return None;
        }
        let mut best: Option<InstanceHit> = None;
        let pad = InstanceTransform::ray_pad(ray, self.condition, self.reach);
        for (k, inst) in self.instances.iter().enumerate() {
            let t_max = best.map_or(ray.t_max, |b| b.t);
            if !reaches(&inst.world_bounds, pad, ray, t_max) {
                continue;
            }
            if let Some(h) = inst.intersect_with(ray, t_max, stats)
                && best.is_none_or(|b| InstanceHit::beats(h.t, k as u32, h.prim, &b))
            {
                best = Some(InstanceHit {
                    instance: k as u32,
                    id: inst.id,
                    prim: h.prim,
                    t: h.t,
                    u: h.u,
                    v: h.v,
                });
            }
        }
        best
    }

    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        let pad = InstanceTransform::ray_pad(ray, self.condition, self.reach);
        ray.is_valid()
            && self.instances.iter().any(|i| {
                reaches(&i.world_bounds, pad, ray, ray.t_max) && i.occluded_with(ray, stats)
            })
    }

    fn closest_point_with<S: Stats>(
        &self,
        point: Vec3,
        max_distance: f32,
        stats: &mut S,
    ) -> Option<InstancePointHit>
    where
        P: TransformPrimitive,
    {
        let mut query = InstancePointQuery::new(point, max_distance, self.reach, self.condition);
        for (k, inst) in self.instances.iter().enumerate() {
            if inst.world_bounds.distance_squared(point) <= query.radius_sq() {
                inst.ball_query(k as u32, &mut query, stats);
            }
        }
        query.best().map(|h| InstancePointHit {
            id: self.instances[h.instance as usize].id,
            ..h
        })
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.instances.capacity() * size_of::<Instance<P>>()
            + bottom_bytes(&self.instances)
    }
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

/// The largest absolute row sum of `m`: how much it can lengthen a vector's largest
/// coordinate, and so the magnitude of the terms a transform sums.
fn norm_inf(m: Mat3A) -> f32 {
    let t = m.transpose();
    [t.x_axis, t.y_axis, t.z_axis]
        .map(|row| row.abs().element_sum())
        .into_iter()
        .fold(0.0, f32::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use rt_core::Rng;

    /// A random affine map: a rotation, scales from 1/30 to 30 on each axis (a mirror on some),
    /// a shear, and a translation of up to `shift`.
    fn random_transform(rng: &mut Rng, shift: f32) -> Affine3A {
        let rotation = Quat::from_axis_angle(rng.unit_vector(), rng.range(0.0, 6.3));
        let scale = Vec3::new(
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
        )
        .map(|e| 10f32.powf(e) * if rng.f32() < 0.2 { -1.0 } else { 1.0 });
        let shear = Mat3A::from_cols(
            Vec3A::X,
            Vec3A::new(rng.range(-0.5, 0.5), 1.0, 0.0),
            Vec3A::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 1.0),
        );
        Affine3A::from_translation(rng.in_box(Vec3::splat(-shift), Vec3::splat(shift)))
            * Affine3A::from_mat3(glam::Mat3::from(shear))
            * Affine3A::from_scale_rotation_translation(scale, rotation, Vec3::ZERO)
    }

    /// Rays spawned from world surface points of instanced triangles (random transforms with
    /// mirrors, shears and condition numbers up to the thousands; object scales from 10⁻³ to
    /// 10³; instances far from the origin), in any direction off the plane, carried back into
    /// the instance as a two-level walk carries them: none hits its own triangle, and one
    /// aimed back at the surface from the same origin does (the offset went to its side only).
    #[test]
    fn rays_spawned_from_instance_hits_leave_their_surface() {
        let mut rng = Rng::new(11);
        let (mut checked, mut backs) = (0, 0);
        for scale in [1e-3f32, 1.0, 1e3] {
            for shift in [0.0f32, 10.0, 1e4] {
                for _ in 0..100 {
                    let Ok(xf) = InstanceTransform::new(random_transform(&mut rng, shift * scale))
                    else {
                        continue;
                    };
                    let v = [0; 3].map(|_| rng.in_box(Vec3::splat(-scale), Vec3::splat(scale)));
                    let tri = Triangle::new(v[0], v[1], v[2]);
                    if tri.normal().length() < 1e-3 * scale * scale {
                        continue;
                    }
                    for _ in 0..20 {
                        let (a, b) = (rng.range(0.02, 0.98), rng.range(0.02, 0.98));
                        let (u, v) = if a + b > 0.98 {
                            (0.98 - a, 0.98 - b)
                        } else {
                            (a, b)
                        };
                        let (u, v) = (u.max(0.01), v.max(0.01));
                        let s = xf.surface_to_world(tri.surface_at(u, v));
                        let dir = rng.unit_vector();
                        if dir.dot(s.normal).abs() < 1e-2 {
                            continue;
                        }
                        let ray = s.spawn_ray(dir);
                        let object = xf.ray_to_object(&ray);
                        assert!(
                            tri.intersect(&object, f32::INFINITY).is_none(),
                            "self-hit: scale {scale}, shift {shift}, {tri:?}, {:?}, {}",
                            xf.to_world(),
                            ray.to_rust()
                        );
                        // Where the offset is small beside the triangle (it is not for tiny
                        // triangles far from the origin under ill-conditioned maps, where the
                        // transforms' rounding alone spans the triangle), the origin still
                        // lies over it.
                        let w = [tri.v0, tri.v1, tri.v2].map(|p| xf.to_world().transform_point3(p));
                        let edge = (w[1] - w[0])
                            .length()
                            .min((w[2] - w[1]).length())
                            .min((w[0] - w[2]).length());
                        if (ray.origin - s.point).length() < 1e-3 * edge {
                            let back = Ray::new(ray.origin, -dir.dot(s.normal).signum() * s.normal);
                            assert!(
                                tri.intersect(&xf.ray_to_object(&back), f32::INFINITY)
                                    .is_some(),
                                "the offset crossed the surface: {}",
                                back.to_rust()
                            );
                            backs += 1;
                        }
                        checked += 1;
                    }
                }
            }
        }
        assert!(
            checked > 10_000 && backs > checked / 3,
            "{checked} rays, {backs} back"
        );
    }

    /// The world normal is the object normal carried by the inverse transpose: perpendicular
    /// to the world image of the triangle's edges, on the object normal's side.
    #[test]
    fn world_normals_are_perpendicular_to_world_edges() {
        let mut rng = Rng::new(12);
        for _ in 0..500 {
            let Ok(xf) = InstanceTransform::new(random_transform(&mut rng, 10.0)) else {
                continue;
            };
            let v = [0; 3].map(|_| rng.in_box(Vec3::splat(-1.0), Vec3::ONE));
            let tri = Triangle::new(v[0], v[1], v[2]);
            if tri.normal().length() < 1e-2 {
                continue;
            }
            let s = xf.surface_to_world(tri.surface_at(0.3, 0.3));
            let w = v.map(|p| xf.to_world().transform_point3(p));
            for e in [w[1] - w[0], w[2] - w[0]] {
                assert!(
                    s.normal.dot(e.normalize()).abs() < 1e-3,
                    "{:?}",
                    xf.to_world()
                );
            }
            // On the object normal's side: a point just off the object surface along its
            // normal lands on the world normal's side.
            let off = xf
                .to_world()
                .transform_point3(tri.surface_at(0.3, 0.3).point + 0.1 * tri.normal().normalize());
            assert!((off - s.point).dot(s.normal) > 0.0);
            assert!((s.normal.length() - 1.0).abs() < 1e-5);
        }
    }

    /// Under a rotation and a translation, the world bound stays within a small factor of the
    /// bound of the same triangle given in world coordinates: the transforms' rounding adds
    /// little where nothing is stretched.
    #[test]
    fn rigid_motions_keep_the_bound_tight() {
        let mut rng = Rng::new(13);
        for _ in 0..500 {
            let rotation = Quat::from_axis_angle(rng.unit_vector(), rng.range(0.0, 6.3));
            let shift = rng.in_box(Vec3::splat(-100.0), Vec3::splat(100.0));
            let xf = InstanceTransform::new(Affine3A::from_rotation_translation(rotation, shift))
                .unwrap();
            let v = [0; 3].map(|_| rng.in_box(Vec3::splat(-1.0), Vec3::ONE));
            let tri = Triangle::new(v[0], v[1], v[2]);
            let world = Triangle::new(
                xf.to_world().transform_point3(v[0]),
                xf.to_world().transform_point3(v[1]),
                xf.to_world().transform_point3(v[2]),
            );
            let (s, one_level) = (
                xf.surface_to_world(tri.surface_at(0.2, 0.3)),
                world.surface_at(0.2, 0.3),
            );
            assert!(
                s.error <= 4.0 * one_level.error,
                "{} against {}",
                s.error,
                one_level.error
            );
        }
    }
}

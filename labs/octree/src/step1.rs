//! Step 1: the ray's constants, and the parameters of a box's faces.
//!
//! The parametric walk never computes a point: it works with the ray parameter `t` at which the
//! ray meets each plane it cares about, `(x - o) / d` along that plane's axis, computed as
//! `(x - o) * inv` with the reciprocal direction `ray.inv_dir()`. For a box `[lo, hi]` the ray
//! meets, per axis, a *near* face first and a *far* face later; the ray is inside the box from
//! the largest near parameter to the smallest far one.
//!
//! Which face is near depends on the direction's sign. Revelles et al. remove the sign once per
//! ray by *mirroring*: an axis the ray runs down is treated as if it ran up, so that near is
//! always the smaller parameter and a node's children can be numbered in the ray's order (child
//! `c` in ray order is child `c ^ neg` in the block, `neg` being the mask of mirrored axes; see
//! step 2). `-0.0` and `+0.0` are not "down": they are *flat*.
//!
//! A flat axis (a zero or denormal direction component: its reciprocal is not finite) has no
//! parameter: the ray stays at its origin's coordinate there. It is in the box's slab for all
//! `t` when the origin lies in `[lo, hi]` on that axis (closed: on a face counts), and never
//! otherwise. Write that as near `-∞`, far `+∞` (always inside) or near `+∞`, far `-∞` (never):
//! then "the largest near, the smallest far" works unchanged.
//!
//! Write the face parameters yourself: rt-core's [`rt_core::Aabb::intersect`] computes the same
//! interval (the tests compare yours with it), and the rest of the walk needs them per axis.

use rt_core::Ray;
use rt_core::glam::Vec3;

/// The constants of one ray that every node's parameters are computed from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axes {
    /// The ray's origin.
    pub origin: Vec3,
    /// The reciprocals of the direction's components, `ray.inv_dir()`.
    pub inv: Vec3,
    /// The axes the ray runs down (a negative, not flat, direction component), bit `a` for
    /// axis `a`: the mirrored axes.
    pub neg: u32,
    /// The flat axes (the reciprocal is not finite: a zero or denormal component), bit `a` for
    /// axis `a`.
    pub flat: u32,
}

/// The ray's constants.
pub fn axes(ray: &Ray) -> Axes {
    todo!("step 1: the ray's constants")
}

/// The parameters at which the ray meets the near and the far face of box `[lo, hi]`, per axis,
/// in the ray's order (near is the face it meets first: `lo` on an axis it runs up, `hi` on a
/// mirrored one). A flat axis gives `(-∞, +∞)` when the origin lies in `[lo, hi]` there, and
/// `(+∞, -∞)` when it does not.
pub fn faces(r: &Axes, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    todo!("step 1: the faces' parameters")
}

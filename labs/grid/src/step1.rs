//! Step 1: the box around the scene, and the slab test.
//!
//! Every ray first meets the grid's box: the slab test (Kay & Kajiya 1986) gives the part
//! `[t0, t1]` of the ray inside it. Per axis, the ray is inside the slab `min ≤ o + t·d ≤ max`
//! between `(min - o) / d` and `(max - o) / d`; the box is the intersection of the three slabs
//! and of the ray's own interval. Mind the corner cases: a zero direction component gives
//! infinite reciprocals (`ray.inv_dir()`), `-0.0` is negative, and `0 × ∞` is NaN when the
//! origin lies in a face plane: such a ray is inside that slab (boxes are closed).
//!
//! Write the slab test yourself: rt-core's [`Aabb::intersect`] is the same test (the step's
//! tests compare your answers with it), so calling it skips the step. The rest of rt-core is
//! yours to use: [`Ray::inv_dir`], [`Aabb::union`], [`Primitive::bounds`],
//! [`Primitive::is_valid`].

use rt_core::{Aabb, Primitive, Ray, SLAB_FAR_SCALE, Triangle};

/// The smallest box around the valid triangles (see [`Primitive::is_valid`]); [`Aabb::EMPTY`]
/// if there are none. Invalid triangles (a NaN vertex, zero area) must not stretch the box.
pub fn scene_bounds(tris: &[Triangle]) -> Aabb {
    todo!("step 1: the box around the valid triangles")
}

/// The part `[t0, t1]` of the ray inside box `b`, within `[ray.t_min, t_max]`, or `None` if
/// the ray misses it there. The box is closed: a ray that only touches a face or lies in a
/// face plane hits it. Make the far end a little generous: multiply `t1` by [`SLAB_FAR_SCALE`]
/// (rt-core's margin, `1 + 2⁻¹⁶`, which step 4 uses too) before comparing it with `t0`, since
/// rounding may put it a hair before a hit on the box's face.
pub fn slab(b: &Aabb, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
    todo!("step 1: the slab test")
}

//! Step 1: boxes, and where a ray enters one.
//!
//! The builder needs two boxes per node: the box around its triangles (what the ray will be
//! tested against) and the box around their centroids (where the split planes go: a plane
//! outside it would leave one side empty). The traversal needs the distance at which a ray
//! enters a box, to skip boxes beyond the best hit and to visit the nearer child first.
//!
//! The entry distance is the slab test (Kay & Kajiya 1986): per axis, the ray is between the
//! box's two planes from `(lo - o) / d` to `(hi - o) / d`, where `lo` is the plane it meets
//! first (the smaller one when `d` is positive, the larger when it is negative); the box is
//! where all three slabs and the ray's own interval overlap. Mind the corner cases: a zero
//! direction component gives infinite reciprocals (`ray.inv_dir()`); `-0.0` counts as negative;
//! `0 × ∞` is NaN when the origin lies in a face plane, and such a ray is inside that slab
//! (boxes are closed).
//!
//! Write the slab test yourself: rt-core's [`Aabb::intersect`] and [`Aabb::entry`] answer the
//! same question (the step's tests compare your answers with theirs), so calling them skips the
//! step. The rest of rt-core is yours to use: [`Ray::inv_dir`], [`Aabb::union`],
//! [`Aabb::grow`], [`Primitive::bounds`], and [`crate::centroid`] from `lib.rs`.

use rt_core::{Aabb, Primitive, Ray, SLAB_FAR_SCALE, Triangle};

/// The box around the triangles `tris[id]` for `id` in `ids`, and the box around their
/// centroids ([`crate::centroid`]: the centre of each triangle's box). Both are [`Aabb::EMPTY`]
/// when `ids` is empty.
pub fn bounds(tris: &[Triangle], ids: &[u32]) -> (Aabb, Aabb) {
    // BEGIN SOLUTION step 1: the boxes around the triangles and around their centroids
    ids.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), &id| {
        let t = &tris[id as usize];
        (b.union(t.bounds()), c.grow(crate::centroid(t)))
    })
    // END SOLUTION
}

/// The distance at which the ray enters box `b`, if it meets the box within
/// `[ray.t_min, t_max]`; `f32::INFINITY` if it does not. A ray starting inside the box enters
/// it at `ray.t_min`. Make the far end of the interval a little generous: compare the entry
/// with the exit times [`SLAB_FAR_SCALE`] (rt-core's margin, `1 + 2⁻¹⁶`, which step 4 uses
/// too), since rounding may put the exit a hair before a hit on the box's face.
pub fn entry(b: &Aabb, ray: &Ray, t_max: f32) -> f32 {
    // BEGIN SOLUTION step 1: the entry distance
    let mut near = ray.t_min;
    let mut far = t_max;
    for a in 0..3 {
        let inv = ray.inv_dir()[a];
        let (lo, hi) = if inv.is_sign_negative() {
            (b.max[a], b.min[a])
        } else {
            (b.min[a], b.max[a])
        };
        let t_lo = (lo - ray.origin[a]) * inv;
        let t_hi = (hi - ray.origin[a]) * inv;
        // A NaN (origin in the plane, zero direction) fails both comparisons: that axis does
        // not narrow the interval.
        near = if t_lo > near { t_lo } else { near };
        far = if t_hi < far { t_hi } else { far };
    }
    if near <= far * SLAB_FAR_SCALE {
        near
    } else {
        f32::INFINITY
    }
    // END SOLUTION
}

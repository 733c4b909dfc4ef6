//! Step 4: the closest hit.
//!
//! Walk the tree with a stack instead of recursion (no call overhead, and a fixed
//! [`MAX_DEPTH`]-entry array on the stack: no allocation per ray). Push each node with the
//! distance at which the ray enters its box. Pop a node; if that distance is beyond the best
//! hit so far, skip it: nothing in its box can be closer. "Beyond" with step 1's margin: the
//! entry distance and a hit's `t` are both rounded, so a hit on a box's face may come out a
//! hair before the box's entry; skip only what starts beyond `best.t * SLAB_FAR_SCALE`.
//! Otherwise test a leaf's triangles, or push an interior node's children (step 3), the
//! farther one first so that the nearer is popped next.
//!
//! Keep the best hit by the tie rule ([`Hit::beats`]: smaller `t`, then smaller index), so a
//! node entered exactly at the best `t` must still be visited. Rays outside the trait's
//! precondition ([`Ray::is_valid`] false: NaN, infinite, zero direction) return `None` at
//! once, visiting nothing. Report each node visited and each triangle tested to `stats`.

use crate::{LabBvh, MAX_DEPTH, Node, step1, step3};
use rt_core::{Hit, Primitive, Ray, SLAB_FAR_SCALE, Stats};

/// Tests the triangles of leaf `node` against the ray up to `best.t`, keeping the best hit in
/// `best` by the tie rule.
pub fn test_leaf<S: Stats>(bvh: &LabBvh, node: &Node, ray: &Ray, best: &mut Hit, stats: &mut S) {
    todo!("step 4: testing a leaf")
}

/// The closest hit along the ray (ties to the smaller index), or `None`.
pub fn closest_hit<S: Stats>(bvh: &LabBvh, ray: &Ray, stats: &mut S) -> Option<Hit> {
    todo!("step 4: the closest hit")
}

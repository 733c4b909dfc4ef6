//! Step 4: the walk for a query.
//!
//! The walk does not decide which hit to keep: it offers each hit it finds to a query
//! ([`RayQuery::offer`]), and the query keeps what it wants. For the closest hit
//! ([`ClosestHit`](rt_core::ClosestHit)) that is the best hit by the tie rule
//! ([`Hit::beats`](rt_core::Hit::beats): smaller `t`, then smaller index), and
//! [`RayQuery::t_far`], how far along the ray the query still wants hits, is the best `t` so
//! far.
//!
//! Walk the tree with a stack instead of recursion (no call overhead, and a fixed
//! [`MAX_DEPTH`]-entry array on the stack: no allocation per ray). Push each node with the
//! distance at which the ray enters its box. Pop a node; if that distance is beyond the query's
//! far end, skip it: nothing in its box can be wanted. "Beyond" with step 1's margin: the
//! entry distance and a hit's `t` are both rounded, so a hit on a box's face may come out a
//! hair before the box's entry; skip only what starts beyond `query.t_far() * SLAB_FAR_SCALE`.
//! Otherwise offer the query the hits of a leaf's triangles (up to `query.t_far()`), or push an
//! interior node's children (step 3), the farther one first so that the nearer is popped next.
//! An offer that returns [`ControlFlow::Break`] ends the walk at once.
//!
//! A node entered exactly at the best `t` must still be visited (a tie goes to the smaller
//! index). Rays outside the trait's precondition ([`Ray::is_valid`] false: NaN, infinite, zero
//! direction) walk nothing. Report each node visited and each triangle tested to `stats`.

use crate::{LabBvh, MAX_DEPTH, Node, step1, step3};
use rt_core::{Primitive, Ray, RayQuery, SLAB_FAR_SCALE, Stats};
use std::ops::ControlFlow;

/// Tests the triangles of leaf `node` against the ray up to `query.t_far()` and offers
/// `query` each hit; `Break` when the query ends the walk.
pub fn test_leaf<Q: RayQuery, S: Stats>(
    bvh: &LabBvh,
    node: &Node,
    ray: &Ray,
    query: &mut Q,
    stats: &mut S,
) -> ControlFlow<()> {
    // BEGIN SOLUTION step 4: testing a leaf
    for &id in bvh.leaf_ids(node) {
        stats.prim_test();
        if let Some(h) = bvh.tris[id as usize].intersect(ray, query.t_far()) {
            query.offer(id, h)?;
        }
    }
    ControlFlow::Continue(())
    // END SOLUTION
}

/// The walk for `query`: every hit in `[ray.t_min, query.t_far()]` offered to it, nearer boxes
/// first, until it stops the walk.
pub fn walk<Q: RayQuery, S: Stats>(bvh: &LabBvh, ray: &Ray, query: &mut Q, stats: &mut S) {
    // BEGIN SOLUTION step 4: the walk for a query
    if !ray.is_valid() || bvh.nodes.is_empty() {
        return;
    }
    let mut stack = [(0u32, 0.0f32); MAX_DEPTH];
    stack[0] = (0, step1::entry(&bvh.nodes[0].bounds, ray, query.t_far()));
    let mut len = usize::from(stack[0].1.is_finite());
    while len > 0 {
        len -= 1;
        let (i, t_entry) = stack[len];
        if t_entry > query.t_far() * SLAB_FAR_SCALE {
            continue;
        }
        stats.node_visit();
        let node = &bvh.nodes[i as usize];
        if node.is_leaf() {
            if test_leaf(bvh, node, ray, query, stats).is_break() {
                return;
            }
            continue;
        }
        let [near, far] = step3::order(bvh, i, ray, query.t_far());
        for (child, t) in [far, near] {
            if t.is_finite() {
                stack[len] = (child, t);
                len += 1;
            }
        }
    }
    // END SOLUTION
}

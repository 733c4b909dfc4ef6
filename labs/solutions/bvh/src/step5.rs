//! Step 5: the any-hit query.
//!
//! A shadow ray asks only whether anything lies between a point and a light: the first
//! triangle found that blocks it ends the walk, whichever it is. So nothing needs sorting and
//! no interval shrinks: visit every node whose box the ray enters within its interval, in any
//! order, and stop at the first [`Primitive::occludes`]. Invalid rays return `false` at once.

use crate::{LabBvh, MAX_DEPTH, step1};
use rt_core::{Primitive, Ray, Stats};

/// Whether any triangle is hit within the ray's interval.
pub fn any_hit<S: Stats>(bvh: &LabBvh, ray: &Ray, stats: &mut S) -> bool {
    // BEGIN SOLUTION step 5: the any hit
    if !ray.is_valid() || bvh.nodes.is_empty() {
        return false;
    }
    let mut stack = [0u32; MAX_DEPTH];
    let mut len = 1;
    while len > 0 {
        len -= 1;
        let i = stack[len];
        let node = &bvh.nodes[i as usize];
        if step1::entry(&node.bounds, ray, ray.t_max).is_infinite() {
            continue;
        }
        stats.node_visit();
        if !node.is_leaf() {
            let [a, b] = bvh.children(i);
            stack[len] = b;
            stack[len + 1] = a;
            len += 2;
            continue;
        }
        for &id in bvh.leaf_ids(node) {
            stats.prim_test();
            if bvh.tris[id as usize].occludes(ray, ray.t_max) {
                return true;
            }
        }
    }
    false
    // END SOLUTION
}

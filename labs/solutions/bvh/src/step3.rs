//! Step 3: one traversal step.
//!
//! At an interior node the ray may enter both children's boxes, one, or neither (the parent's
//! box is bigger than the two together). Visiting the nearer one first matters: a hit found
//! there makes `t_max` shorter, and the farther child may then be skipped without a test (step
//! 4). Which child is nearer depends on the ray, so order them by where the ray enters their
//! boxes, not by their place in the tree.

use crate::{LabBvh, step1};
use rt_core::Ray;

/// The two children of interior node `i` with the distance at which the ray enters each box
/// within `[ray.t_min, t_max]` (`f32::INFINITY` for a child it misses), nearest first. On a
/// tie the first child ([`LabBvh::children`]) comes first.
pub fn order(bvh: &LabBvh, i: u32, ray: &Ray, t_max: f32) -> [(u32, f32); 2] {
    // BEGIN SOLUTION step 3: the children entered, nearest first
    let [a, b] = bvh.children(i);
    let ta = step1::entry(&bvh.nodes[a as usize].bounds, ray, t_max);
    let tb = step1::entry(&bvh.nodes[b as usize].bounds, ray, t_max);
    if tb < ta {
        [(b, tb), (a, ta)]
    } else {
        [(a, ta), (b, tb)]
    }
    // END SOLUTION
}

//! Step 1: a node's plane, and which side the ray starts on.
//!
//! An interior node splits its cell at `node.split()` along axis `node.axis()` (0 = x, 1 = y,
//! 2 = z); its children are `node.index()` (below the plane) and `node.index() + 1` (above).
//! The node has no box: all a ray needs is the parameter `t` where it crosses the plane,
//! `(split - o) / d` along that axis (use `ray.inv_dir()`, the reciprocals, as every traversal
//! does), and which child it is in before that crossing: the near child.
//!
//! The near child is the one the ray is in before it crosses the plane: the origin's side. An
//! origin exactly in the plane crosses it at `t = 0`; then the near child is the one the ray
//! comes from (below, for a ray going up), and step 2 visits it over the single point `t = 0`
//! before the far child, the one the ray goes into: a triangle lying in the plane at the origin
//! may be listed on either side. Mind the corner cases: a direction parallel to the plane
//! (`d = ±0.0`) never crosses it (`t` is infinite), or gives NaN (`0 × ∞`) when the origin
//! also lies in the plane: step 2 deals with that.

use crate::Node;
use rt_core::Ray;

/// The ray parameter at which the ray crosses interior node `node`'s split plane: `±∞` if the
/// ray is parallel to it, NaN if it also lies in it.
pub fn plane_t(node: &Node, ray: &Ray) -> f32 {
    // BEGIN SOLUTION step 1: where the ray crosses the plane
    let a = node.axis();
    (node.split() - ray.origin[a]) * ray.inv_dir()[a]
    // END SOLUTION
}

/// The children of interior node `node` as `(near, far)`: the near one holds the ray's origin
/// (for an origin in the plane, the one the ray comes from: below unless the ray goes down).
pub fn near_far(node: &Node, ray: &Ray) -> (usize, usize) {
    // BEGIN SOLUTION step 1: the near and the far child
    let a = node.axis();
    let (o, d, split) = (ray.origin[a], ray.dir()[a], node.split());
    let below = o < split || (o == split && d > 0.0);
    let first = node.index();
    if below {
        (first, first + 1)
    } else {
        (first + 1, first)
    }
    // END SOLUTION
}

//! Step 2: which children the ray's interval reaches.
//!
//! The ray is in the current cell for `t` in `[t0, t1]`, and crosses the node's plane at `t`
//! (step 1). Four cases:
//!
//! - the plane lies beyond the interval (`t > t1`), or behind the origin (`t < 0`; `t = 0` is
//!   an origin in the plane, a crossing like any other): the ray stays in the near child
//!   ([`Visit::Near`]);
//! - the plane lies before the interval (`t < t0`): the ray crossed it before entering this
//!   cell, and is only in the far child ([`Visit::Far`]);
//! - otherwise the ray visits the near child over `[t0, t]`, then the far child over
//!   `[t, t1]` ([`Visit::Both`]);
//! - `t` is NaN: the ray lies in the plane, on the boundary of both children, and each may hold
//!   a triangle it hits; visit both over the whole interval ([`Visit::InPlane`]).
//!
//! Rounding: `t0`, `t1` and `t` are all computed, and a triangle lying on a cell's boundary may
//! be listed on only one side. So treat a plane *near* either end as inside the interval: use
//! the margin [`SLAB_FAR_SCALE`] (`1 + 2⁻¹⁶`), as in `t > t1 * SLAB_FAR_SCALE` and
//! `t * SLAB_FAR_SCALE < t0`. Visiting a child that turns out empty costs a step; missing
//! one costs a wrong answer.

use crate::{Node, step1};
use rt_core::{Ray, SLAB_FAR_SCALE};

/// Where the ray goes at an interior node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Visit {
    /// Only this child: the near one.
    Near(usize),
    /// Only this child: the far one.
    Far(usize),
    /// The near child over `[t0, t]`, then the far child over `[t, t1]`.
    Both {
        /// The child on the origin's side.
        near: usize,
        /// The other child.
        far: usize,
        /// Where the ray crosses the plane.
        t: f32,
    },
    /// The ray lies in the plane: both children, each over the whole `[t0, t1]`.
    InPlane {
        /// The child the ray is taken to be in first (either would do).
        near: usize,
        /// The other child.
        far: usize,
    },
}

/// Where the ray, inside interior node `node`'s cell for `t` in `[t0, t1]`, goes next.
pub fn visit(node: &Node, ray: &Ray, t0: f32, t1: f32) -> Visit {
    // BEGIN SOLUTION step 2: the four cases
    let t = step1::plane_t(node, ray);
    let (near, far) = step1::near_far(node, ray);
    if t.is_nan() {
        Visit::InPlane { near, far }
    } else if t < 0.0 || t > t1 * SLAB_FAR_SCALE {
        Visit::Near(near)
    } else if t * SLAB_FAR_SCALE < t0 {
        Visit::Far(far)
    } else {
        Visit::Both { near, far, t }
    }
    // END SOLUTION
}

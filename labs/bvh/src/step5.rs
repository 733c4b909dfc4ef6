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
    todo!("step 5: the any hit")
}

//! Step 5: the any-hit query.
//!
//! A shadow ray asks only whether anything lies between a point and a light: its query
//! ([`AnyHit`](rt_core::AnyHit)) is an occlusion query ([`RayQuery::OCCLUSION`]), and the
//! first triangle found that blocks it ends the walk, whichever it is. So nothing needs sorting
//! and no interval shrinks: visit every node whose box the ray enters within
//! `[t_min, query.t_far()]`, in any order, and stop at the first [`Primitive::occludes`] (which
//! needs no `t`, `u` or `v`), offering the query that triangle as [`BLOCKS`]. Invalid rays walk
//! nothing.

use crate::{LabBvh, MAX_DEPTH, step1};
use rt_core::query::BLOCKS;
use rt_core::{Primitive, Ray, RayQuery, Stats};

/// The occlusion walk for `query`: the first triangle that blocks the ray within
/// `[t_min, query.t_far()]` is offered to it, and ends the walk.
pub fn any_hit<Q: RayQuery, S: Stats>(bvh: &LabBvh, ray: &Ray, query: &mut Q, stats: &mut S) {
    todo!("step 5: the any hit")
}

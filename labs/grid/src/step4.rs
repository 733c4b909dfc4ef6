//! Step 4: the ray walk for a query, and when the walk may stop.
//!
//! The walk does not decide which hit to keep: it offers every hit it finds to a query
//! ([`RayQuery`]), and the query keeps what it wants. For the closest hit
//! ([`ClosestHit`](rt_core::ClosestHit)) that is the best hit by the tie rule
//! ([`Hit::beats`](rt_core::Hit::beats): smaller `t`, then smaller index), and
//! [`RayQuery::t_far`], how far along the ray the query still wants hits, is that best hit's
//! `t`. So test the triangles of each cell the walk visits up to `query.t_far()` and offer each
//! hit ([`RayQuery::offer`]). The trap: a triangle spanning several cells can be hit *beyond*
//! the current cell while a closer triangle waits in the next cell. So the walk stops only when
//! the next cell begins beyond what the query still wants. Allow for rounding: a closer
//! triangle in the next cell can report a `t` a few units in the last place below a hit on this
//! cell's exit, so walk on until the exit lies beyond `t_far` widened by
//! [`SLAB_FAR_SCALE`](rt_core::SLAB_FAR_SCALE) (`t_exit > query.t_far() * SLAB_FAR_SCALE`). An
//! offer that returns [`ControlFlow::Break`] ends the walk at once.
//!
//! Rays outside the trait's precondition ([`Ray::is_valid`] false: NaN, infinite, zero
//! direction) must walk nothing.

use crate::{LabGrid, step1, step3, step6};
use rt_core::{Primitive, Ray, RayQuery, Stats};
use std::ops::ControlFlow;

/// Tests the triangles of `cell` against the ray up to `query.t_far()` and offers `query` each
/// hit; `Break` when the query ends the walk. Each test is reported to `stats`; with mailboxes
/// on, a triangle this ray tested before is skipped (step 6) and reported as a mailbox skip.
pub fn test_cell<Q: RayQuery, S: Stats>(
    grid: &LabGrid,
    cell: [u32; 3],
    ray: &Ray,
    query: &mut Q,
    mailbox: &mut step6::RayMailbox,
    stats: &mut S,
) -> ControlFlow<()> {
    todo!("step 4: testing one cell")
}

/// The walk for `query`: every hit in `[ray.t_min, query.t_far()]` offered to it, until it
/// stops the walk.
pub fn walk<Q: RayQuery, S: Stats>(grid: &LabGrid, ray: &Ray, query: &mut Q, stats: &mut S) {
    todo!("step 4: the walk for a query")
}

//! Step 4: the walk for a query, and when it may stop.
//!
//! The walk does not decide which hit to keep: it offers each hit it finds to a query
//! ([`RayQuery::offer`]), and the query keeps what it wants. For the closest hit
//! ([`ClosestHit`](rt_core::ClosestHit)) that is the best hit by the tie rule
//! ([`Hit::beats`](rt_core::Hit::beats): smaller `t`, then smaller index), and
//! [`RayQuery::t_far`], how far along the ray the query still wants hits, is the best `t` so
//! far. Test the triangles of each cell the walk reaches up to `query.t_far()`, offer each
//! hit, and give the walk `query.t_far()` as its limit; an offer that returns
//! [`ControlFlow::Break`] ends the walk at once (a limit of `f32::NEG_INFINITY`).
//!
//! The trap, as in the uniform grid: a triangle is listed in every cell its surface
//! overlaps, in every grid of the hierarchy, so it can be hit *beyond* the current cell while a
//! closer one waits in the next cell (or in a nested grid the walk has not entered yet).
//! Stopping at the first cell with a hit returns the wrong one; the limit lets the walk go on
//! to every cell that starts before the best hit, and no further.
//!
//! The same listing in several cells means a ray meets the same triangle again in the next
//! cell. A mailbox ([`rt_core::Mailbox`]) remembers the last few triangles this ray tested:
//! skip those (and report each skip as `stats.mailbox_skip()`), unless `params.no_mailbox`.
//! Report each triangle tested as `stats.prim_test()`.

use crate::{LabHGrid, step3};
use rt_core::{Mailbox, Primitive, Ray, RayQuery, Stats};
use std::ops::ControlFlow;

/// How many recently tested triangles a ray remembers.
pub const MAILBOX: usize = 8;

/// Tests the triangles of the cell, `ids`, against the ray up to `query.t_far()` and offers
/// `query` each hit; `Break` when the query ends the walk. Skips (and reports) the triangles
/// the mailbox has seen, unless the mailbox is off.
pub fn test_cell<Q: RayQuery, S: Stats>(
    lab: &LabHGrid,
    ids: &[u32],
    ray: &Ray,
    query: &mut Q,
    mailbox: &mut Mailbox<MAILBOX>,
    stats: &mut S,
) -> ControlFlow<()> {
    // BEGIN SOLUTION step 4: testing a cell
    for &id in ids {
        if !lab.params.no_mailbox && mailbox.check_and_insert(id) {
            stats.mailbox_skip();
            continue;
        }
        stats.prim_test();
        if let Some(h) = lab.tris[id as usize].intersect(ray, query.t_far()) {
            query.offer(id, h)?;
        }
    }
    ControlFlow::Continue(())
    // END SOLUTION
}

/// The walk for `query`: every hit in `[ray.t_min, query.t_far()]` offered to it, until it
/// stops the walk.
pub fn walk<Q: RayQuery, S: Stats>(lab: &LabHGrid, ray: &Ray, query: &mut Q, stats: &mut S) {
    // BEGIN SOLUTION step 4: the walk for a query
    let mut mailbox = Mailbox::new();
    step3::walk(lab, ray, stats, |ids, _, _, stats| {
        match test_cell(lab, ids, ray, query, &mut mailbox, stats) {
            ControlFlow::Break(()) => f32::NEG_INFINITY,
            ControlFlow::Continue(()) => query.t_far(),
        }
    });
    // END SOLUTION
}

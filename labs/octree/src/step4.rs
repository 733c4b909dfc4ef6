//! Step 4: the closest hit, and when the walk may stop.
//!
//! Test the triangles of each leaf the walk reaches, keeping the best hit by the tie rule
//! ([`Hit::beats`]: smaller `t`, then smaller index), and give the walk the best `t` so far as
//! its limit. The trap, as in a grid or a kd-tree: the octree lists a triangle in every leaf its
//! surface overlaps, so a triangle can be hit *beyond* the current leaf while a closer one waits
//! in the next leaf. Stopping at the first leaf with a hit returns the wrong one; the limit lets
//! the walk go on to every leaf that starts before the best hit, and no further.
//!
//! The same listing in several leaves means a ray meets the same triangle again in the next
//! leaf. A mailbox ([`rt_core::Mailbox`]) remembers the last few triangles this ray tested:
//! skip those (and report each skip as `stats.mailbox_skip()`), unless `params.no_mailbox`.
//! Report each triangle tested as `stats.prim_test()`.

use crate::{LabOctree, Node, step3};
use rt_core::{Hit, Mailbox, Primitive, Ray, Stats};

/// How many recently tested triangles a ray remembers.
pub const MAILBOX: usize = 8;

/// Tests the triangles of leaf `node` against the ray up to `best.t`, updating `best` by the
/// tie rule; skips (and reports) those the mailbox has seen, unless the mailbox is off.
pub fn test_leaf<S: Stats>(
    lab: &LabOctree,
    node: &Node,
    ray: &Ray,
    best: &mut Hit,
    mailbox: &mut Mailbox<MAILBOX>,
    stats: &mut S,
) {
    todo!("step 4: testing a leaf")
}

/// The closest hit along the ray (ties to the smaller index), or `None`.
pub fn closest_hit<S: Stats>(lab: &LabOctree, ray: &Ray, stats: &mut S) -> Option<Hit> {
    todo!("step 4: the closest hit")
}

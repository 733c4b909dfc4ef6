//! Step 4: the closest hit, and when the walk may stop.
//!
//! Test the triangles of each cell the walk reaches, keeping the best hit by the tie rule
//! ([`Hit::beats`]: smaller `t`, then smaller index), and give the walk the best `t` so far as
//! its limit. The trap, as in the uniform grid: a triangle is listed in every cell its surface
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
use rt_core::{Hit, Mailbox, Primitive, Ray, Stats};

/// How many recently tested triangles a ray remembers.
pub const MAILBOX: usize = 8;

/// Tests the triangles `ids` against the ray up to `best.t`, updating `best` by the tie rule;
/// skips (and reports) those the mailbox has seen, unless the mailbox is off.
pub fn test_cell<S: Stats>(
    lab: &LabHGrid,
    ids: &[u32],
    ray: &Ray,
    best: &mut Hit,
    mailbox: &mut Mailbox<MAILBOX>,
    stats: &mut S,
) {
    // BEGIN SOLUTION step 4: testing a cell
    for &id in ids {
        if !lab.params.no_mailbox && mailbox.check_and_insert(id) {
            stats.mailbox_skip();
            continue;
        }
        stats.prim_test();
        if let Some(h) = lab.tris[id as usize].intersect(ray, best.t)
            && Hit::beats(h.t, id, best.t, best.prim)
        {
            *best = Hit {
                prim: id,
                t: h.t,
                u: h.u,
                v: h.v,
            };
        }
    }
    // END SOLUTION
}

/// The closest hit along the ray (ties to the smaller index), or `None`.
pub fn closest_hit<S: Stats>(lab: &LabHGrid, ray: &Ray, stats: &mut S) -> Option<Hit> {
    // BEGIN SOLUTION step 4: the closest hit
    let mut best = Hit {
        prim: u32::MAX,
        t: ray.t_max,
        u: 0.0,
        v: 0.0,
    };
    let mut mailbox = Mailbox::new();
    step3::walk(lab, ray, stats, |ids, _, _, stats| {
        test_cell(lab, ids, ray, &mut best, &mut mailbox, stats);
        best.t
    });
    (best.prim != u32::MAX).then_some(best)
    // END SOLUTION
}

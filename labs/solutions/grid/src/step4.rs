//! Step 4: the closest hit, and when the walk may stop.
//!
//! Test the triangles of each cell the walk visits, keeping the best hit by the tie rule
//! ([`Hit::beats`]: smaller `t`, then smaller index). The trap: a triangle spanning several
//! cells can be hit *beyond* the current cell while a closer triangle waits in the next cell.
//! So a hit ends the walk only if it lies inside the cell just tested; otherwise keep it as the
//! best so far and walk on. Allow for rounding: a closer triangle in the next cell can report a
//! `t` a few units in the last place below a hit on this cell's exit, so walk on until the exit
//! lies beyond the best hit widened by [`SLAB_FAR_SCALE`](rt_core::SLAB_FAR_SCALE)
//! (`t_exit > best.t * SLAB_FAR_SCALE`).
//!
//! Rays outside the trait's precondition ([`Ray::is_valid`] false: NaN, infinite, zero
//! direction) must return `None` at once, visiting nothing.

use crate::{LabGrid, step1, step3, step6};
use rt_core::{Hit, Primitive, Ray, Stats};

/// Tests the triangles of `cell` against the ray up to `best.t`, updating `best`. With `any`,
/// returns `true` at the first hit instead. Each test is reported to `stats`; with mailboxes
/// on, a triangle this ray tested before is skipped (step 6) and reported as a mailbox skip.
pub fn test_cell<S: Stats>(
    grid: &LabGrid,
    cell: [u32; 3],
    ray: &Ray,
    best: &mut Hit,
    mailbox: &mut step6::RayMailbox,
    any: bool,
    stats: &mut S,
) -> bool {
    // BEGIN SOLUTION step 4: testing one cell
    for &id in grid.cell(cell) {
        if grid.params.mailbox && mailbox.seen(id) {
            stats.mailbox_skip();
            continue;
        }
        stats.prim_test();
        let tri = &grid.tris[id as usize];
        if any {
            if tri.occludes(ray, best.t) {
                best.prim = id;
                return true;
            }
        } else if let Some(h) = tri.intersect(ray, best.t)
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
    false
    // END SOLUTION
}

/// The closest hit along the ray (ties to the smaller index), or `None`.
pub fn closest_hit<S: Stats>(grid: &LabGrid, ray: &Ray, stats: &mut S) -> Option<Hit> {
    // BEGIN SOLUTION step 4: the closest hit
    if !ray.is_valid() || grid.refs.is_empty() {
        return None;
    }
    let (t0, t1) = step1::slab(&grid.bounds, ray, ray.t_max)?;
    let mut best = Hit {
        prim: u32::MAX,
        t: ray.t_max,
        u: 0.0,
        v: 0.0,
    };
    let mut mailbox = step6::RayMailbox::new();
    step3::walk(grid, ray, t0, t1, |cell, _, t_exit| {
        stats.node_visit();
        test_cell(grid, cell, ray, &mut best, &mut mailbox, false, stats);
        best.prim != u32::MAX && t_exit > best.t * rt_core::SLAB_FAR_SCALE
    });
    (best.prim != u32::MAX).then_some(best)
    // END SOLUTION
}

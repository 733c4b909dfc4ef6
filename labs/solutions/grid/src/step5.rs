//! Step 5: the any-hit query, for shadow rays.
//!
//! A shadow ray only asks whether anything lies in `[t_min, t_max]`: the first hit found in
//! any cell answers it, so no ordering rule is needed and the walk stops at once.

use crate::{LabGrid, step1, step3, step4, step6};
use rt_core::{Hit, Ray, Stats};

/// Whether anything is hit in the ray's interval; stops at the first hit found.
pub fn any_hit<S: Stats>(grid: &LabGrid, ray: &Ray, stats: &mut S) -> bool {
    // BEGIN SOLUTION step 5: the any-hit walk
    if !ray.is_valid() || grid.refs.is_empty() {
        return false;
    }
    let Some((t0, t1)) = step1::slab(&grid.bounds, ray, ray.t_max) else {
        return false;
    };
    let mut best = Hit {
        prim: u32::MAX,
        t: ray.t_max,
        u: 0.0,
        v: 0.0,
    };
    let mut mailbox = step6::RayMailbox::new();
    let mut found = false;
    step3::walk(grid, ray, t0, t1, |cell, _, _| {
        stats.node_visit();
        found = step4::test_cell(grid, cell, ray, &mut best, &mut mailbox, true, stats);
        found
    });
    found
    // END SOLUTION
}

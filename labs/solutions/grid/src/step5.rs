//! Step 5: the any-hit query, for shadow rays.
//!
//! A shadow ray only asks whether anything lies in `[t_min, t_max]`: its query
//! ([`AnyHit`](rt_core::AnyHit)) is an occlusion query ([`RayQuery::OCCLUSION`]), which takes
//! the first hit found in any cell, so no ordering rule is needed and the walk stops at once.
//! It needs no `t`, `u` or `v` either: test with the yes-or-no [`Primitive::occludes`] (up to
//! `query.t_far()`) and offer the query the first triangle that blocks as [`BLOCKS`].

use crate::{LabGrid, step1, step3, step6};
use rt_core::query::BLOCKS;
use rt_core::{Primitive, Ray, RayQuery, Stats};

/// The occlusion walk for `query`: the first triangle that blocks the ray within
/// `[t_min, query.t_far()]` is offered to it, and ends the walk.
pub fn any_hit<Q: RayQuery, S: Stats>(grid: &LabGrid, ray: &Ray, query: &mut Q, stats: &mut S) {
    // BEGIN SOLUTION step 5: the any-hit walk
    if !ray.is_valid() || grid.refs.is_empty() {
        return;
    }
    let Some((t0, t1)) = step1::slab(&grid.bounds, ray, query.t_far()) else {
        return;
    };
    let mut mailbox = step6::RayMailbox::new();
    step3::walk(grid, ray, t0, t1, |cell, _, _| {
        stats.node_visit();
        for &id in grid.cell(cell) {
            if grid.params.mailbox && mailbox.seen(id) {
                stats.mailbox_skip();
                continue;
            }
            stats.prim_test();
            if grid.tris[id as usize].occludes(ray, query.t_far()) {
                let _ = query.offer(id, BLOCKS);
                return true;
            }
        }
        false
    });
    // END SOLUTION
}

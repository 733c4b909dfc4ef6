//! Step 5: the any-hit query.
//!
//! A shadow ray only asks whether anything blocks it: its query ([`AnyHit`](rt_core::AnyHit))
//! is an occlusion query ([`RayQuery::OCCLUSION`]). The first triangle found that blocks the
//! ray ([`Primitive::occludes`] within `[t_min, query.t_far()]`, which needs no `t`, `u` or
//! `v`) is offered to it as [`BLOCKS`] and ends the walk, whichever leaf it
//! lies in and wherever along the ray. The walk of step 3 is all you need: a limit of
//! `f32::NEG_INFINITY` ends it. Invalid rays walk
//! nothing.

use crate::{LabKdTree, step3};
use rt_core::query::BLOCKS;
use rt_core::{Primitive, Ray, RayQuery, Stats};

/// The occlusion walk for `query`: the first triangle that blocks the ray within
/// `[t_min, query.t_far()]` is offered to it, and ends the walk.
pub fn any_hit<Q: RayQuery, S: Stats>(lab: &LabKdTree, ray: &Ray, query: &mut Q, stats: &mut S) {
    // BEGIN SOLUTION step 5: the any hit
    if !ray.is_valid() || lab.tree.references().is_empty() {
        return;
    }
    let Some((t0, t1)) = lab.tree.bounds().intersect(ray, query.t_far()) else {
        return;
    };
    let mut hit = false;
    step3::walk(lab, ray, t0, t1, stats, |leaf, _, _, stats| {
        for &id in lab.leaf_ids(leaf) {
            stats.prim_test();
            if lab.tris[id as usize].occludes(ray, query.t_far()) {
                let _ = query.offer(id, BLOCKS);
                hit = true;
                break;
            }
        }
        if hit {
            f32::NEG_INFINITY
        } else {
            f32::INFINITY
        }
    });
    // END SOLUTION
}

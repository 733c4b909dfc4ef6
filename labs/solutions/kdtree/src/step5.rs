//! Step 5: the any-hit query.
//!
//! A shadow ray only asks whether anything blocks it: the first triangle found that does
//! ([`Primitive::occludes`] within the ray's whole interval) ends the walk, whichever leaf it
//! lies in and wherever along the ray. The walk of step 3 is all you need: a limit of
//! `f32::NEG_INFINITY` ends it. Invalid rays return
//! `false` at once.

use crate::{LabKdTree, step3};
use rt_core::{Primitive, Ray, Stats};

/// Whether any triangle is hit within the ray's interval.
pub fn any_hit<S: Stats>(lab: &LabKdTree, ray: &Ray, stats: &mut S) -> bool {
    // BEGIN SOLUTION step 5: the any hit
    if !ray.is_valid() || lab.tree.references().is_empty() {
        return false;
    }
    let Some((t0, t1)) = lab.tree.bounds().intersect(ray, ray.t_max) else {
        return false;
    };
    let mut hit = false;
    step3::walk(lab, ray, t0, t1, stats, |leaf, _, _, stats| {
        for &id in lab.leaf_ids(leaf) {
            stats.prim_test();
            if lab.tris[id as usize].occludes(ray, ray.t_max) {
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
    hit
    // END SOLUTION
}

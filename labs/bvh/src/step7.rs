//! Step 7: ray packets.
//!
//! Neighbouring camera rays (an 8×8 tile of pixels), and shadow rays from neighbouring points
//! towards one light, travel nearly together: they enter mostly the same boxes and test mostly
//! the same triangles. A packet walk (Wald, Boulos & Shirley 2007, "Ray tracing deformable
//! scenes using dynamic bounding volume hierarchies") takes up to 64 such rays down the tree at
//! once: one stack, one fetch of each node for all of them, and with each stack entry the mask
//! of the lanes that reach it. The rays come as a [`Bundle`]: all of one direction octant, in
//! structure-of-arrays form, with bounds over the lanes. Each lane keeps its own best hit in
//! [`Lanes`], and at a leaf each triangle is tested against the lanes of the mask, each with its
//! own single-ray arithmetic, so that every lane's answer is exactly its single ray's: the
//! same triangle and the same bits of `t`, `u`, `v` (the kit checks it, bit for bit).
//!
//! What a packet walk must get right is which lanes enter a box. It may take along lanes that
//! do not enter (they test triangles they cannot hit: slower, still exact), but it must never
//! drop a lane that does. Three tests, cheapest first:
//! 1. The first active lane's own slab test ([`Bundle::lane_enters`]). Coherent lanes mostly
//!    enter together, so when it enters, take every active lane along: one lane's test decides
//!    for the packet, the "first active lane" rule of Wald et al.
//! 2. Otherwise an interval bound over all the lanes ([`Bundle::may_enter`]): from the smallest
//!    and largest origins and reciprocal directions, a box that no lane can enter is ruled out
//!    in one test. Read its documentation for why it is safe under rounding.
//! 3. Otherwise each lane's own slab test ([`Bundle::lanes_entering`]): exactly the lanes that
//!    enter, eight per vector step.
//!
//! A lane's `t_max` is its best hit so far ([`Lanes::t`], [`Lanes::best_t`]), and
//! [`Lanes::far_end`] is the largest of them, which bounds every lane's.
//!
//! `src/lib.rs` hands your walk the bundles (`rt_simd::bundle::walk_groups`): it sorts the
//! rays of a call into bundles, answers at once a bundle that misses the root's box, sends
//! rays that cannot travel together (a zero direction component, directions far apart) down
//! your single-ray walk of steps 4 and 5, and writes every lane's answer back in its slot.

use crate::{LabBvh, MAX_DEPTH, step3};
use rt_core::{Aabb, Stats};
use rt_simd::Bundle;
use rt_simd::bundle::Lanes;

/// The lanes of `active` that may enter `bounds`, each lane up to its best hit so far: all of
/// `active` when its first lane enters (test 1 above); none when the interval bound rules the
/// box out for every lane (test 2); else exactly the lanes whose own slab test enters (test 3).
/// `0` when `active` is `0`. Never leaves out a lane of `active` that enters.
pub fn enter(b: &Bundle, lanes: &Lanes, bounds: &Aabb, active: u64) -> u64 {
    todo!("step 7: which lanes enter a box")
}

/// Takes bundle `b` through the tree. For the closest hit (`ANY` false), each lane's best hit
/// is kept in `lanes` ([`Lanes::intersect`]); for the any-hit query (`ANY` true), the lanes a
/// triangle blocks are marked in `lanes` ([`Lanes::occluded`] returns them), a blocked lane
/// stops, and the walk ends when every lane is blocked.
///
/// Keep on the stack each node with the lanes that reached it, and at a pop narrow them to
/// those that enter its box ([`enter`]); visit the children nearest first for the first of
/// those lanes (step 3, with that lane as a ray: [`Bundle::ray`]). Report one
/// [`Stats::node_visit`] per node the packet enters, whatever its number of lanes, with
/// [`Stats::bundle_lanes`] (the lanes `b` carries, the lanes that entered); [`Lanes`] counts
/// the triangle tests, one per lane.
pub fn walk<S: Stats, const ANY: bool>(bvh: &LabBvh, b: &Bundle, lanes: &mut Lanes, stats: &mut S) {
    todo!("step 7: the packet walk")
}

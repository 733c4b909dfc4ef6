//! Step 2: the cells beside the path.
//!
//! The DDA leaves a cell through the boundary it reaches first. When the ray crosses two
//! boundaries at nearly the same parameter (near an edge or a corner of the cell), rounding may
//! pick the wrong one first, and the walk then skips a sliver of a cell the ray really passes
//! through. So at each exit, the cells beside the path are visited too: each cell one step away
//! on the other axes whose boundaries are crossed within rounding of the exit
//! ([`crate::Dda::side_cells`] lists them: empty almost always, up to three next to a
//! corner). Such a cell is grazed for an instant at the exit parameter, so it is tested by its
//! whole list ([`step1::grazed_ids`]): a parent cell's, rather than walking its nested grid.
//!
//! The kit's `lattice` scene and step 4's test of rays grazing cell edges from 10⁴ away fail
//! without them.

use crate::step1::{self, Walk};
use crate::{LabHGrid, RayAxes};
use rt_core::Stats;

/// Visits the cells beside the path of `walk` at its exit through `axis`, at parameter
/// `t_exit`: for each, reports a node visit to `stats` and calls `visit(ids, t_exit, t_exit,
/// stats)` with its grazed triangles. Returns the smallest limit `visit` returned
/// (`f32::INFINITY` if no cell is beside the path).
pub fn beside<S: Stats>(
    lab: &LabHGrid,
    walk: &Walk,
    r: &RayAxes,
    axis: usize,
    t_exit: f32,
    stats: &mut S,
    visit: &mut impl FnMut(&[u32], f32, f32, &mut S) -> f32,
) -> f32 {
    // BEGIN SOLUTION step 2: the cells beside the path
    let shape = &lab.grid.levels()[walk.level].shape;
    let mut limit = f32::INFINITY;
    for c in walk.dda.side_cells(shape, r, axis) {
        stats.node_visit();
        let cell = step1::cell(lab, walk.level, c);
        limit = limit.min(visit(step1::grazed_ids(lab, &cell), t_exit, t_exit, stats));
    }
    limit
    // END SOLUTION
}

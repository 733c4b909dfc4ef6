//! Box queries (box overlap) over a grid: the block of cells the query box covers.

use crate::{Grid, GridShape};
use rt_core::{Aabb, BoxQuery, Primitive, Stats, Visited, leaf};
use std::ops::ControlFlow;

/// Calls `visit` for each cell of `shape` whose box meets `b` (closed boxes), in memory order,
/// until it returns `Break`.
///
/// Boxes meet when they meet on every axis, so the cells are a block: on each axis, the cells
/// from the one of `b`'s lower end to the one of its upper end, moved by the planes themselves
/// (a corner on a plane, or within rounding of one, may be placed in the cell beyond it, and the
/// cell before it still touches `b`).
///
/// The hierarchical grid runs it on each nested grid too.
pub fn cells_meeting(
    shape: &GridShape,
    b: &Aabb,
    mut visit: impl FnMut([u32; 3]) -> ControlFlow<()>,
) -> ControlFlow<()> {
    if b.is_empty() || !shape.bounds().overlaps(b) {
        return ControlFlow::Continue(());
    }
    let res = shape.resolution_per_axis();
    let mut lo = [0u32; 3];
    let mut hi = [0u32; 3];
    for a in 0..3 {
        // Cell k spans [plane(k), plane(k + 1)] and meets b when plane(k) <= max and
        // min <= plane(k + 1).
        let (mut l, mut h) = (shape.cell_of(a, b.min[a]), shape.cell_of(a, b.max[a]));
        while l > 0 && shape.plane(a, l) >= b.min[a] {
            l -= 1;
        }
        while l < h && shape.plane(a, l + 1) < b.min[a] {
            l += 1;
        }
        while h + 1 < res[a] && shape.plane(a, h + 1) <= b.max[a] {
            h += 1;
        }
        while h > l && shape.plane(a, h) > b.max[a] {
            h -= 1;
        }
        (lo[a], hi[a]) = (l, h);
    }
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                visit([x, y, z])?;
            }
        }
    }
    ControlFlow::Continue(())
}

impl<P: Primitive> Grid<P> {
    /// The box query: [`cells_meeting`], offering each primitive once however many of the cells
    /// list it ([`Visited`]: a box covers many cells, and a few mailbox slots would forget).
    pub(crate) fn box_cells<Q: BoxQuery<P>, S: Stats>(
        &self,
        q: &mut Q,
        stats: &mut S,
    ) -> ControlFlow<()> {
        if self.refs.is_empty() {
            return ControlFlow::Continue(());
        }
        Visited::with(self.prims.len(), |seen| {
            cells_meeting(&self.shape, &q.bounds(), |c| {
                stats.node_visit();
                let i = self.shape.index(c);
                let ids = &self.refs[self.cells[i] as usize..self.cells[i + 1] as usize];
                leaf::offer_once(&self.prims, ids, seen, q, stats)
            })
        })
    }
}

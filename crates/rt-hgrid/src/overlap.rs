//! Box queries (box overlap): the cells the query box covers, level by level.

use crate::HGrid;
use rt_core::{BoxQuery, Primitive, Stats, Visited, leaf};
use rt_grid::overlap::cells_meeting;
use std::ops::ControlFlow;

impl<P: Primitive> HGrid<P> {
    /// The box query: the top grid's cells that meet the query box ([`cells_meeting`]); a cell
    /// with a nested grid is searched the same way. The recursion is as deep as the hierarchy
    /// (at most [`MAX_LEVELS`](crate::MAX_LEVELS)). Each primitive is offered once, however many
    /// cells list it ([`Visited`]).
    pub(crate) fn box_cells<Q: BoxQuery<P>, S: Stats>(
        &self,
        q: &mut Q,
        stats: &mut S,
    ) -> ControlFlow<()> {
        if self.refs.is_empty() {
            return ControlFlow::Continue(());
        }
        Visited::with(self.prims.len(), |seen| self.box_level(0, q, stats, seen))
    }

    fn box_level<Q: BoxQuery<P>, S: Stats>(
        &self,
        level: usize,
        q: &mut Q,
        stats: &mut S,
        seen: &mut Visited,
    ) -> ControlFlow<()> {
        let grid = &self.levels[level];
        cells_meeting(&grid.shape, &q.bounds(), |c| {
            stats.node_visit();
            let cell = self.cells[grid.first_cell + grid.shape.index(c)];
            if let Some(nested) = cell.nested() {
                return self.box_level(nested, q, stats, seen);
            }
            leaf::offer_once(&self.prims, &self.refs[cell.references()], seen, q, stats)
        })
    }
}

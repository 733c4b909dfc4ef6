//! The grid's cells as [`Region`]s, for drawings of the structure.

use crate::Grid;
use rt_core::Region;

impl<P> Grid<P> {
    /// Every cell, in memory order (x fastest), each with its reference count (see
    /// [`rt_core::Accel::regions`]); all at depth 0.
    pub(crate) fn walk_regions(&self, visit: &mut dyn FnMut(Region)) {
        if self.cells.len() < 2 {
            return;
        }
        for i in 0..self.shape.cell_count() {
            visit(Region {
                bounds: self.shape.cell_box(self.shape.coords(i)),
                depth: 0,
                prims: Some(self.cells[i + 1] - self.cells[i]),
                split: None,
            });
        }
    }
}

//! The hierarchy's cells as [`Region`]s, for drawings of the structure.

use crate::HGrid;
use rt_core::Region;

impl<P> HGrid<P> {
    /// Every cell of every grid, each parent cell before the cells of its nested grid (see
    /// [`rt_core::Accel::regions`]): a leaf cell with its reference count, a refined cell as an
    /// interior region; a nested grid's cells one level deeper.
    pub(crate) fn walk_regions(&self, visit: &mut dyn FnMut(Region)) {
        if self.levels.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(l) = stack.pop() {
            let level = &self.levels[l];
            let mut nested = Vec::new();
            for i in 0..level.shape.cell_count() {
                let cell = self.cells[level.first_cell + i];
                let child = cell.nested();
                visit(Region {
                    bounds: level.shape.cell_box(level.shape.coords(i)),
                    depth: level.depth,
                    prims: child.is_none().then(|| cell.references().len() as u32),
                    split: None,
                });
                nested.extend(child);
            }
            stack.extend(nested.into_iter().rev());
        }
    }
}

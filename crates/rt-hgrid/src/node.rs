//! The hierarchical grid's cells and levels.

use rt_grid::GridShape;

rt_core::pod_struct! {
    /// One cell: a range of primitive references, or a nested grid. 8 bytes.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct Cell {
        /// First reference of a leaf; the nested grid's index for a parent cell.
        first: u32,
        /// Number of references, or [`Cell::PARENT`].
        count: u32,
    }
}

const _: () = assert!(size_of::<Cell>() == 8);

impl Cell {
    /// The `count` field of a cell with a nested grid.
    const PARENT: u32 = u32::MAX;

    /// A cell listing `refs[first..first + count]`.
    pub(crate) fn leaf(first: usize, count: usize) -> Self {
        Self {
            first: u32::try_from(first).expect("at most 2^32 - 1 references"),
            count: u32::try_from(count)
                .ok()
                .filter(|&c| c != Self::PARENT)
                .expect("at most 2^32 - 2 references in a cell"),
        }
    }

    /// A cell holding the nested grid `grid`.
    pub(crate) fn parent(grid: usize) -> Self {
        Self {
            first: u32::try_from(grid).expect("at most 2^32 - 1 grids"),
            count: Self::PARENT,
        }
    }

    /// The nested grid's index, if the cell has one.
    #[inline(always)]
    pub fn nested(&self) -> Option<usize> {
        (self.count == Self::PARENT).then_some(self.first as usize)
    }

    /// The reference range of a leaf cell (empty for a parent cell).
    #[inline(always)]
    pub fn references(&self) -> std::ops::Range<usize> {
        if self.count == Self::PARENT {
            0..0
        } else {
            self.first as usize..self.first as usize + self.count as usize
        }
    }
}

/// One grid of the hierarchy: its shape, where its cells start, and (for a nested grid) the
/// references of the parent cell it refines, which a walk tests when it only grazes that cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Level {
    /// The grid's box and resolution; a nested grid's box is its parent cell's.
    pub shape: GridShape,
    /// Its cells are `cells[first_cell..first_cell + shape.cell_count()]`.
    pub first_cell: usize,
    /// The parent cell's references, `refs[all.0..all.1]` (empty for the top grid).
    pub all: (usize, usize),
    /// 0 for the top grid.
    pub depth: u32,
}

//! Step 1: the hierarchy's cells, and a walk started in one grid.
//!
//! All cells of all grids sit in one array, [`rt_hgrid::HGrid::cells`]: grid `g`'s cells start
//! at `levels()[g].first_cell`, in the order [`crate::GridShape::index`] gives a cell's
//! coordinates (x fastest). A cell either lists triangles (`cell.references()`, a range of
//! [`rt_hgrid::HGrid::references`]) or holds a nested grid (`cell.nested()`, an index into
//! `levels()`), a grid of its own over exactly that cell's box.
//!
//! A parent cell keeps its own list too: the triangles of its whole nested grid,
//! `references()[all.0..all.1]` where `all` is the nested grid's [`crate::Level::all`]. A walk
//! that only grazes the cell (step 2's cells beside the path) tests that list instead of
//! walking the nested grid for an instant.
//!
//! Walking one grid is the uniform grid's 3D-DDA, given here as `rt-grid`'s [`Dda`] (the grid
//! lab's step 3): [`Dda::start`] finds the cell where the ray is at a parameter `t` inside the
//! grid's box, [`Dda::exit`] the axis and parameter where it leaves the current cell, and
//! [`Dda::step`] moves to the next cell (false when that leaves the grid).

use crate::{Cell, Dda, LabHGrid, RayAxes};

/// One grid's walk in progress.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    /// The grid's index in `levels()`.
    pub level: usize,
    /// The DDA through it.
    pub dda: Dda,
    /// Where the ray enters the current cell.
    pub t_enter: f32,
    /// Whether the current cell was visited already (tested, or its nested grid walked).
    pub visited: bool,
}

/// The cell with coordinates `cell` of grid `level`.
pub fn cell(lab: &LabHGrid, level: usize, cell: [u32; 3]) -> Cell {
    todo!("step 1: a cell of a grid")
}

/// The triangles to test for a cell the walk only grazes: a leaf cell's own list, or for a
/// parent cell the list of its whole nested grid.
pub fn grazed_ids<'a>(lab: &'a LabHGrid, cell: &Cell) -> &'a [u32] {
    todo!("step 1: a grazed cell's triangles")
}

/// The walk through grid `level` of a ray (`r`) that is inside that grid's box at parameter
/// `t`: a DDA started there, its current cell entered at `t` and not visited yet.
pub fn enter(lab: &LabHGrid, level: usize, r: &RayAxes, t: f32) -> Walk {
    todo!("step 1: a walk started in a grid")
}

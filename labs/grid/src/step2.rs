//! Step 2: how many cells, and which triangles go in each.
//!
//! Resolution: Cleary & Wyvill's rule, as in pbrt-v1 and Wald's grid papers: about
//! `density × N` cells, as close to cubes as the box allows. With `V` the box's volume, a cube
//! cell has side `s = ∛(V / (density · N))`, and axis `a` gets `⌈extent_a / s⌉` cells (at least
//! 1, and at most [`MAX_RES`]). A flat axis (extent 0) gets one cell; then compute the side from
//! the area (or length) of the other axes instead.
//!
//! Build: each valid triangle goes into every cell its bounding box overlaps (conservative: a
//! cell may list a triangle that only its box touches; that costs tests, never answers). Pad
//! the triangle's box by a small fraction of the scene's size so that a triangle lying on a
//! cell boundary is listed on both sides: rays are walked through one side or the other by
//! rounding. Store the lists as one array: count per cell, prefix sums into `cells`, then fill
//! `refs` (a counting sort).

use crate::LabGrid;
use rt_core::{Aabb, Primitive};

/// The most cells along one axis.
pub const MAX_RES: u32 = 128;

/// Cells per axis for `n` triangles in `bounds` with `density` cells per triangle; each entry
/// in `1..=MAX_RES`. An empty or invalid box gets `[1, 1, 1]`.
pub fn resolution(bounds: &Aabb, n: usize, density: f32) -> [u32; 3] {
    todo!("step 2: the resolution")
}

/// The cell lists of `grid` (whose `bounds`, `res`, `inv_cell` and `tris` are set): the
/// offsets `cells` (one per cell, plus one) and the triangle indices `refs`.
pub fn fill_cells(grid: &LabGrid) -> (Vec<u32>, Vec<u32>) {
    todo!("step 2: the build")
}

//! Step 3: the walk through the cells a ray crosses, in order (a 3D-DDA).
//!
//! Find the cell where the ray enters the grid (at `t0`, from step 1). Per axis, the ray moves
//! to the next cell when it crosses the next cell boundary in its direction (`plane(a, c + 1)`
//! going up, `plane(a, c)` going down, never for a zero direction component). The current
//! cell ends at the first of the three crossings, `t_exit`; step along that axis, and stop when
//! the walk leaves the grid or passes `t1`. Compute each crossing from the plane's coordinate
//! ([`LabGrid::plane`]), not by adding up step lengths, so rounding does not pile up.
//!
//! Rounding still bites when the origin is far away: from 10¹², the parameter's rounding step
//! (131,072) is larger than a small grid, so every plane is crossed at the same rounded `t`,
//! and the rounded entry point may lie cells away from the truth. Start in the first cell
//! along the ray that the ray leaves at or after `t0`, and do not stop at a crossing equal to
//! `t1`, or the walk skips cells (the kit's `far_origins` scene).

use crate::LabGrid;
use rt_core::Ray;

/// Calls `visit(cell, t_enter, t_exit)` for each cell the ray crosses between `t0` and `t1`
/// (where it is inside the grid's box), in order along the ray, until `visit` returns `true`
/// or the ray leaves the grid. `t_exit` is where the ray leaves the cell (at most `t1`).
pub fn walk(
    grid: &LabGrid,
    ray: &Ray,
    t0: f32,
    t1: f32,
    visit: impl FnMut([u32; 3], f32, f32) -> bool,
) {
    todo!("step 3: the walk")
}

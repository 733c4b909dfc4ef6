//! Step 3: the nested walk, front to back.
//!
//! Start a walk through the top grid (level 0) where the ray enters its box
//! ([`rt_core::Aabb::intersect`] of the top grid's box, up to `ray.t_max`); a ray that misses it
//! visits nothing. Keep the walks in progress on a stack, one per level (at most
//! [`MAX_LEVELS`]). Then repeat, with the top walk:
//!
//! - If its current cell is not visited yet, mark it visited and report a node visit. A cell
//!   with a nested grid: push a walk through that grid, started where the ray enters the cell,
//!   and go on with it. A leaf cell: `visit(ids, t_enter, t_exit, stats)` tests its triangles
//!   and returns the limit.
//! - Where does the ray leave the cell ([`crate::Dda::exit`])? If beyond the limit (times
//!   [`SLAB_FAR_SCALE`]) or beyond the top grid's exit, the walk is done: every cell after this
//!   one starts there or later, in this grid and in every grid below it on the stack.
//! - The cells beside the path at that exit (step 2); a limit below the exit ends the walk too.
//! - Step the DDA. If it leaves its grid, pop the walk: the grid below goes on from its own
//!   current cell, already visited (the nested grid was that cell). When the stack is empty the
//!   walk is done.
//!
//! No recursion and no allocation: the stack is an array of [`MAX_LEVELS`] walks.

use crate::step1::{self, Walk};
use crate::{LabHGrid, MAX_LEVELS, RayAxes, step2};
use rt_core::{Ray, SLAB_FAR_SCALE, Stats};

/// Walks the cells the ray passes through within `[ray.t_min, ray.t_max]`, nearest first,
/// calling `visit(ids, t_enter, t_exit, stats)` with each leaf cell's triangles and its
/// interval, and step 2's cells beside the path. `visit` returns a limit: the walk ends at the
/// first cell that starts beyond it (`f32::INFINITY` ends none, `f32::NEG_INFINITY` ends the
/// walk). Reports each cell visited (leaf, parent or beside the path) to `stats`. Invalid rays
/// ([`Ray::is_valid`] false) and an empty hierarchy visit nothing. (To call `visit`, rebind it
/// as mutable: `let mut visit = visit;`.)
pub fn walk<S: Stats>(
    lab: &LabHGrid,
    ray: &Ray,
    stats: &mut S,
    visit: impl FnMut(&[u32], f32, f32, &mut S) -> f32,
) {
    todo!("step 3: the nested walk")
}

//! Step 3: the walk over the leaves, front to back.
//!
//! Start at the root with the interval where the ray is inside the tree's box
//! ([`rt_core::Aabb::intersect`] on `tree.bounds()`, given to you by the caller). At an
//! interior node, step 2 says where to go: one child with the same interval, or the near child
//! now and the far child later. "Later" is a stack: push the far child with its interval
//! `[t, t1]`, and go on into the near child with `[t0, t]`, with `t` clamped to `[t0, t1]` first:
//! step 2 lets a plane within rounding of an end through, and an interval must not run
//! backwards. At a leaf, call `visit`: it returns a limit, the distance beyond which nothing
//! can matter any more (step 4's best hit so far). Then pop far children, skipping each that
//! starts beyond the limit (with step 2's margin: beyond `limit * SLAB_FAR_SCALE`), and go on
//! from the first that does not; when the stack is empty, the walk ends.
//!
//! No recursion and no allocation: the stack is an array of [`MAX_DEPTH`] entries, enough
//! because a path from the root pushes at most one far child per level and the builder keeps
//! the tree within that depth.

use crate::step2::{self, Visit};
use crate::{LabKdTree, MAX_DEPTH, Node};
use rt_core::{Ray, SLAB_FAR_SCALE, Stats};

/// Walks the leaves the ray's interval `[t0, t1]` reaches, nearest first, calling
/// `visit(leaf, t0, t1, stats)` with each leaf's part of the interval. `visit` returns a limit:
/// leaves that start beyond it are skipped (`f32::INFINITY` skips none, `f32::NEG_INFINITY`
/// ends the walk). Reports each node entered (interior or leaf) to `stats`. (To call `visit`,
/// rebind it as mutable: `let mut visit = visit;`.)
pub fn walk<S: Stats>(
    lab: &LabKdTree,
    ray: &Ray,
    t0: f32,
    t1: f32,
    stats: &mut S,
    visit: impl FnMut(&Node, f32, f32, &mut S) -> f32,
) {
    todo!("step 3: the stack walk")
}

//! Step 3: the walk over the leaves, front to back.
//!
//! Start at the root, whose box is the tree's cube ([`rt_octree::Octree::bounds`]): its faces'
//! parameters (step 1) give the interval the ray spends inside it. A ray that misses the cube
//! (an interval empty by more than [`step2::widen`] allows), that leaves it before `t_from`, or
//! that enters it beyond `ray.t_max` (with [`SLAB_FAR_SCALE`] of rounding allowed) visits
//! nothing.
//!
//! Then walk with a stack of frames, one per interior node being walked: its box, its faces'
//! and mid-planes' parameters, its children in order (step 2) and which of them comes next.
//! Take the top frame's next child. If it starts beyond the limit (the best hit so far, times
//! [`SLAB_FAR_SCALE`]), so does every child after it in that frame: drop the frame. Otherwise
//! enter it: a leaf goes to `visit`, which tests it and returns the new limit; an interior node
//! gets a frame of its own on top, its faces from its parent's (step 2), its box from
//! [`crate::child_box`]. A frame whose children are all taken is dropped; the walk ends when no
//! frame is left.
//!
//! `t_from` is where the ray starts, `ray.t_min`, moved down by [`NEAR_TIE`] so that a child
//! ending exactly there, give or take rounding, is still visited. No recursion and no
//! allocation: the stack is an array with one frame per level ([`MAX_DEPTH`] levels below the
//! root).

use crate::step2::{self, Order};
use crate::{LabOctree, MAX_DEPTH, Node, step1};
use rt_core::glam::Vec3;
use rt_core::{NEAR_TIE, Ray, SLAB_FAR_SCALE, Stats};

/// One interior node being walked.
#[derive(Clone, Copy, Debug, Default)]
pub struct Frame {
    /// Its box.
    pub lo: Vec3,
    /// Its box.
    pub hi: Vec3,
    /// Its faces' parameters, in the ray's order.
    pub near: Vec3,
    /// Its faces' parameters, in the ray's order.
    pub far: Vec3,
    /// Its mid-planes' parameters.
    pub tm: Vec3,
    /// The index of its children's block.
    pub block: usize,
    /// Its children the ray passes through, in order.
    pub order: Order,
    /// Which of them comes next.
    pub next: usize,
}

/// Walks the leaves the ray passes through within `[ray.t_min, ray.t_max]`, nearest first,
/// calling `visit(leaf, entry, exit, stats)` with each leaf's interval. `visit` returns a
/// limit: leaves that start beyond it are skipped (`f32::INFINITY` skips none,
/// `f32::NEG_INFINITY` ends the walk). Reports each node entered (the root, interior nodes and
/// leaves) to `stats`. Invalid rays ([`Ray::is_valid`] false) and an empty tree visit nothing.
/// (To call `visit`, rebind it as mutable: `let mut visit = visit;`.)
pub fn walk<S: Stats>(
    lab: &LabOctree,
    ray: &Ray,
    stats: &mut S,
    visit: impl FnMut(&Node, f32, f32, &mut S) -> f32,
) {
    // BEGIN SOLUTION step 3: the stack walk
    let mut visit = visit;
    if !ray.is_valid() || lab.tree.references().is_empty() {
        return;
    }
    let r = step1::axes(ray);
    let cube = lab.tree.bounds();
    let (near, far) = step1::faces(&r, cube.min, cube.max);
    let (t_enter, t_exit) = (near.max_element(), far.min_element());
    let t_from = ray.t_min - ray.t_min.abs() * (NEAR_TIE - 1.0);
    if t_enter > step2::widen(t_exit) || t_exit < t_from || t_enter > ray.t_max * SLAB_FAR_SCALE {
        return;
    }
    let root = lab.tree.root();
    stats.node_visit();
    let Some(block) = root.children() else {
        visit(&root, t_enter, t_exit, stats);
        return;
    };
    let blocks = lab.tree.blocks();
    let frame = |lo: Vec3, hi: Vec3, (near, far): (Vec3, Vec3), block: usize| {
        let tm = step2::mid_params(&r, lo, hi);
        let order = step2::order(&r, (near, far), tm, &blocks[block], t_from);
        Frame {
            lo,
            hi,
            near,
            far,
            tm,
            block,
            order,
            next: 0,
        }
    };
    let mut stack = [Frame::default(); MAX_DEPTH as usize + 1];
    stack[0] = frame(cube.min, cube.max, (near, far), block);
    let mut len = 1;
    let mut limit = ray.t_max;
    while len > 0 {
        let f = stack[len - 1];
        if f.next == f.order.len {
            len -= 1;
            continue;
        }
        stack[len - 1].next += 1;
        let (i, entry, exit) = f.order.children[f.next];
        if entry > limit * SLAB_FAR_SCALE {
            len -= 1;
            continue;
        }
        let node = blocks[f.block].0[i as usize];
        stats.node_visit();
        match node.children() {
            None => limit = visit(&node, entry, exit, stats),
            Some(block) => {
                let (lo, hi) = crate::child_box(f.lo, f.hi, i);
                let faces = step2::child_faces(f.near, f.far, f.tm, i ^ r.neg);
                stack[len] = frame(lo, hi, faces, block);
                len += 1;
            }
        }
    }
    // END SOLUTION
}

//! Parametric front-to-back traversal (Revelles, Ureña & Lastra 2000).
//!
//! Everything is decided by ray parameters, never by points. For a node the walk computes, per
//! axis, the parameters where the ray meets the node's near face, its far face and its mid-plane
//! (one subtraction and one multiplication each, from the same plane coordinates the builder
//! cut at). A direction component that is negative is handled by mirroring: near and far swap on
//! that axis, and a child's index in the ray's order is XORed with the mask of negative axes to
//! give its index in the block. In the ray's order:
//!
//! - the first child is given by the entry parameter `t_enter` (the largest near-face parameter)
//!   and the mid-planes: bit `a` is set when the ray has crossed mid-plane `a` before entering;
//! - the next child is given by the exit plane: the axis whose plane comes first among the
//!   current child's far planes; if that is the node's own face the node is done, otherwise the
//!   bit of that axis is set (a child is followed by at most three others). A child's far planes
//!   are the node's far faces on its set axes and the mid-planes on the others, so this is the
//!   same as crossing the mid-planes still ahead in increasing order of their parameters, as
//!   long as they come before the node's exit; that is how it is computed, with three
//!   compare-exchanges per node instead of a minimum per step.
//!
//! A zero (or denormal) direction component gives no parameters on its axis: its slab is
//! `(-∞, +∞)`, the ray stays on the side of the mid-plane its origin is on (the upper side when
//! exactly on it, which is correct because boxes are closed and primitives touching a plane are
//! listed on both sides), and it never exits through that axis. Rays starting inside the octree
//! walk the same sequence; children ending before `t_min` are skipped.
//!
//! Exactness. Rounding can order two nearly simultaneous crossings wrongly, which would skip a
//! sliver of a cell the ray really passes through. Crossings within [`NEAR_TIE`] of each other
//! are therefore taken both ways: at a node's entry and at each exit, every child the other order
//! would visit is visited too (up to all eight; almost never more than the usual four). Ties
//! between a node's own faces are resolved the same way one level up, in the neighbours that
//! share the face, since they compute the same parameters from the same planes.
//!
//! The in-cell hit rule: a primitive may be hit beyond the leaf being tested (it spans several
//! cells) while a closer one waits in the next leaf; such a hit is kept as the best so far, and
//! the walk stops at the first child that starts beyond it (with [`SLAB_FAR_SCALE`] of rounding
//! allowed), which is the first valid hit. The children to visit go on a fixed stack, one frame
//! per level.

use crate::Octree;
use crate::builder::MAX_DEPTH;
use crate::node::{Block, Node};
use rt_core::glam::{BVec3A, Vec3A};
use rt_core::leaf::{self, Seen};
use rt_core::trace::{self, Event, Place};
use rt_core::{Aabb, NEAR_TIE, Primitive, Ray, RayQuery, SLAB_FAR_SCALE, Stack, Stats};

/// Mailbox slots per ray: the last this many primitives tested are not tested again.
pub(crate) const MAILBOX: usize = 8;

/// The frames of the walk: one per level below the root.
const STACK: usize = MAX_DEPTH as usize + 1;

/// The per-ray constants.
#[derive(Clone, Copy, Debug)]
struct RayAxes {
    o: Vec3A,
    inv: Vec3A,
    /// Axes the ray runs down (mirrored).
    neg: BVec3A,
    /// Axes with no usable reciprocal: zero or denormal direction components.
    flat: BVec3A,
    /// `neg` as a bit mask, to XOR a child's index in ray order into its index in the block.
    neg_bits: u32,
    flat_bits: u32,
}

impl RayAxes {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let inv = Vec3A::from(ray.inv_dir());
        let flat = !inv.is_finite_mask();
        let neg = Vec3A::from(ray.dir()).cmplt(Vec3A::ZERO) & !flat;
        Self {
            o: Vec3A::from(ray.origin),
            inv,
            neg,
            flat,
            neg_bits: neg.bitmask(),
            flat_bits: flat.bitmask(),
        }
    }

    /// The parameters of the near and the far face of box `[lo, hi]` per axis, in ray order;
    /// `(-∞, +∞)` on flat axes.
    #[inline(always)]
    fn slabs(&self, lo: Vec3A, hi: Vec3A) -> (Vec3A, Vec3A) {
        let t_lo = (lo - self.o) * self.inv;
        let t_hi = (hi - self.o) * self.inv;
        let near = Vec3A::select(self.neg, t_hi, t_lo);
        let far = Vec3A::select(self.neg, t_lo, t_hi);
        (
            Vec3A::select(self.flat, Vec3A::NEG_INFINITY, near),
            Vec3A::select(self.flat, Vec3A::INFINITY, far),
        )
    }
}

/// `t` widened upwards by the near-tie tolerance.
#[inline(always)]
fn widen(t: f32) -> f32 {
    t + t.abs() * (NEAR_TIE - 1.0)
}

/// Lane masks: `LANES[i]` has bit `a` of `i` on lane `a`.
const LANES: [BVec3A; 8] = {
    let mut t = [BVec3A::new(false, false, false); 8];
    let mut i = 0;
    while i < 8 {
        t[i] = BVec3A::new(i & 1 != 0, i & 2 != 0, i & 4 != 0);
        i += 1;
    }
    t
};

/// The mask with bit `a` of `bits` on lane `a`.
#[inline(always)]
fn lanes(bits: u32) -> BVec3A {
    LANES[(bits & 7) as usize]
}

/// Calls `f` with every non-empty subset of the bits of `mask`.
#[inline(always)]
fn for_each_subset(mask: u32, mut f: impl FnMut(u32)) {
    let mut sub = mask;
    while sub != 0 {
        f(sub);
        sub = (sub - 1) & mask;
    }
}

/// A node whose children are being walked: its box, its block, and the children still to visit
/// (block indices, four bits each, the next in the low bits).
#[derive(Clone, Copy, Debug)]
struct Frame {
    lo: Vec3A,
    hi: Vec3A,
    block: u32,
    order: u32,
    left: u32,
}

/// The children of the node with box `[lo, hi]` and face parameters `near`, `far` that the ray
/// visits, in the order it visits them, as block indices packed four bits each, and their count.
/// Empty leaves and children ending before `t_from` are left out; children the ray would visit
/// if near-simultaneous crossings were ordered the other way are put in (see the module doc).
#[inline(always)]
fn children_order(
    r: &RayAxes,
    lo: Vec3A,
    hi: Vec3A,
    (near, far): (Vec3A, Vec3A),
    block: &Block,
    t_from: f32,
) -> (u32, u32) {
    let mid = lo * 0.5 + hi * 0.5;
    let t_mid = Vec3A::select(r.flat, Vec3A::INFINITY, (mid - r.o) * r.inv);
    let t_enter = near.max_element();
    // The first child: crossed mid-planes, and on flat axes the origin's side.
    let first = t_mid.cmplt(Vec3A::splat(t_enter)).bitmask() | (r.o.cmpge(mid) & r.flat).bitmask();
    let tie = (t_mid - Vec3A::splat(t_enter))
        .abs()
        .cmple(Vec3A::splat(t_enter.abs() * (NEAR_TIE - 1.0)))
        .bitmask()
        & !r.flat_bits;
    let (mut order, mut count, mut seen) = (0u32, 0u32, 0u32);
    // Only a node the ray enters before `t_from` can have children that end before it. PERF:
    // testing the children of those nodes only, and taking the lane masks from a table, took
    // the bunny's primary rays from 3.47 to 3.75 Mrays/s (same command as below).
    let starts_inside = t_enter < t_from;
    let mut add = |c: u32| {
        if seen & 1 << c == 0 {
            seen |= 1 << c;
            let real = c ^ r.neg_bits;
            let behind =
                starts_inside && Vec3A::select(lanes(c), far, t_mid).min_element() < t_from;
            if !block.0[real as usize].is_empty_leaf() && !behind {
                order |= real << (4 * count);
                count += 1;
            }
        }
    };
    // The first child, with every combination of the crossings that tie with the entry, in
    // increasing order.
    let mut sub = 0;
    loop {
        add(first & !tie | sub);
        if sub == tie {
            break;
        }
        sub = sub.wrapping_sub(tie) & tie;
    }
    // The mid-planes still ahead, crossed in increasing order of their parameters while they
    // come before the node's exit; each crossing sets its axis' bit. PERF: sorting once instead
    // of taking the minimum of the child's exit parameters at every step took the bunny's
    // primary rays from 3.75 to 4.07 Mrays/s (`cargo xtask compare --scene
    // ../shared/meshes/stanford-bunny.obj --threads 1`, two interleaved runs each).
    let t_exit = far.min_element();
    let tm = t_mid.to_array();
    let (mut a0, mut a1, mut a2) = (0, 1, 2);
    if tm[a1] < tm[a0] {
        (a0, a1) = (a1, a0);
    }
    if tm[a2] < tm[a1] {
        (a1, a2) = (a2, a1);
    }
    if tm[a1] < tm[a0] {
        (a0, a1) = (a1, a0);
    }
    let mut c = first;
    for a in [a0, a1, a2] {
        if c & 1 << a != 0 {
            continue;
        }
        let t = tm[a];
        if t.is_nan() || t >= t_exit {
            break;
        }
        // Mid-planes crossed together with this one: the children of the other orders too.
        let side = t_mid.cmple(Vec3A::splat(widen(t))).bitmask() & !c & !(1 << a) & 7;
        for_each_subset(side, |sub| add(c | sub));
        c |= 1 << a;
        add(c);
    }
    // Mid-planes crossed together with the node's exit.
    let side = t_mid.cmple(Vec3A::splat(widen(t_exit))).bitmask() & !c & 7;
    for_each_subset(side, |sub| add(c | sub));
    (order, count)
}

/// How a trace names child `i` of block `block`: the root is node 0, and the children of
/// block `b` are numbered from `1 + 8b`.
fn place(node: &Node, block: u32, i: u32) -> Place {
    let id = 1 + 8 * block + i;
    if node.children().is_some() {
        Place::Node(id)
    } else {
        Place::Leaf(id)
    }
}

/// The trace's report of entering a node with box `[lo, hi]` and face parameters `slabs`.
fn enter(place: Place, lo: Vec3A, hi: Vec3A, slabs: (Vec3A, Vec3A)) -> Event {
    Event::Enter {
        place,
        t0: slabs.0.max_element(),
        t1: slabs.1.min_element(),
        bounds: Some(Aabb {
            min: lo.into(),
            max: hi.into(),
        }),
    }
}

/// Reports, in the order the walk will take them, the children of block `b` (of the node with
/// box `[lo, hi]`) that the ray crosses, with their entry parameters.
fn report_children<S: Stats>(
    stats: &mut S,
    r: &RayAxes,
    (lo, hi): (Vec3A, Vec3A),
    (b, block): (u32, &Block),
    (mut order, left): (u32, u32),
) {
    if !S::TRACE {
        return;
    }
    let mid = lo * 0.5 + hi * 0.5;
    for _ in 0..left {
        let i = order & 7;
        order >>= 4;
        let upper = lanes(i);
        let (clo, chi) = (Vec3A::select(upper, mid, lo), Vec3A::select(upper, hi, mid));
        let t = r.slabs(clo, chi).0.max_element();
        let place = place(&block.0[i as usize], b, i);
        stats.event(Event::Child { place, t });
    }
}

impl<P: Primitive> Octree<P> {
    /// The walk for query `q`, with the record of tested primitives its query needs
    /// ([`leaf::walk_once`]: a mailbox of the last [`MAILBOX`], or every one).
    #[inline(always)]
    pub(crate) fn query<S: Stats, Q: RayQuery>(&self, ray: &Ray, q: &mut Q, stats: &mut S) {
        leaf::walk_once::<_, MAILBOX, Q, S>(self, ray, q, stats);
    }
}

impl<P: Primitive> leaf::CellWalk for Octree<P> {
    #[inline(always)]
    fn prim_count(&self) -> usize {
        self.prims.len()
    }

    /// The walk.
    #[inline(always)]
    fn walk<Q: RayQuery, S: Stats, M: Seen>(
        &self,
        ray: &Ray,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) {
        // An empty structure walks nothing (`walk_once` has already turned away invalid rays).
        if self.refs.is_empty() {
            return;
        }
        let r = RayAxes::new(ray);
        let (lo, hi) = (Vec3A::from(self.bounds.min), Vec3A::from(self.bounds.max));
        let slabs = r.slabs(lo, hi);
        let (t_enter, t_exit) = (slabs.0.max_element(), slabs.1.min_element());
        let t_from = ray.t_min - ray.t_min.abs() * (NEAR_TIE - 1.0);
        let inside_flat = (r.o.cmpge(lo) & r.o.cmple(hi)) | !r.flat;
        if !inside_flat.all()
            || t_enter > widen(t_exit)
            || t_exit < t_from
            || t_enter > q.t_far() * SLAB_FAR_SCALE
        {
            return;
        }
        // A query that wants each hit once is remembered exactly, whatever the ablation says.
        let dedupe = self.mailbox || !Q::REPEATABLE;
        let mut test = |node: &Node, q: &mut Q, stats: &mut S| {
            let ids = &self.refs[node.references()];
            leaf::test_primitives(&self.prims, ids, ray, q, seen, dedupe, stats).is_break()
        };
        stats.node_visit();
        trace::report(stats, || {
            let place = match self.root.children() {
                Some(_) => Place::Node(0),
                None => Place::Leaf(0),
            };
            enter(place, lo, hi, slabs)
        });
        let Some(block) = self.root.children() else {
            test(&self.root, q, stats);
            return;
        };
        let (order, left) = children_order(&r, lo, hi, slabs, &self.blocks[block], t_from);
        let b = (block as u32, &self.blocks[block]);
        report_children(stats, &r, (lo, hi), b, (order, left));
        let frame = Frame {
            lo,
            hi,
            block: block as u32,
            order,
            left,
        };
        // PERF: not filled per ray with copies of the first frame (21 frames of 48 bytes). In-
        // process A/B on the four peer scenes, one thread, medians of 3-5 processes: primary
        // rays 1.03-1.05x as fast, shadow 1.01-1.08x, incoherent 1.00-1.02x.
        let mut stack = Stack::<Frame, STACK>::new();
        stack.push(frame);
        while let Some(f) = stack.last_mut() {
            if f.left == 0 {
                stack.pop();
                continue;
            }
            let i = f.order & 7;
            (f.order, f.left) = (f.order >> 4, f.left - 1);
            let mid = f.lo * 0.5 + f.hi * 0.5;
            let upper = lanes(i);
            let (lo, hi) = (
                Vec3A::select(upper, mid, f.lo),
                Vec3A::select(upper, f.hi, mid),
            );
            let node = self.blocks[f.block as usize].0[i as usize];
            let slabs = r.slabs(lo, hi);
            if slabs.0.max_element() > q.t_far() * SLAB_FAR_SCALE {
                trace::report(stats, || {
                    Event::Note("the next child starts beyond the query's far end: done")
                });
                break;
            }
            stats.node_visit();
            trace::report(stats, || enter(place(&node, f.block, i), lo, hi, slabs));
            match node.children() {
                None => {
                    if test(&node, q, stats) {
                        trace::report(stats, || Event::Note("the query ends the walk: done"));
                        break;
                    }
                }
                Some(block) => {
                    let (order, left) =
                        children_order(&r, lo, hi, slabs, &self.blocks[block], t_from);
                    let b = (block as u32, &self.blocks[block]);
                    report_children(stats, &r, (lo, hi), b, (order, left));
                    stack.push(Frame {
                        lo,
                        hi,
                        block: block as u32,
                        order,
                        left,
                    });
                }
            }
        }
    }
}

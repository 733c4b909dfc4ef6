//! The O(N log N) SAH build of Wald & Havran (2006), with perfect splits and planar handling.
//!
//! Every primitive contributes, per axis, a start and an end event at the bounds of its part in
//! the node's cell (or one planar event if that part is flat in the axis). The three event lists
//! are sorted once at the root. A node sweeps each sorted list to find the plane of least SAH
//! cost, then splits the lists in O(n) by filtering: primitives entirely on one side keep their
//! events, already in order; only primitives straddling the plane are clipped to the two child
//! cells and get new events, which are sorted (there are few, O(√n) for typical meshes) and
//! merged in. So no node sorts its whole list again.

use crate::KdParams;
use crate::node::{MAX_INDEX, Node};
use rt_core::{Aabb, Primitive};
use std::cell::RefCell;

/// Nodes with at least this many references build their two subtrees in parallel.
///
/// Smaller subtrees are built on the current thread: a node of a few thousand references is tens
/// of microseconds of work, the same order as handing a task to another thread.
const PARALLEL_MIN_REFS: usize = 4096;

/// Event kinds, in their sort order at equal position: ends before planars before starts (Wald &
/// Havran §4.2), so a sweep sees a primitive leave before the ones that enter at the same plane.
const END: u32 = 0;
const PLANAR: u32 = 1;
const START: u32 = 2;

/// The most primitives a tree can index: event tags keep the kind in their top two bits.
pub(crate) const MAX_PRIMS: usize = (1 << 30) - 1;

/// One split candidate, packed in its own sort key: the position's bits made monotonic as an
/// unsigned integer in the upper 32 bits, then the kind in two bits, then the primitive index.
///
/// Sorting by the key orders by position, then kind, then primitive. That order is total, so the
/// sorted lists (and so the tree) do not depend on the sort algorithm or on threading. Keeping
/// only the key makes every comparison while sorting and merging one integer comparison; the
/// sweep decodes the position with two bit operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Event(u64);

impl Event {
    const ZERO: Self = Self(0);

    #[inline]
    fn new(pos: f32, kind: u32, prim: u32) -> Self {
        // `+ 0.0` turns -0.0 into +0.0, so that equal positions have equal keys.
        let bits = (pos + 0.0).to_bits();
        let ordered = if bits >> 31 == 1 {
            !bits
        } else {
            bits | 1 << 31
        };
        Self((u64::from(ordered) << 32) | u64::from((kind << 30) | prim))
    }

    /// The position's key bits: equal exactly when the positions are equal.
    #[inline(always)]
    fn pos_bits(self) -> u32 {
        (self.0 >> 32) as u32
    }

    #[inline(always)]
    fn pos(self) -> f32 {
        let ordered = self.pos_bits();
        f32::from_bits(if ordered >> 31 == 1 {
            ordered & !(1 << 31)
        } else {
            !ordered
        })
    }

    #[inline(always)]
    fn kind(self) -> u32 {
        (self.0 as u32) >> 30
    }

    #[inline(always)]
    fn prim(self) -> usize {
        (self.0 as u32 & MAX_PRIMS as u32) as usize
    }
}

/// The events of primitive `prim` on `axis`, whose part in the cell is `b`: a start and an end,
/// or one planar event where the part is flat on that axis.
fn events(prim: u32, b: &Aabb, axis: usize) -> impl Iterator<Item = Event> {
    let (lo, hi) = (b.min[axis], b.max[axis]);
    let pair = if lo == hi {
        [Some(Event::new(lo, PLANAR, prim)), None]
    } else {
        [
            Some(Event::new(lo, START, prim)),
            Some(Event::new(hi, END, prim)),
        ]
    };
    pair.into_iter().flatten()
}

/// Appends the events of primitive `prim`, whose part in the cell is `b`.
fn push_events(lists: &mut [Vec<Event>; 3], prim: u32, b: &Aabb) {
    for (axis, list) in lists.iter_mut().enumerate() {
        list.extend(events(prim, b, axis));
    }
}

/// A node waiting to be built: its cell, and where the sorted events of the primitives
/// overlapping it lie in the event arena.
#[derive(Clone, Copy, Debug)]
struct Task {
    /// The x, y and z event lists, one after the other: `arena[bounds[a]..bounds[a + 1]]`.
    bounds: [usize; 4],
    /// How many primitives overlap the cell.
    count: usize,
    cell: Aabb,
    depth: u32,
    /// Splits on the path from the root that did not lower the SAH cost (pbrt's "bad refines").
    bad_refines: u32,
}

impl Task {
    /// The sorted events of `axis`.
    #[inline]
    fn axis_events<'a>(&self, arena: &'a [Event], axis: usize) -> &'a [Event] {
        &arena[self.bounds[axis]..self.bounds[axis + 1]]
    }
}

/// Per-thread buffers reused from node to node, so that a node allocates only its children's
/// event lists.
#[derive(Default)]
struct Scratch {
    /// Which side each primitive goes to, indexed by primitive; only the current node's entries
    /// are meaningful.
    side: Vec<u8>,
    /// The current node's straddling primitives (with one spare slot for a speculative write).
    straddlers: Vec<u32>,
    lnew: [Vec<Event>; 3],
    rnew: [Vec<Event>; 3],
}

thread_local! {
    /// One scratch per thread: a node's partition runs start to finish on one thread, with no
    /// rayon call inside, so it never shares the buffer.
    static SCRATCH: RefCell<Scratch> = RefCell::default();
}

trait CellExt {
    fn with_max(self, axis: usize, pos: f32) -> Self;
    fn with_min(self, axis: usize, pos: f32) -> Self;
}

impl CellExt for Aabb {
    #[inline]
    fn with_max(mut self, axis: usize, pos: f32) -> Self {
        self.max[axis] = pos;
        self
    }
    #[inline]
    fn with_min(mut self, axis: usize, pos: f32) -> Self {
        self.min[axis] = pos;
        self
    }
}

/// The chosen plane.
#[derive(Clone, Copy, Debug)]
struct Plane {
    cost: f32,
    axis: usize,
    pos: f32,
    /// Whether primitives lying in the plane go to the left child.
    planar_left: bool,
    /// Primitives in the left and right child.
    left_count: usize,
    right_count: usize,
}

/// What the builder hands to [`KdTree`](crate::KdTree).
#[derive(Debug, Default)]
pub(crate) struct Built {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    pub bounds: Aabb,
    pub max_depth: usize,
    pub leaves: usize,
    pub empty_leaves: usize,
    pub valid_prims: usize,
}

/// What the build asks of a primitive once its events are made: its box, and its parts on
/// either side of a plane within a cell (perfect splits).
///
/// The build reaches the primitives through this trait object rather than a type parameter, so
/// that it is compiled once, in this crate, and not again for every primitive type a program
/// builds trees of (with rayon's machinery for its parallel calls). It is called for the
/// primitives a split straddles, each clip of which costs far more than the call.
// PERF: rt-kdtree's test suite compiles 132k lines of LLVM IR instead of 155k, and the build's
// time did not move (new ÷ old, one thread, medians of six processes: bunny 1.000, teapot
// 1.002, sphereflake 1.008, teapot in a stadium 1.004).
trait Parts: Sync {
    /// How many primitives there are (valid or not).
    fn len(&self) -> usize;
    /// Primitive `id`'s box ([`Primitive::bounds`]).
    fn bounds(&self, id: u32) -> Aabb;
    /// Primitive `id`'s parts below and above `pos` on `axis` within `cell`
    /// ([`Primitive::split_bounds`]).
    fn split_bounds(
        &self,
        id: u32,
        cell: &Aabb,
        axis: usize,
        pos: f32,
    ) -> (Option<Aabb>, Option<Aabb>);
}

/// A primitive slice as [`Parts`].
struct Source<'a, P>(&'a [P]);

impl<P: Primitive> Parts for Source<'_, P> {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn bounds(&self, id: u32) -> Aabb {
        self.0[id as usize].bounds()
    }

    fn split_bounds(
        &self,
        id: u32,
        cell: &Aabb,
        axis: usize,
        pos: f32,
    ) -> (Option<Aabb>, Option<Aabb>) {
        self.0[id as usize].split_bounds(cell, axis, pos)
    }
}

struct Ctx<'a> {
    prims: &'a dyn Parts,
    kt: f32,
    ki: f32,
    empty_factor: f32,
    empty_cut: f32,
    perfect: bool,
    max_depth: u32,
    max_bad_refines: u32,
    leaf_size: usize,
    parallel: bool,
}

impl<'a> Ctx<'a> {
    /// The build context for `valid` valid primitives among `prims`.
    fn new(prims: &'a dyn Parts, params: &KdParams, valid: usize) -> Self {
        Self {
            prims,
            kt: params.traversal_cost.max(0.0),
            ki: params.intersection_cost.max(f32::MIN_POSITIVE),
            empty_factor: 1.0 - params.empty_bonus.clamp(0.0, 1.0),
            empty_cut: params.empty_cut,
            perfect: params.perfect_splits,
            max_depth: params.resolved_max_depth(valid),
            max_bad_refines: params.max_bad_refines,
            leaf_size: params.leaf_size as usize,
            parallel: params.parallel,
        }
    }
}

pub(crate) fn build<P: Primitive>(prims: &[P], params: &KdParams) -> Built {
    let ids: Vec<u32> = (0..prims.len().min(MAX_PRIMS + 1))
        .filter(|&i| prims[i].is_valid())
        .map(|i| i as u32)
        .collect();
    assert!(
        prims.len() <= MAX_PRIMS,
        "a kd-tree holds at most 2^30 - 1 primitives"
    );
    build_valid(&Source(prims), ids, params)
}

/// [`build`] from the valid primitives' indices on: everything that does not depend on the
/// primitive type.
fn build_valid(prims: &dyn Parts, ids: Vec<u32>, params: &KdParams) -> Built {
    let bounds = ids
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(prims.bounds(i)));
    let mut out = Built {
        bounds,
        valid_prims: ids.len(),
        nodes: vec![Node::leaf(0, 0)],
        ..Built::default()
    };
    if ids.is_empty() {
        out.leaves = 1;
        out.empty_leaves = 1;
        return out;
    }
    let ctx = Ctx::new(prims, params, ids.len());
    // The scene box is the union of the primitives' bounds, so every valid primitive meets it and
    // its part in it is its whole bounds. The three lists are written straight into one arena of
    // exactly their size: pushing to growing lists and joining them would hold up to three
    // times the events at once, 48 bytes per triangle each.
    let mut sizes = [0usize; 3];
    for &id in &ids {
        let b = prims.bounds(id);
        for (axis, size) in sizes.iter_mut().enumerate() {
            *size += if b.min[axis] == b.max[axis] { 1 } else { 2 };
        }
    }
    let (nx, ny) = (sizes[0], sizes[1]);
    let mut arena = vec![Event::ZERO; nx + ny + sizes[2]];
    let mut at = [0, nx, nx + ny];
    for &id in &ids {
        let b = prims.bounds(id);
        for (axis, at) in at.iter_mut().enumerate() {
            for e in events(id, &b, axis) {
                arena[*at] = e;
                *at += 1;
            }
        }
    }
    let count = ids.len();
    drop(ids);
    {
        let (x, rest) = arena.split_at_mut(nx);
        let (y, z) = rest.split_at_mut(ny);
        if ctx.parallel && count >= PARALLEL_MIN_REFS {
            for list in [x, y, z] {
                rt_core::par::sort_unstable(list);
            }
        } else {
            for list in [x, y, z] {
                list.sort_unstable();
            }
        }
    }
    let root = Task {
        bounds: [0, nx, nx + ny, arena.len()],
        count,
        cell: bounds,
        depth: 0,
        bad_refines: 0,
    };
    build_into(&ctx, root, 0, &mut out, &mut arena);
    out.nodes.shrink_to_fit();
    out.refs.shrink_to_fit();
    out
}

/// Builds `task` with its root written to `out.nodes[slot]` and its descendants appended.
///
/// The layout is: a node's two children side by side, then the left child's descendants, then
/// the right child's. Parallel subtrees are built into their own buffers and appended in the same
/// order, so the output does not depend on threading.
///
/// The events of a small task are the top of `arena`, a stack (whose logical top is the current
/// task's end; the vector itself only grows): a split replaces them with the children's (right
/// below left), the left subtree is built on top, then the right one. So a sequential build
/// allocates nothing per node, and the events in use stay in cache. A large task (at least
/// [`PARALLEL_MIN_REFS`] references) that is partitioned writes its children's events to two
/// new lists of their own instead and frees its own, whether or not the two are then built in
/// parallel. So the build holds the events of the tasks on its current paths and of their
/// waiting siblings, about the root's events again, and never a stack of ancestors' lists.
fn build_into(ctx: &Ctx<'_>, task: Task, slot: usize, out: &mut Built, arena: &mut Vec<Event>) {
    out.max_depth = out.max_depth.max(task.depth as usize);
    let detach = task.count >= PARALLEL_MIN_REFS;
    let Some((children, axis, pos)) = split(ctx, &task, arena, detach) else {
        make_leaf(&task, arena, slot, out);
        return;
    };
    let first = out.nodes.len();
    assert!(first < MAX_INDEX, "a kd-tree holds at most 2^30 nodes");
    out.nodes[slot] = Node::interior(axis, pos, first);
    out.nodes.push(Node::leaf(0, 0));
    out.nodes.push(Node::leaf(0, 0));
    match children {
        Children::InPlace(left, right) => {
            // The left subtree only writes above the right child's events.
            build_into(ctx, left, first, out, arena);
            build_into(ctx, right, first + 1, out, arena);
        }
        Children::Detached((left, mut larena), (right, mut rarena)) => {
            // The task's events are the top of the arena; below them lie the events of tasks
            // still waiting, if any (a large task's arena is its own, so usually none).
            arena.truncate(task.bounds[0]);
            if arena.is_empty() {
                *arena = Vec::new();
            }
            if ctx.parallel {
                let (l, r) = rt_core::par::join(
                    || subtree(ctx, left, larena),
                    || subtree(ctx, right, rarena),
                );
                out.nodes.reserve_exact(l.nodes.len() + r.nodes.len() - 2);
                out.refs.reserve_exact(l.refs.len() + r.refs.len());
                append(out, first, l);
                append(out, first + 1, r);
            } else {
                build_into(ctx, left, first, out, &mut larena);
                drop(larena);
                build_into(ctx, right, first + 1, out, &mut rarena);
            }
        }
    }
}

fn make_leaf(task: &Task, arena: &[Event], slot: usize, out: &mut Built) {
    let first = out.refs.len();
    assert!(
        first + task.count <= MAX_INDEX + 1,
        "a kd-tree holds at most 2^30 primitive references"
    );
    out.nodes[slot] = Node::leaf(first, task.count);
    out.leaves += 1;
    out.empty_leaves += usize::from(task.count == 0);
    if task.count == 0 {
        // An empty child of a cut may come after its full sibling has freed the arena.
        return;
    }
    // Each primitive has exactly one start or planar event on every axis; list them in index
    // order, so the leaf does not depend on event order.
    out.refs.extend(
        task.axis_events(arena, 0)
            .iter()
            .filter(|e| e.kind() != END)
            .map(|e| e.prim() as u32),
    );
    out.refs[first..].sort_unstable();
}

fn subtree(ctx: &Ctx<'_>, task: Task, mut arena: Vec<Event>) -> Built {
    let mut out = Built {
        nodes: vec![Node::leaf(0, 0)],
        ..Built::default()
    };
    build_into(ctx, task, 0, &mut out, &mut arena);
    drop(arena);
    // The vectors grew by doubling; the caller copies them into its own at once, and the slack
    // of both halves of a large tree would otherwise add up to the tree's size again.
    out.nodes.shrink_to_fit();
    out.refs.shrink_to_fit();
    out
}

/// Appends a separately built subtree, its root going to `out.nodes[slot]`.
fn append(out: &mut Built, slot: usize, sub: Built) {
    // Local node j >= 1 lands at base + j - 1.
    let node_shift = out.nodes.len() - 1;
    let ref_shift = out.refs.len();
    assert!(
        node_shift + sub.nodes.len() <= MAX_INDEX && ref_shift + sub.refs.len() <= MAX_INDEX + 1,
        "a kd-tree holds at most 2^30 nodes and 2^30 references"
    );
    out.nodes[slot] = sub.nodes[0].relocated(node_shift, ref_shift);
    out.nodes.extend(
        sub.nodes[1..]
            .iter()
            .map(|n| n.relocated(node_shift, ref_shift)),
    );
    out.refs.extend_from_slice(&sub.refs);
    out.max_depth = out.max_depth.max(sub.max_depth);
    out.leaves += sub.leaves;
    out.empty_leaves += sub.empty_leaves;
}

/// A task's two children: with their events at the top of the parent's arena, or each with a
/// list of its own.
enum Children {
    InPlace(Task, Task),
    Detached((Task, Vec<Event>), (Task, Vec<Event>)),
}

/// Splits `task` into its two children, or returns `None` when it should be a leaf. The
/// children's events replace the task's at the top of `arena`, unless the task is partitioned
/// and `detach` asks for lists of their own. (A cut that leaves one side empty moves no event:
/// the other child keeps the task's events where they are.)
fn split(
    ctx: &Ctx<'_>,
    task: &Task,
    arena: &mut Vec<Event>,
    detach: bool,
) -> Option<(Children, usize, f32)> {
    if !may_split(ctx, task.count, task.depth) {
        return None;
    }
    if let Some(plane) = empty_space(ctx, task, arena) {
        let (left, right) = cut_empty(task, plane, task.bad_refines);
        return Some((Children::InPlace(left, right), plane.axis, plane.pos));
    }
    // A small node keeps the empty-space cuts above (cheap, and they let rays skip its cell) but
    // prices no plane. (PERF: leaf size 3 against the default 0, the bunny's single-threaded
    // build 253 -> 205 ms, best of 9, and 823k -> 520k nodes; speed on six meshes, one thread:
    // primary rays 1.02-1.10x, shadow 1.01-1.11x, incoherent 1.05-1.18x.)
    if task.count <= ctx.leaf_size {
        return None;
    }
    let plane = best_plane(ctx, task, arena)?;
    let bad_refines = accept(ctx, task.count, task.bad_refines, &plane)?;
    let children = if plane.left_count == 0 || plane.right_count == 0 {
        let (left, right) = cut_empty(task, plane, bad_refines);
        Children::InPlace(left, right)
    } else {
        SCRATCH.with_borrow_mut(|s| partition(ctx, task, plane, bad_refines, arena, s, detach))
    };
    Some((children, plane.axis, plane.pos))
}

/// The cut that removes the largest empty slab from the cell, if that slab spans at least
/// `empty_cut` of the cell's extent on its axis.
///
/// The primitives' parts span from the first to the last event of each sorted list, so the
/// empty slabs at the six faces cost O(1) to find. A wide empty slab is what the SAH with an
/// empty-side bonus would cut anyway; cutting it without pricing every candidate saves the sweep
/// of every node along a chain of such cuts. (PERF: with the default constants on the bunny,
/// single-threaded, best of 9: build 326 -> 302 ms, 853k -> 823k nodes, 0.758 -> 0.764 primitive
/// tests per primary ray.)
fn empty_space(ctx: &Ctx<'_>, task: &Task, arena: &[Event]) -> Option<Plane> {
    if ctx.empty_cut <= 0.0 {
        return None;
    }
    let mut best: Option<(f32, Plane)> = None;
    for axis in 0..3 {
        let events = task.axis_events(arena, axis);
        let (lo, hi) = (task.cell.min[axis], task.cell.max[axis]);
        let (Some(first), Some(last)) = (events.first(), events.last()) else {
            continue;
        };
        let (first, last) = (first.pos(), last.pos());
        let extent = hi - lo;
        // Left empty: the plane at the parts' lowest bound, with primitives lying in it going
        // right; right empty: at their highest bound, with those in it going left.
        for (gap, pos, planar_left) in [(first - lo, first, false), (hi - last, last, true)] {
            let fraction = gap / extent;
            if lo < pos
                && pos < hi
                && fraction >= ctx.empty_cut
                && best.is_none_or(|b| fraction > b.0)
            {
                let (left_count, right_count) = if planar_left {
                    (task.count, 0)
                } else {
                    (0, task.count)
                };
                let plane = Plane {
                    cost: f32::NAN,
                    axis,
                    pos,
                    planar_left,
                    left_count,
                    right_count,
                };
                best = Some((fraction, plane));
            }
        }
    }
    best.map(|(_, plane)| plane)
}

/// Whether a node of `n` primitives at `depth` may be split at all.
#[inline]
fn may_split(ctx: &Ctx<'_>, n: usize, depth: u32) -> bool {
    n > 0 && depth < ctx.max_depth
}

/// The termination rule for a node of `n` primitives whose best plane is `plane`: the node's
/// bad-refine count after splitting there, or `None` if it should be a leaf.
///
/// Wald & Havran stop when no split beats the leaf; pbrt-v4 tolerates a few non-improving splits
/// on a path, since a later split may still pay off.
#[inline]
fn accept(ctx: &Ctx<'_>, n: usize, bad_refines: u32, plane: &Plane) -> Option<u32> {
    let leaf_cost = ctx.ki * n as f32;
    if plane.cost < leaf_cost {
        return Some(bad_refines);
    }
    let bad_refines = bad_refines + 1;
    (bad_refines <= ctx.max_bad_refines && !(plane.cost > 4.0 * leaf_cost && n < 16))
        .then_some(bad_refines)
}

/// The sweep (Wald & Havran, Algorithm 4): per axis, walk the sorted events keeping the counts of
/// primitives left of, in and right of the current plane, and price every plane strictly inside
/// the cell.
fn best_plane(ctx: &Ctx<'_>, task: &Task, arena: &[Event]) -> Option<Plane> {
    let cell = &task.cell;
    let ext = cell.extent();
    let half_area = ext.x * ext.y + ext.y * ext.z + ext.z * ext.x;
    // Also false for NaN, which cannot occur with finite primitives.
    if half_area.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    // Candidates are priced in units of K_I / A (A: the cell's half area), which leaves three
    // multiplications per candidate instead of six: cost · A / K_I = λ · (K + a_l·n_l + a_r·n_r),
    // with a_l, a_r the children's half areas and K = K_T · A / K_I. (PERF: this, u32 counts and
    // one load per event took the bunny build with one bad refine from 1 to 0.977 of its time,
    // best of 15 builds each, interleaved.)
    let k = ctx.kt / ctx.ki * half_area;
    // Counts are u32 (a tree holds fewer than 2^30 primitives): converting them to f32 is one
    // instruction, where a usize takes several.
    let n = task.count as u32;
    let mut best: Option<Plane> = None;
    let mut best_cost = f32::INFINITY;
    for axis in 0..3 {
        let events = task.axis_events(arena, axis);
        let (lo, hi) = (cell.min[axis], cell.max[axis]);
        let Some(&last) = events.last() else {
            continue;
        };
        if lo >= hi {
            continue;
        }
        // Positions compare as their key bits, which keep the order.
        let (lo_bits, hi_bits) = (key_bits(lo), key_bits(hi));
        // Half area of a child as a function of its extent `w` along `axis`: w·(e1 + e2) + e1·e2.
        let (e1, e2) = (ext[(axis + 1) % 3], ext[(axis + 2) % 3]);
        let (side, cap) = (e1 + e2, e1 * e2);
        // Per event: `nr` drops at an end or planar event; planars and starts of the current
        // position wait in `np` and `ns` until its last event, where the plane is priced with
        // left = nl, in-plane = np, right = nr, and they then move to the left.
        let (mut nl, mut nr, mut np, mut ns) = (0u32, n, 0u32, 0u32);
        let mut visit = |e: Event, group_end: bool| {
            let kind = e.kind();
            nr -= u32::from(kind != START);
            np += u32::from(kind == PLANAR);
            ns += u32::from(kind == START);
            if !group_end {
                return;
            }
            let bits = e.pos_bits();
            if lo_bits < bits && bits < hi_bits {
                let candidate = price(ctx, k, axis, e.pos(), lo, hi, side, cap, nl, nr, np);
                if candidate.cost < best_cost {
                    best_cost = candidate.cost;
                    best = Some(candidate);
                }
            }
            nl += np + ns;
            np = 0;
            ns = 0;
        };
        // Each event is read once: a group of equal positions ends where the next event's
        // position differs.
        for pair in events.windows(2) {
            visit(pair[0], pair[1].pos_bits() != pair[0].pos_bits());
        }
        visit(last, true);
    }
    best.map(|p| Plane {
        cost: p.cost * (ctx.ki / half_area),
        ..p
    })
}

/// The key bits of position `pos`, as [`Event::pos_bits`] gives them.
#[inline]
fn key_bits(pos: f32) -> u32 {
    Event::new(pos, 0, 0).pos_bits()
}

/// The plane at `pos` on `axis` of a cell spanning `lo..hi` there, whose children's half areas
/// are `w · side + cap` for their extents `w`, with `nl`, `np` and `nr` primitives left of, in and
/// right of it; its cost is in units of K_I / A (`k` is K_T in those units).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn price(
    ctx: &Ctx<'_>,
    k: f32,
    axis: usize,
    pos: f32,
    lo: f32,
    hi: f32,
    side: f32,
    cap: f32,
    nl: u32,
    nr: u32,
    np: u32,
) -> Plane {
    let al = (pos - lo) * side + cap;
    let ar = (hi - pos) * side + cap;
    let (cost, planar_left) = sah(ctx, k, al, ar, nl, nr, np);
    Plane {
        cost,
        axis,
        pos,
        planar_left,
        left_count: (nl + if planar_left { np } else { 0 }) as usize,
        right_count: (nr + if planar_left { 0 } else { np }) as usize,
    }
}

/// The cost, in units of K_I / A, of a split into children of half areas `al` and `ar` with `np`
/// primitives in the plane, and the side those should go to. `k` is K_T in the same units.
#[inline(always)]
fn sah(ctx: &Ctx<'_>, k: f32, al: f32, ar: f32, nl: u32, nr: u32, np: u32) -> (f32, bool) {
    let factor = |l: u32, r: u32| {
        if l == 0 || r == 0 {
            ctx.empty_factor
        } else {
            1.0
        }
    };
    let base = k + (al * nl as f32 + ar * nr as f32);
    if np == 0 {
        // The common case: nothing lies in the plane. (PERF: the sweep of the bunny's root
        // went from 3.58 to 3.12 ns per event with this shortcut.)
        return (factor(nl, nr) * base, false);
    }
    let npf = np as f32;
    let cl = factor(nl + np, nr) * (base + al * npf);
    let cr = factor(nl, nr + np) * (base + ar * npf);
    let left = cl < cr;
    (if left { cl } else { cr }, left)
}

/// A split with one side empty: the other child holds every primitive with unchanged events
/// (each one's part in the cell already lies on that side), so it reuses the parent's events in
/// place. PERF: most splits of a Wald & Havran tree cut off empty space (on the bunny, 59% of the
/// leaves are empty); skipping their partition took a single-threaded bunny build from 380 to
/// 342 ms (best of 7 builds, same tree).
fn cut_empty(task: &Task, plane: Plane, bad_refines: u32) -> (Task, Task) {
    let depth = task.depth + 1;
    let top = task.bounds[3];
    let empty = Task {
        bounds: [top; 4],
        count: 0,
        cell: task.cell,
        depth,
        bad_refines,
    };
    let full = Task {
        count: task.count,
        depth,
        bad_refines,
        ..*task
    };
    let (lcell, rcell) = (
        task.cell.with_max(plane.axis, plane.pos),
        task.cell.with_min(plane.axis, plane.pos),
    );
    if plane.left_count == 0 {
        (
            Task {
                cell: lcell,
                ..empty
            },
            Task {
                cell: rcell,
                ..full
            },
        )
    } else {
        (
            Task {
                cell: lcell,
                ..full
            },
            Task {
                cell: rcell,
                ..empty
            },
        )
    }
}

const LEFT: u8 = 1;
const RIGHT: u8 = 2;
const BOTH: u8 = 3;

/// Splits the task's events at `plane` (Wald & Havran, Algorithms 5 and 6), replacing them at
/// the top of `arena` with the right child's events, then the left child's; or, if `detach`,
/// writing each child's events to a list of its own of exactly their size.
fn partition(
    ctx: &Ctx<'_>,
    task: &Task,
    plane: Plane,
    bad_refines: u32,
    arena: &mut Vec<Event>,
    scratch: &mut Scratch,
    detach: bool,
) -> Children {
    let Plane {
        axis,
        pos,
        planar_left,
        ..
    } = plane;
    let Scratch {
        side,
        straddlers,
        lnew,
        rnew,
    } = scratch;
    if side.len() < ctx.prims.len() {
        side.resize(ctx.prims.len(), BOTH);
    }
    // Classify from the split axis' events alone, in one pass: a primitive ending at or before
    // the plane is left only, one starting at or after it right only, one in it goes where the
    // SAH said, and one starting before and ending after straddles: it is clipped to both
    // children when its end event comes (a start event comes before its end event). Positions
    // compare as their key bits, which keep the order. (PERF: one pass instead of classifying
    // and then counting: bunny build 342 -> 324 ms, best of 7.)
    lnew.iter_mut().chain(rnew.iter_mut()).for_each(Vec::clear);
    let plane_bits = Event::new(pos, 0, 0).pos_bits();
    let (mut lcount, mut rcount) = (0, 0);
    // Children at the depth limit are leaves, which need only to know their primitives, not
    // their parts: a straddler's part in the cell crosses the plane, so it meets both children
    // and its bounds cut to each child say so. (PERF: 40k of the 391k clips of the bunny build with
    // one bad refine are at the last level.)
    let exact = task.depth + 1 < ctx.max_depth;
    if straddlers.len() <= task.count {
        straddlers.resize(task.count + 1, 0);
    }
    let mut ns = 0;
    for e in task.axis_events(arena, axis) {
        let prim = e.prim();
        let p = e.pos_bits();
        let kind = e.kind();
        // The event's verdict for its primitive, chosen by table rather than by branching on
        // the kind, which is random. (PERF: bunny build with one bad refine 353 -> 347 ms, best of
        // 30 interleaved builds; same tree.)
        let old = side[prim];
        let verdicts = [
            // END: left if it ends at or before the plane, else what its start said.
            if p <= plane_bits { LEFT } else { old },
            // PLANAR: its side of the plane, or the SAH's side if it is in the plane.
            if p < plane_bits || (p == plane_bits && planar_left) {
                LEFT
            } else {
                RIGHT
            },
            // START: right if it starts at or after the plane, else undecided until its end.
            if p >= plane_bits { RIGHT } else { BOTH },
        ];
        let verdict = verdicts[kind as usize];
        side[prim] = verdict;
        let last = kind != START;
        lcount += usize::from(last & (verdict == LEFT));
        rcount += usize::from(last & (verdict == RIGHT));
        straddlers[ns] = prim as u32;
        ns += usize::from(last & (verdict == BOTH));
    }
    for &prim in &straddlers[..ns] {
        let (lb, rb) = clip_both(ctx, prim, &task.cell, axis, pos, exact);
        if let Some(b) = lb {
            push_events(lnew, prim, &b);
            lcount += 1;
        }
        if let Some(b) = rb {
            push_events(rnew, prim, &b);
            rcount += 1;
        }
    }
    // Room for both children: at most two events per primitive and axis, plus one slot each
    // for the branch-free filter's last speculative write.
    let rcap = 6 * rcount + 1;
    let lcap = 6 * lcount + 1;
    let depth = task.depth + 1;
    let child = |bounds: [usize; 4], count: usize, cell: Aabb| Task {
        bounds,
        count,
        cell,
        depth,
        bad_refines,
    };
    let (lcell, rcell) = (task.cell.with_max(axis, pos), task.cell.with_min(axis, pos));
    if detach {
        let mut lout = vec![Event::ZERO; lcap];
        let mut rout = vec![Event::ZERO; rcap];
        let (lb, rb) = merge(task, arena, side, lnew, rnew, &mut lout, &mut rout);
        for (list, len) in [(&mut lout, lb[3]), (&mut rout, rb[3])] {
            list.truncate(len);
            list.shrink_to_fit();
        }
        return Children::Detached(
            (child(lb, lcount, lcell), lout),
            (child(rb, rcount, rcell), rout),
        );
    }
    let top = task.bounds[3];
    // The arena only grows: slots above the top are stale but written before they are read, so
    // they need no zeroing (truncating and re-growing would zero 48 bytes per reference at
    // every level).
    let needed = top + rcap + lcap;
    if arena.len() < needed {
        arena.resize(needed, Event::ZERO);
    }
    let (below, above) = arena.split_at_mut(top);
    let (rout, lout) = above.split_at_mut(rcap);
    let (lb, rb) = merge(task, below, side, lnew, rnew, lout, rout);
    let (li, ri) = (lb[3], rb[3]);
    // Move the children down over the parent's events: right first, then left on top.
    let base = task.bounds[0];
    arena.copy_within(top..top + ri, base);
    arena.copy_within(top + rcap..top + rcap + li, base + ri);
    Children::InPlace(
        child(lb.map(|b| b + base + ri), lcount, lcell),
        child(rb.map(|b| b + base), rcount, rcell),
    )
}

/// Writes the children's sorted event lists of a task whose events lie in `src` to `lout` and
/// `rout` (each long enough for six events per primitive and one more): each parent event goes
/// to the side `side` gives its primitive, and the straddlers' new events `lnew` and `rnew` are
/// sorted and merged in. Returns where each child's x, y and z events start and end.
fn merge(
    task: &Task,
    src: &[Event],
    side: &[u8],
    lnew: &mut [Vec<Event>; 3],
    rnew: &mut [Vec<Event>; 3],
    lout: &mut [Event],
    rout: &mut [Event],
) -> ([usize; 4], [usize; 4]) {
    let (mut li, mut ri) = (0, 0);
    let mut lb = [0; 4];
    let mut rb = [0; 4];
    for a in 0..3 {
        (lb[a], rb[a]) = (li, ri);
        // Every event is written to both lists and only the index of its side advances, instead
        // of branching on a side that is left or right at random. The straddlers' new events,
        // sorted, are merged in on the way: before each parent event, those with smaller keys
        // go first.
        let (ln, rn) = (&mut lnew[a], &mut rnew[a]);
        ln.sort_unstable();
        rn.sort_unstable();
        let key_at = |list: &[Event], i: usize| list.get(i).map_or(u64::MAX, |e| e.0);
        let (mut lj, mut rj) = (0, 0);
        let (mut lnext, mut rnext) = (key_at(ln, 0), key_at(rn, 0));
        for &e in task.axis_events(src, a) {
            let key = e.0;
            while lnext < key {
                lout[li] = ln[lj];
                (li, lj) = (li + 1, lj + 1);
                lnext = key_at(ln, lj);
            }
            while rnext < key {
                rout[ri] = rn[rj];
                (ri, rj) = (ri + 1, rj + 1);
                rnext = key_at(rn, rj);
            }
            let s = side[e.prim()];
            lout[li] = e;
            li += usize::from(s == LEFT);
            rout[ri] = e;
            ri += usize::from(s == RIGHT);
        }
        for &e in &ln[lj..] {
            lout[li] = e;
            li += 1;
        }
        for &e in &rn[rj..] {
            rout[ri] = e;
            ri += 1;
        }
    }
    (lb[3], rb[3]) = (li, ri);
    (lb, rb)
}

/// The parts of a straddling primitive in the two child cells: clipped exactly with perfect
/// splits when `exact`, else its bounds cut to each cell.
fn clip_both(
    ctx: &Ctx<'_>,
    prim: u32,
    cell: &Aabb,
    axis: usize,
    pos: f32,
    exact: bool,
) -> (Option<Aabb>, Option<Aabb>) {
    let loose = || {
        let b = ctx.prims.bounds(prim).intersection(cell);
        let (mut l, mut r) = (b, b);
        l.max[axis] = l.max[axis].min(pos);
        r.min[axis] = r.min[axis].max(pos);
        ((!l.is_empty()).then_some(l), (!r.is_empty()).then_some(r))
    };
    if !ctx.perfect || !exact {
        return loose();
    }
    match ctx.prims.split_bounds(prim, cell, axis, pos) {
        // The primitive was in the parent cell, so in exact arithmetic it meets a child; if
        // rounding lost it on both sides, keep the loose parts rather than drop it.
        (None, None) => loose(),
        (l, r) => {
            // The true parts lie in the primitive's own box. With coordinates far larger than
            // the cell (a triangle reaching 10¹⁷ clipped to a unit cell) the clipper's rounding
            // can put a part outside that box, where the primitive would be listed in cells it
            // misses (found by the `trace` fuzz target: `validate` failed). Keep each part
            // within the box; if nothing is left, that side's loose part decides.
            let b = ctx.prims.bounds(prim);
            // The loose parts are computed only if a part falls outside the box (rarely).
            let within = |part: Option<Aabb>, left: bool| {
                part.and_then(|p| {
                    let p = p.intersection(&b);
                    if !p.is_empty() {
                        Some(p)
                    } else if left {
                        loose().0
                    } else {
                        loose().1
                    }
                })
            };
            (within(l, true), within(r, false))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::KdTree;
    use rt_core::glam::Vec3;
    use rt_core::{Accel, Counters, Ray, Triangle};

    /// A small triangle in the plane `z`, at x 0.9..1 and y 0..0.1.
    fn small(z: f32) -> Triangle {
        Triangle::new(
            Vec3::new(0.9, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(0.95, 0.1, z),
        )
    }

    #[test]
    fn a_node_of_at_most_leaf_size_primitives_prices_no_plane() {
        // Three triangles in parallel planes, with no empty slab around them: the SAH would
        // separate them, `leaf_size` 3 keeps them in one leaf.
        let tris = [small(0.2), small(0.5), small(0.8)];
        let three = KdParams {
            leaf_size: 3,
            ..KdParams::sah()
        };
        assert_eq!(KdTree::build(&tris, &three).nodes().len(), 1);
        assert_eq!(KdTree::build(&tris, &KdParams::sah()).nodes().len(), 1);
        assert!(
            KdTree::build(&tris, &KdParams::fewest_tests())
                .nodes()
                .len()
                > 1
        );
    }

    #[test]
    fn a_small_node_still_loses_its_empty_slabs() {
        // A large triangle in the plane x = 0 and the three small ones at x 0.9..1: the cell of
        // the three spans y 0..1 but they fill only y 0..0.1. A ray through the empty part of
        // that cell tests nothing when the slab is cut off, and the three triangles when it
        // is not.
        let tris = [
            Triangle::new(Vec3::ZERO, Vec3::Y, Vec3::Z),
            small(0.2),
            small(0.5),
            small(0.8),
        ];
        let ray = Ray::new(Vec3::new(0.95, 0.5, 2.0), -Vec3::Z);
        let three = KdParams {
            leaf_size: 3,
            ..KdParams::sah()
        };
        let tests = |params: &KdParams| {
            let tree = KdTree::build(&tris, params);
            let mut counters = Counters::default();
            assert!(tree.intersect_with(&ray, &mut counters).is_none());
            counters.prim_tests
        };
        assert_eq!(tests(&three), 0);
        let no_cut = KdParams {
            empty_cut: 0.0,
            ..three.clone()
        };
        assert_eq!(tests(&no_cut), 3);
    }

    #[test]
    fn empty_space_cuts_the_widest_slab_at_the_parts_bounds() {
        // The triangle spans x 0.6..0.9 and y 0.1..0.2 and lies in the plane z = 0.1 of the unit
        // cell: the widest empty slab is z 0.1..1, 90% of the cell.
        let tri = [Triangle::new(
            Vec3::new(0.6, 0.1, 0.1),
            Vec3::new(0.9, 0.1, 0.1),
            Vec3::new(0.9, 0.2, 0.1),
        )];
        let mut lists: [Vec<Event>; 3] = Default::default();
        push_events(&mut lists, 0, &tri[0].bounds());
        let (nx, ny) = (lists[0].len(), lists[1].len());
        let arena = lists.concat();
        let task = Task {
            bounds: [0, nx, nx + ny, arena.len()],
            count: 1,
            cell: Aabb::new(Vec3::ZERO, Vec3::ONE),
            depth: 0,
            bad_refines: 0,
        };
        let mut params = KdParams::sah();
        let plane = empty_space(&Ctx::new(&Source(&tri[..]), &params, 1), &task, &arena).unwrap();
        // The flat triangle lies in the plane and stays with the non-empty (left) side.
        assert_eq!((plane.axis, plane.pos, plane.planar_left), (2, 0.1, true));
        assert_eq!((plane.left_count, plane.right_count), (1, 0));
        // No slab is that wide, or the heuristic is off: the SAH decides.
        params.empty_cut = 0.95;
        assert!(empty_space(&Ctx::new(&Source(&tri[..]), &params, 1), &task, &arena).is_none());
        params.empty_cut = 0.0;
        assert!(empty_space(&Ctx::new(&Source(&tri[..]), &params, 1), &task, &arena).is_none());
    }
}

//! Top-down construction of the binary and the 8-wide tree from one split routine.
//!
//! Every set of primitives is split in two (binned SAH, median or middle), and gets its own split
//! planned as soon as it exists. The binary tree emits each split as a node. The wide tree starts
//! a node from one split and keeps splitting the child with the largest surface area until the
//! node has eight children or none can be split (Wald et al. 2008; Embree's BVH8 builder), so it
//! is the binary tree collapsed, built without the binary tree in between.
//!
//! Parallelism (rayon): the binning of large sets is split into chunks whose bins are merged, and
//! subtrees of many primitives are built concurrently into their own arrays, appended afterwards
//! in the order a sequential build would write them. Bins merge exactly (minima, maxima and
//! counts do not depend on the order they are combined in), and partitions run sequentially, so
//! the tree is the same, byte for byte, whatever the number of threads.

use crate::node::{ChildRef, Node, PACK, TriPack, WIDTH, WideNode};
use crate::{BvhParams, Layout, MAX_DEPTH, SplitMethod};
use rayon::prelude::*;
use rt_core::glam::{Vec3, Vec3A};
use rt_core::{Aabb, Primitive, Triangle, TriangleTest};

/// A box in SIMD registers for the build's inner loops.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Self = Self {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn union(self, o: Self) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline(always)]
    fn grow(self, p: Vec3A) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline(always)]
    fn half_area(self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    fn to_aabb(self) -> Aabb {
        Aabb::new(Vec3::from(self.min), Vec3::from(self.max))
    }

    fn longest_axis(&self) -> usize {
        self.to_aabb().largest_axis()
    }
}

/// What the builder keeps of a primitive: its box and its input index, 32 bytes. Splits sort by
/// `min + max`, twice the box centre, which needs no extra storage.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct PrimRef {
    min: [f32; 3],
    id: u32,
    max: [f32; 3],
    pad: u32,
}

impl PrimRef {
    #[inline(always)]
    fn bounds(&self) -> Bounds {
        Bounds {
            min: Vec3A::from_array(self.min),
            max: Vec3A::from_array(self.max),
        }
    }

    /// Twice the box centre.
    #[inline(always)]
    fn center2(&self) -> Vec3A {
        Vec3A::from_array(self.min) + Vec3A::from_array(self.max)
    }
}

/// How a set is split, decided when the set is made.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Plan {
    Leaf,
    /// Binned SAH: buckets `..plane` of `bins` along `axis` go left.
    Sah {
        axis: usize,
        plane: usize,
        bins: usize,
    },
    /// Half by count (quickselect) along the longest axis of the centres.
    Count,
    /// At the middle of the centres' extent along its longest axis.
    Middle,
}

/// A set of primitives: a range of the reference array, its bounds, the bounds of its centres
/// (doubled), its depth in the binary split tree, and its planned split.
#[derive(Clone, Copy, Debug)]
struct Set {
    start: usize,
    end: usize,
    bounds: Bounds,
    cbounds: Bounds,
    depth: usize,
    plan: Plan,
}

impl Set {
    fn len(&self) -> usize {
        self.end - self.start
    }
}

/// The output of a build.
pub(crate) struct Built<P> {
    pub binary: Vec<Node>,
    pub wide: Vec<WideNode>,
    pub packs: Vec<TriPack>,
    pub test: Option<TriangleTest>,
    pub prims: Vec<P>,
    pub ids: Vec<u32>,
    pub max_depth: usize,
    pub leaves: usize,
    pub valid: usize,
}

/// Build settings derived from the parameters and the input.
struct Ctx<'a, P> {
    prims: &'a [P],
    split: SplitMethod,
    bins: usize,
    traversal_cost: f32,
    intersection_cost: f32,
    max_leaf: usize,
    /// Primitives tested together at the cost of one (4 for triangle packs, else 1): the SAH
    /// prices a leaf by its number of packs.
    block: usize,
    /// Triangle packs for this test, when the wide tree packs its leaves.
    test: Option<TriangleTest>,
    parallel: bool,
}

/// Sets at least this large are binned in parallel chunks.
const PAR_BIN_MIN: usize = 1 << 15;
/// Chunks of the parallel binning.
const PAR_BIN_CHUNK: usize = 1 << 13;
/// Subtrees at least this large are built as parallel tasks.
const PAR_SUBTREE_MIN: usize = 1 << 12;

/// Builds the tree for `params`. Each set costs O(n) for its binning and partition and there are
/// O(log N) levels for balanced splits, so the build is O(N log N); the depth is bounded by
/// [`MAX_DEPTH`] (count splits take over when the budget runs short), so it is O(N · MAX_DEPTH)
/// at worst. Scratch memory: the 32-byte references and, per thread, one bin array.
pub(crate) fn build<P: Primitive>(prims: &[P], params: &BvhParams) -> Built<P> {
    let wide = params.layout == Layout::Wide;
    // Triangle packs when the wide tree is asked for and every valid primitive is a triangle
    // with the same test.
    let test = if wide {
        common_triangle_test(prims)
    } else {
        None
    };
    let max_leaf = match (wide, test) {
        (false, _) => params.max_leaf_size.clamp(1, 255) as usize,
        (true, Some(_)) => {
            (params.max_leaf_size as usize).clamp(1, PACK * ChildRef::MAX_LEAF_ITEMS)
        }
        (true, None) => (params.max_leaf_size as usize).clamp(1, ChildRef::MAX_LEAF_ITEMS),
    };
    let ctx = Ctx {
        prims,
        split: params.split,
        bins: params.bins.clamp(2, MAX_BINS as u32) as usize,
        traversal_cost: params.traversal_cost,
        intersection_cost: params.intersection_cost,
        max_leaf,
        block: if test.is_some() { PACK } else { 1 },
        test,
        parallel: params.parallel && rayon::current_num_threads() > 1,
    };
    let mut refs: Vec<PrimRef> = prims
        .iter()
        .enumerate()
        .take(u32::MAX as usize)
        .filter(|(_, p)| p.is_valid())
        .map(|(i, p)| {
            let b = p.bounds();
            PrimRef {
                min: b.min.to_array(),
                id: i as u32,
                max: b.max.to_array(),
                pad: 0,
            }
        })
        .collect();
    let valid = refs.len();
    let mut out = Built {
        binary: Vec::new(),
        wide: Vec::new(),
        packs: Vec::new(),
        test,
        prims: Vec::new(),
        ids: Vec::new(),
        max_depth: 0,
        leaves: 0,
        valid,
    };
    if refs.is_empty() {
        if !wide {
            // One empty, never-hit leaf, so the binary traversal needs no special case.
            out.binary.push(Node {
                bounds: Aabb::EMPTY,
                index: 0,
                count: 0,
                axis: 0,
                pad: 0,
            });
        }
        return out;
    }
    let mut root = Set {
        start: 0,
        end: refs.len(),
        bounds: Bounds::EMPTY,
        cbounds: Bounds::EMPTY,
        depth: 0,
        plan: Plan::Leaf,
    };
    for r in &refs {
        root.bounds = root.bounds.union(r.bounds());
        root.cbounds = root.cbounds.grow(r.center2());
    }
    let mut scratch = Bins::new();
    root.plan = plan(&ctx, &refs, 0, &root, &mut scratch);
    let mut shape = Shape::default();
    if wide {
        let mut o = WideOut::default();
        let root_ref = emit_wide(&ctx, &mut refs, 0, root, &mut o, &mut shape, &mut scratch);
        if root_ref.is_leaf() {
            // A tree of one leaf still starts at a node, so traversal always starts at node 0.
            let mut node = WideNode::EMPTY;
            set_child(&mut node, 0, &root.bounds, root_ref);
            node.order = octant_orders(&[root.bounds]);
            o.nodes.push(node);
        }
        out.wide = o.nodes;
        out.packs = o.packs;
    } else {
        let mut nodes = Vec::with_capacity(2 * refs.len().div_ceil(ctx.max_leaf.max(2)));
        emit_binary(
            &ctx,
            &mut refs,
            0,
            root,
            &mut nodes,
            &mut shape,
            &mut scratch,
        );
        nodes.shrink_to_fit();
        out.binary = nodes;
    }
    out.max_depth = shape.max_depth;
    out.leaves = shape.leaves;
    if test.is_none() {
        out.prims = refs.iter().map(|r| prims[r.id as usize].clone()).collect();
        out.ids = refs.iter().map(|r| r.id).collect();
    }
    out
}

/// The test of the triangle packs, when every valid primitive is a triangle with the same test.
fn common_triangle_test<P: Primitive>(prims: &[P]) -> Option<TriangleTest> {
    let mut test = None;
    for p in prims.iter().filter(|p| p.is_valid()) {
        let (_, t) = p.as_triangle()?;
        if *test.get_or_insert(t) != t {
            return None;
        }
    }
    test
}

/// Depth and leaf count of what was emitted.
#[derive(Clone, Copy, Default)]
struct Shape {
    max_depth: usize,
    leaves: usize,
}

impl Shape {
    fn merge(&mut self, o: Shape) {
        self.max_depth = self.max_depth.max(o.max_depth);
        self.leaves += o.leaves;
    }
}

const MAX_BINS: usize = 32;

/// SAH buckets per axis: their bounds and primitive counts.
#[derive(Clone)]
struct Bins {
    bounds: [[Bounds; MAX_BINS]; 3],
    counts: [[u32; MAX_BINS]; 3],
}

impl Bins {
    fn new() -> Self {
        Self {
            bounds: [[Bounds::EMPTY; MAX_BINS]; 3],
            counts: [[0; MAX_BINS]; 3],
        }
    }

    fn reset(&mut self, bins: usize) {
        for axis in 0..3 {
            self.bounds[axis][..bins].fill(Bounds::EMPTY);
            self.counts[axis][..bins].fill(0);
        }
    }

    #[inline(always)]
    fn add(&mut self, refs: &[PrimRef], map: &BinMap) {
        for r in refs {
            let b = r.bounds();
            let k = map.bins_of(b.min + b.max);
            for (axis, &k) in k.iter().enumerate() {
                self.counts[axis][k] += 1;
                self.bounds[axis][k] = self.bounds[axis][k].union(b);
            }
        }
    }

    fn merge(&mut self, o: &Bins, bins: usize) {
        for axis in 0..3 {
            for k in 0..bins {
                self.counts[axis][k] += o.counts[axis][k];
                self.bounds[axis][k] = self.bounds[axis][k].union(o.bounds[axis][k]);
            }
        }
    }
}

/// The mapping from doubled centres to buckets of one set.
#[derive(Clone, Copy)]
struct BinMap {
    lo: Vec3A,
    scale: Vec3A,
    max_bin: Vec3A,
}

impl BinMap {
    fn new(cbounds: &Bounds, bins: usize) -> Self {
        let extent = cbounds.max - cbounds.min;
        let bins_f = bins as f32;
        // A zero extent gives scale 0: every centre lands in bucket 0 on that axis.
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(bins_f) / extent,
            Vec3A::ZERO,
        );
        Self {
            lo: cbounds.min,
            scale,
            max_bin: Vec3A::splat(bins_f - 1.0),
        }
    }

    #[inline(always)]
    fn bins_of(&self, c2: Vec3A) -> [usize; 3] {
        let b = ((c2 - self.lo) * self.scale)
            .min(self.max_bin)
            .max(Vec3A::ZERO)
            .as_uvec3();
        [b.x as usize, b.y as usize, b.z as usize]
    }
}

fn ceil_log2(n: usize) -> usize {
    if n <= 1 {
        0
    } else {
        (usize::BITS - (n - 1).leading_zeros()) as usize
    }
}

/// Decides how `set` is split (or that it is a leaf).
///
/// Binned SAH (Wald 2007; pbrt-v4 §7.3): centres are projected into buckets on all three axes in
/// one pass, the planes between buckets are priced with `C_trav + C_isect · (A_L·B(N_L) +
/// A_R·B(N_R)) / A`, where `B(n)` counts blocks of [`Ctx::block`] primitives (leaves are tested
/// a pack at a time), and the set becomes a leaf when no plane beats `C_isect · B(N)` and it fits
/// in a leaf. A set too big for a leaf whose centres coincide is split by count, and so is any
/// set once the remaining depth budget only just fits a balanced split: that keeps every tree
/// within [`MAX_DEPTH`], the traversal stacks' bound.
fn plan<P>(ctx: &Ctx<'_, P>, refs: &[PrimRef], base: usize, set: &Set, scratch: &mut Bins) -> Plan {
    let n = set.len();
    if n <= 1 {
        return Plan::Leaf;
    }
    let forced = set.depth + ceil_log2(n.div_ceil(ctx.max_leaf)) + 1 >= MAX_DEPTH;
    if forced || ctx.split == SplitMethod::Median {
        return if n > ctx.max_leaf {
            Plan::Count
        } else {
            Plan::Leaf
        };
    }
    if ctx.split == SplitMethod::Middle {
        return if n > ctx.max_leaf {
            Plan::Middle
        } else {
            Plan::Leaf
        };
    }
    // PERF: a set of n primitives gets min(bins, max(n, 4)) buckets; a small set needs no more
    // planes than it has primitives, and initializing and sweeping 3 × 16 buckets dominated the
    // cost of the ~38k small nodes of the bunny: SAH build 51.6 ms -> 40.1 ms with the same tree
    // quality, measured with `cargo xtask compare --scene ../shared/meshes/stanford-bunny.obj`.
    let bins = ctx.bins.min(n.max(4));
    let extent = set.cbounds.max - set.cbounds.min;
    let map = BinMap::new(&set.cbounds, bins);
    let refs = &refs[set.start - base..set.end - base];
    if ctx.parallel && n >= PAR_BIN_MIN {
        let merged = refs
            .par_chunks(PAR_BIN_CHUNK)
            .fold(
                || {
                    let mut b = Bins::new();
                    b.reset(bins);
                    b
                },
                |mut b, chunk| {
                    b.add(chunk, &map);
                    b
                },
            )
            .reduce_with(|mut a, b| {
                a.merge(&b, bins);
                a
            });
        if let Some(m) = merged {
            *scratch = m;
        }
    } else {
        scratch.reset(bins);
        scratch.add(refs, &map);
    }
    let blocks = |count: u32| ((count as usize).div_ceil(ctx.block)) as f32;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, plane)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let (bb, bc) = (&scratch.bounds[axis], &scratch.counts[axis]);
        // Sweep from the right for the area-weighted blocks right of each plane, then from the
        // left to price each plane.
        let mut right_cost = [0.0f32; MAX_BINS];
        let mut acc = Bounds::EMPTY;
        let mut count = 0u32;
        for b in (1..bins).rev() {
            acc = acc.union(bb[b]);
            count += bc[b];
            right_cost[b] = acc.half_area() * blocks(count);
        }
        let mut acc = Bounds::EMPTY;
        let mut count = 0u32;
        for plane in 1..bins {
            acc = acc.union(bb[plane - 1]);
            count += bc[plane - 1];
            if count == 0 || count as usize == n {
                continue;
            }
            let cost = acc.half_area() * blocks(count) + right_cost[plane];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, plane));
            }
        }
    }
    let Some((cost, axis, plane)) = best else {
        return if n > ctx.max_leaf {
            Plan::Count
        } else {
            Plan::Leaf
        };
    };
    let split_cost = ctx.traversal_cost + ctx.intersection_cost * cost / set.bounds.half_area();
    let leaf_cost = ctx.intersection_cost * blocks(n as u32);
    // A NaN cost (a zero-area set) does not pay either.
    let split_pays = split_cost < leaf_cost;
    if n <= ctx.max_leaf && !split_pays {
        return Plan::Leaf;
    }
    Plan::Sah { axis, plane, bins }
}

/// Splits `set` by its plan (not [`Plan::Leaf`]), reordering its references, and plans both
/// halves.
fn split<P>(
    ctx: &Ctx<'_, P>,
    refs: &mut [PrimRef],
    base: usize,
    set: &Set,
    scratch: &mut Bins,
) -> (Set, Set) {
    let range = &mut refs[set.start - base..set.end - base];
    let n = range.len();
    let mid = match set.plan {
        Plan::Sah { axis, plane, bins } => {
            let map = BinMap::new(&set.cbounds, bins);
            partition(range, |r| map.bins_of(r.center2())[axis] < plane)
        }
        Plan::Middle => {
            let axis = set.cbounds.longest_axis();
            let middle = 0.5 * (set.cbounds.min[axis] + set.cbounds.max[axis]);
            partition(range, |r| r.center2()[axis] < middle)
        }
        Plan::Count | Plan::Leaf => n / 2,
    };
    // A count split, and any split that left a side empty (unreachable for SAH by
    // construction; possible for the middle split of coinciding centres): half by count.
    let mid = if set.plan == Plan::Count || mid == 0 || mid == n {
        let axis = set.cbounds.longest_axis();
        range.select_nth_unstable_by(n / 2, |a, b| {
            a.center2()[axis].total_cmp(&b.center2()[axis])
        });
        n / 2
    } else {
        mid
    };
    let side = |start: usize, end: usize, refs: &[PrimRef]| {
        let mut s = Set {
            start,
            end,
            bounds: Bounds::EMPTY,
            cbounds: Bounds::EMPTY,
            depth: set.depth + 1,
            plan: Plan::Leaf,
        };
        for r in &refs[start - base..end - base] {
            s.bounds = s.bounds.union(r.bounds());
            s.cbounds = s.cbounds.grow(r.center2());
        }
        s
    };
    let mut left = side(set.start, set.start + mid, refs);
    let mut right = side(set.start + mid, set.end, refs);
    left.plan = plan(ctx, refs, base, &left, scratch);
    right.plan = plan(ctx, refs, base, &right, scratch);
    (left, right)
}

/// Moves the references for which `go_left` holds to the front; returns how many there are.
#[inline(always)]
fn partition(refs: &mut [PrimRef], go_left: impl Fn(&PrimRef) -> bool) -> usize {
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        if go_left(&refs[i]) {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    i
}

/// Emits the binary subtree of `set` depth first (first child right after its parent). `refs`
/// holds the references from absolute index `base` on.
fn emit_binary<P: Primitive>(
    ctx: &Ctx<'_, P>,
    refs: &mut [PrimRef],
    base: usize,
    set: Set,
    out: &mut Vec<Node>,
    shape: &mut Shape,
    scratch: &mut Bins,
) {
    shape.max_depth = shape.max_depth.max(set.depth);
    let index = out.len();
    if set.plan == Plan::Leaf {
        shape.leaves += 1;
        out.push(Node {
            bounds: set.bounds.to_aabb(),
            index: set.start as u32,
            count: set.len() as u16,
            axis: 0,
            pad: 0,
        });
        return;
    }
    let axis = match set.plan {
        Plan::Sah { axis, .. } => axis,
        _ => set.cbounds.longest_axis(),
    };
    let (left, right) = split(ctx, refs, base, &set, scratch);
    out.push(Node {
        bounds: set.bounds.to_aabb(),
        index: 0,
        count: 0,
        axis: axis as u8,
        pad: 0,
    });
    if ctx.parallel && left.len().min(right.len()) >= PAR_SUBTREE_MIN {
        let (lo, hi) = refs.split_at_mut(right.start - base);
        let task = |refs: &mut [PrimRef], base: usize, s: Set| {
            let (mut v, mut sh) = (Vec::new(), Shape::default());
            emit_binary(ctx, refs, base, s, &mut v, &mut sh, &mut Bins::new());
            (v, sh)
        };
        let ((lv, ls), (rv, rs)) =
            rayon::join(|| task(lo, base, left), || task(hi, right.start, right));
        for (first, (v, s)) in [(true, (lv, ls)), (false, (rv, rs))] {
            let offset = out.len() as u32;
            if !first {
                out[index].index = offset;
            }
            out.extend(v.into_iter().map(|mut n| {
                if !n.is_leaf() {
                    n.index += offset;
                }
                n
            }));
            shape.merge(s);
        }
    } else {
        emit_binary(ctx, refs, base, left, out, shape, scratch);
        out[index].index = out.len() as u32;
        emit_binary(ctx, refs, base, right, out, shape, scratch);
    }
}

/// The wide tree's output arrays.
#[derive(Default)]
struct WideOut {
    nodes: Vec<WideNode>,
    packs: Vec<TriPack>,
}

/// Emits the wide subtree of `set` and returns the reference to it: a leaf, or a node whose
/// children are the sets left after splitting the largest child until there are eight. `refs`
/// holds the references from absolute index `base` on.
fn emit_wide<P: Primitive>(
    ctx: &Ctx<'_, P>,
    refs: &mut [PrimRef],
    base: usize,
    set: Set,
    out: &mut WideOut,
    shape: &mut Shape,
    scratch: &mut Bins,
) -> ChildRef {
    shape.max_depth = shape.max_depth.max(set.depth);
    if set.plan == Plan::Leaf {
        shape.leaves += 1;
        return emit_leaf(ctx, &refs[set.start - base..set.end - base], &set, out);
    }
    let mut kids: Vec<Set> = Vec::with_capacity(WIDTH);
    let (l, r) = split(ctx, refs, base, &set, scratch);
    kids.extend([l, r]);
    while kids.len() < WIDTH {
        let mut largest: Option<(usize, f32)> = None;
        for (i, k) in kids.iter().enumerate() {
            let area = k.bounds.half_area();
            if k.plan != Plan::Leaf && largest.is_none_or(|(_, a)| area > a) {
                largest = Some((i, area));
            }
        }
        let Some((i, _)) = largest else { break };
        let (l, r) = split(ctx, refs, base, &kids[i], scratch);
        kids[i] = l;
        kids.insert(i + 1, r);
    }
    let index = out.nodes.len();
    out.nodes.push(WideNode::EMPTY);
    let mut node = WideNode::EMPTY;
    let boxes: Vec<Bounds> = kids.iter().map(|k| k.bounds).collect();
    node.order = octant_orders(&boxes);
    let big = kids.iter().filter(|k| k.len() >= PAR_SUBTREE_MIN).count();
    if ctx.parallel && big >= 2 {
        // Each child into its own arrays, concurrently; then appended in order, which is where a
        // sequential build would have written them.
        let mut slices = Vec::with_capacity(kids.len());
        let mut rest = refs;
        let mut at = base;
        for k in &kids {
            let (_, tail) = std::mem::take(&mut rest).split_at_mut(k.start - at);
            let (mine, tail) = tail.split_at_mut(k.len());
            slices.push((mine, *k));
            rest = tail;
            at = k.end;
        }
        let parts: Vec<(ChildRef, WideOut, Shape)> = slices
            .into_par_iter()
            .map(|(slice, k)| {
                let mut o = WideOut::default();
                let mut sh = Shape::default();
                let c = emit_wide(ctx, slice, k.start, k, &mut o, &mut sh, &mut Bins::new());
                (c, o, sh)
            })
            .collect();
        for (i, (c, o, sh)) in parts.into_iter().enumerate() {
            let c = append(ctx, out, o, c);
            set_child(&mut node, i, &kids[i].bounds, c);
            shape.merge(sh);
        }
    } else {
        for (i, k) in kids.iter().enumerate() {
            let c = emit_wide(ctx, refs, base, *k, out, shape, scratch);
            set_child(&mut node, i, &k.bounds, c);
        }
    }
    out.nodes[index] = node;
    ChildRef::node(index as u32)
}

/// Appends a subtree built into its own arrays, relocating its node and pack indices; returns
/// the relocated reference to its root.
fn append<P>(ctx: &Ctx<'_, P>, out: &mut WideOut, part: WideOut, root: ChildRef) -> ChildRef {
    let node_offset = out.nodes.len() as u32;
    let pack_offset = out.packs.len() as u32;
    let relocate = |c: ChildRef| {
        if c == ChildRef::EMPTY {
            c
        } else if c.is_leaf() {
            if ctx.test.is_some() {
                let items = c.items();
                ChildRef::leaf(items.start as u32 + pack_offset, items.len() as u32)
            } else {
                c
            }
        } else {
            ChildRef::node(c.0 + node_offset)
        }
    };
    out.nodes.extend(part.nodes.into_iter().map(|mut n| {
        for ch in &mut n.children {
            *ch = relocate(ChildRef(*ch)).0;
        }
        n
    }));
    out.packs.extend(part.packs);
    relocate(root)
}

/// A leaf: its triangles packed four to a pack, or its range of references.
fn emit_leaf<P: Primitive>(
    ctx: &Ctx<'_, P>,
    range: &[PrimRef],
    set: &Set,
    out: &mut WideOut,
) -> ChildRef {
    match ctx.test {
        Some(test) => {
            let first = out.packs.len();
            for chunk in range.chunks(PACK) {
                let mut tris = [(Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO), 0u32); PACK];
                for (slot, r) in tris.iter_mut().zip(chunk) {
                    let (t, _) = ctx.prims[r.id as usize]
                        .as_triangle()
                        .expect("every primitive of a packed tree is a triangle");
                    *slot = (t, r.id);
                }
                out.packs.push(TriPack::new(&tris[..chunk.len()], test));
            }
            ChildRef::leaf(first as u32, (out.packs.len() - first) as u32)
        }
        None => ChildRef::leaf(set.start as u32, set.len() as u32),
    }
}

fn set_child(node: &mut WideNode, i: usize, b: &Bounds, c: ChildRef) {
    let (min, max) = (b.min.to_array(), b.max.to_array());
    for a in 0..3 {
        node.bounds[a][i] = min[a];
        node.bounds[3 + a][i] = max[a];
    }
    node.children[i] = c.0;
}

/// For each of the eight ray octants, the children ordered by how early a ray of that octant
/// meets their centres (the projection of the centre on the octant's diagonal), as nibbles.
fn octant_orders(boxes: &[Bounds]) -> [u32; WIDTH] {
    let mut orders = [0u32; WIDTH];
    for (octant, order) in orders.iter_mut().enumerate() {
        let d = Vec3A::new(
            if octant & 1 != 0 { -1.0 } else { 1.0 },
            if octant & 2 != 0 { -1.0 } else { 1.0 },
            if octant & 4 != 0 { -1.0 } else { 1.0 },
        );
        let mut idx: Vec<usize> = (0..boxes.len()).collect();
        let key = |i: usize| (boxes[i].min + boxes[i].max).dot(d);
        idx.sort_by(|&a, &b| key(a).total_cmp(&key(b)));
        // Empty lanes last; they are never entered.
        idx.extend(boxes.len()..WIDTH);
        *order = idx
            .iter()
            .enumerate()
            .fold(0, |acc, (k, &i)| acc | (i as u32) << (4 * k));
    }
    orders
}

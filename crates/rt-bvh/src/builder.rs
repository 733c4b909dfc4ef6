//! Top-down construction of the binary and the 8-wide tree from one split routine.
//!
//! Every set of primitives is split in two (binned SAH, median or middle), and gets its own split
//! planned as soon as it exists. The binary tree emits each split as a node. The wide tree starts
//! a node from one split and keeps splitting the child with the largest surface area until the
//! node has eight children or none can be split (Wald et al. 2008; Embree's BVH8 builder), so it
//! is the binary tree collapsed, built without the binary tree in between.
//!
//! Parallelism (rayon): the binning of large sets is split into chunks whose bins are merged, and
//! subtrees of many primitives are built concurrently into their own arrays, appended (moved,
//! not copied) in the order a sequential build would write them, and copied into place once when
//! the tree is finished. Bins merge exactly (minima, maxima and
//! counts do not depend on the order they are combined in), and partitions run sequentially, so
//! the tree is the same, byte for byte, whatever the number of threads.

mod reinsert;

use crate::node::{ChildRef, Node, PACK, TriPack, WIDTH, WideNode};
use crate::{BvhParams, Layout, MAX_DEPTH, SplitMethod};
use rt_core::glam::{Vec3, Vec3A};
use rt_core::par;
use rt_core::{Aabb, Geometry, Primitive, Triangle, TriangleTest};

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
    const ZERO: Self = Self {
        min: [0.0; 3],
        id: 0,
        max: [0.0; 3],
        pad: 0,
    };

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
    /// The triangles are known to be distinct (see [`dedup`]).
    unique: bool,
}

impl Set {
    fn len(&self) -> usize {
        self.end - self.start
    }
}

/// The output of a build: the tree, and its primitives in leaf order (for trees whose leaves
/// are not triangle packs).
pub(crate) struct Built<P> {
    pub tree: Tree,
    pub prims: Vec<P>,
}

/// The tree a build makes, whatever the primitive type.
pub(crate) struct Tree {
    pub binary: Vec<Node>,
    pub wide: Vec<WideNode>,
    pub packs: Vec<TriPack>,
    pub test: Option<TriangleTest>,
    /// The input indices of the leaves' primitives, in leaf order (empty for packs).
    pub ids: Vec<u32>,
    pub max_depth: usize,
    pub leaves: usize,
    pub valid: usize,
    /// The primitives the tree holds: the valid ones but for bit-identical copies of a triangle
    /// (see [`dedup`]).
    pub stored: usize,
}

/// What the build reads of the primitives once their references are made: the vertices of a
/// triangle, for the packs and for finding copies ([`dedup`]).
///
/// The build reaches the primitives through this trait object rather than a type parameter, so
/// that everything after [`make_refs`] is compiled once, in this crate, and not again for every
/// primitive and geometry type a program builds trees of (with rayon's machinery for each of
/// its parallel calls).
// PERF: rt-bvh's test suite compiles 586k lines of LLVM IR instead of 1.0M, and a program that
// builds and traces one tree (the `large` example, release) in 8.5–9.6 s instead of 10.3–10.6
// s. The build's time did not move (new ÷ old, one thread, medians of five processes: bunny
// 1.017, teapot 1.007, sphereflake 1.025, teapot in a stadium 1.011).
trait Triangles: Sync {
    /// The triangle of input index `id`, which the references say is one.
    fn triangle(&self, id: u32) -> Triangle;
}

/// A geometry as [`Triangles`].
struct Source<'a, G: ?Sized>(&'a G);

impl<G: Geometry + ?Sized> Triangles for Source<'_, G> {
    fn triangle(&self, id: u32) -> Triangle {
        let (t, _) = self
            .0
            .prim(id as usize)
            .as_triangle()
            .expect("the references say this primitive is a triangle");
        t
    }
}

/// Build settings derived from the parameters and the input.
struct Ctx<'a> {
    prims: &'a dyn Triangles,
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
    /// Every valid primitive is a triangle, so bit-identical copies can be found (see
    /// [`dedup`]).
    triangles: bool,
    parallel: bool,
}

/// Inputs at least this large are built in parallel (when asked and threads are available).
const PAR_BUILD_MIN: usize = 1 << 14;
/// Sets at least this large are binned in parallel chunks.
const PAR_BIN_MIN: usize = 1 << 15;
/// Chunks of the parallel binning.
const PAR_BIN_CHUNK: usize = 1 << 13;
/// Subtrees at least this large are built as parallel tasks.
const PAR_SUBTREE_MIN: usize = 1 << 11;
/// A wide node whose children hold at least this many references together builds them as
/// parallel tasks, however they divide them.
// PERF: the rule was "at least two children of `PAR_SUBTREE_MIN`", under which up to eight
// children of 2047 references (16k, a quarter of the bunny) were built on one thread while the
// other waited: perf's samples put one thread alone for 24% of a 2-thread bunny build, 7% with
// this rule. With this rule alone the extra subtrees' copies ate the gain (terrain 1.01x,
// sphereflake 1.025x the time); appending them without copying (`WideOut`) keeps the CPU time
// of the old rule. Both: 2-thread bunny builds 0.95x the time (farm-bench, median of 21 pairs
// of processes of 150 builds; AMD Zen 3), terrain and sphereflake 0.98-1.01x, one thread
// 1.01x; 2048 or 1024 here measured the same as 4096.
const PAR_WIDE_MIN: usize = 1 << 12;

/// Builds the tree for `params`. Each set costs O(n) for its binning and partition and there are
/// O(log N) levels for balanced splits, so the build is O(N log N); the depth is bounded by
/// [`MAX_DEPTH`] (count splits take over when the budget runs short), so it is O(N · MAX_DEPTH)
/// at worst. Scratch memory: the 32-byte references and, per task, two bin arrays and a
/// partition buffer of up to [`CHUNKED_PARTITION_MIN`] references (512 KB).
pub(crate) fn build<G: Geometry + ?Sized>(prims: &G, params: &BvhParams) -> Built<G::Prim> {
    // PERF: below PAR_BUILD_MIN primitives the parallel build's overhead outweighs its gain
    // (teapot, 6,320 triangles: 1.1 ms sequential, 1.2 ms on 2 threads).
    let parallel = params.parallel && par::threads() > 1 && prims.len() >= PAR_BUILD_MIN;
    let refs = make_refs(prims, parallel);
    let tree = build_refs(&Source(prims), refs, params, parallel);
    let prims = tree.ids.iter().map(|&id| prims.prim(id as usize)).collect();
    Built { tree, prims }
}

/// [`build`] from the references on: everything that does not depend on the primitive type.
fn build_refs(prims: &dyn Triangles, refs: Refs, params: &BvhParams, parallel: bool) -> Tree {
    let wide = params.layout == Layout::Wide;
    let Refs {
        mut refs,
        tests,
        bounds,
        cbounds,
    } = refs;
    // Triangle packs when the wide tree is asked for and every valid primitive is a triangle
    // with the same test.
    let test = match tests {
        Tests::One(t) if wide => Some(t),
        _ => None,
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
        triangles: matches!(tests, Tests::One(_)),
        parallel,
    };
    let valid = refs.len();
    let mut out = Tree {
        binary: Vec::new(),
        wide: Vec::new(),
        packs: Vec::new(),
        test,
        ids: Vec::new(),
        max_depth: 0,
        leaves: 0,
        valid,
        stored: 0,
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
        bounds,
        cbounds,
        depth: 0,
        plan: Plan::Leaf,
        unique: false,
    };
    let mut scratch = Scratch::new();
    plan_set(&ctx, &mut refs, &mut root, &mut scratch);
    let mut shape = Shape::default();
    let planned = if params.reinsertion_passes > 0 && root.plan != Plan::Leaf {
        reinsert::optimized(
            &ctx,
            &mut refs,
            root,
            params.reinsertion_passes,
            &mut scratch,
        )
    } else {
        Planned::new(root)
    };
    if wide {
        let mut o = WideOut::default();
        let root_ref = emit_wide(
            &ctx,
            &mut refs,
            0,
            planned,
            &mut o,
            &mut shape,
            &mut scratch,
        );
        if root_ref.is_leaf() {
            // A tree of one leaf still starts at a node, so traversal always starts at node 0.
            let slot = o.reserve_node();
            set_child(o.node_mut(slot), 0, &root.bounds, root_ref);
        }
        (out.wide, out.packs) = o.finish(ctx.test.is_some());
    } else {
        let mut nodes = Vec::with_capacity(2 * refs.len().div_ceil(ctx.max_leaf.max(2)));
        emit_binary(
            &ctx,
            &mut refs,
            0,
            planned,
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
        if !wide {
            compact_binary(&mut out.binary, &mut refs);
        }
        out.ids = refs.iter().map(|r| r.id).collect();
    }
    out.stored = if test.is_some() {
        out.packs.iter().map(TriPack::len).sum()
    } else {
        out.ids.len()
    };
    out
}

/// Drops the references no leaf holds (copies left out by [`dedup`]) from the binary tree's
/// reference array, moving the leaves' ranges down to match. Leaves never straddle a dropped
/// reference, so each range stays contiguous.
fn compact_binary(nodes: &mut [Node], refs: &mut Vec<PrimRef>) {
    let mut held = vec![false; refs.len()];
    for n in nodes.iter().filter(|n| n.is_leaf()) {
        held[n.prim_range()].fill(true);
    }
    if held.iter().all(|&h| h) {
        return;
    }
    // New index of each reference: how many held references come before it.
    let mut new_index = Vec::with_capacity(refs.len());
    let mut next = 0u32;
    for &h in &held {
        new_index.push(next);
        next += u32::from(h);
    }
    for n in nodes.iter_mut().filter(|n| n.is_leaf()) {
        n.index = new_index[n.index as usize];
    }
    let mut k = 0;
    refs.retain(|_| {
        k += 1;
        held[k - 1]
    });
}

/// What the valid primitives say of [`Primitive::as_triangle`].
#[derive(Clone, Copy, Debug, PartialEq)]
enum Tests {
    /// No valid primitive.
    Empty,
    /// All are triangles with this test.
    One(TriangleTest),
    /// Some are not triangles, or the tests differ.
    Mixed,
}

impl Tests {
    fn and(self, o: Tests) -> Tests {
        match (self, o) {
            (Tests::Empty, x) | (x, Tests::Empty) => x,
            (Tests::One(a), Tests::One(b)) if a == b => self,
            _ => Tests::Mixed,
        }
    }
}

/// References per chunk of the reference pass's summary.
const REFS_CHUNK: usize = 1 << 13;

/// [`PrimRef::pad`] during the reference pass: what the primitive is.
const INVALID: u32 = 0;
const WATERTIGHT: u32 = 1;
const MOLLER_TRUMBORE: u32 = 2;
const OTHER: u32 = 3;

/// The references to the valid primitives among the first 2³² - 1, in input order, what they
/// say of `as_triangle`, and their bounds. On rayon's threads when `parallel` (the result is the
/// same either way): every primitive is mapped to a reference in place, its kind kept in the
/// reference's spare word; the references are summarised chunk by chunk; invalid ones, if any,
/// are then dropped in one sequential pass.
///
/// PERF: gathering each chunk's valid references into its own vector and concatenating them
/// took 0.68 ms on 2 threads for the sphereflake, no faster than the sequential 0.61 ms.
fn make_refs<G: Geometry + ?Sized>(prims: &G, parallel: bool) -> Refs {
    let n = prims.len().min(u32::MAX as usize);
    let make = |i: usize| {
        let p = prims.prim(i);
        let kind = if !p.is_valid() {
            INVALID
        } else {
            match p.as_triangle() {
                Some((_, TriangleTest::Watertight)) => WATERTIGHT,
                Some((_, TriangleTest::MollerTrumbore)) => MOLLER_TRUMBORE,
                None => OTHER,
            }
        };
        let b = if kind == INVALID {
            Aabb::EMPTY
        } else {
            p.bounds()
        };
        PrimRef {
            min: b.min.to_array(),
            id: i as u32,
            max: b.max.to_array(),
            pad: kind,
        }
    };
    let refs: Vec<PrimRef> = if parallel {
        par::map_range(0..n, make)
    } else {
        (0..n).map(make).collect()
    };
    summarize(refs, parallel)
}

/// The part of [`make_refs`] that does not depend on the primitive type: what the references
/// say of `as_triangle`, their bounds, and the invalid ones dropped.
fn summarize(refs: Vec<PrimRef>, parallel: bool) -> Refs {
    let summary = |c: &[PrimRef]| {
        let mut s = Refs {
            refs: Vec::new(),
            tests: Tests::Empty,
            bounds: Bounds::EMPTY,
            cbounds: Bounds::EMPTY,
        };
        let mut invalid = 0;
        for r in c {
            let t = match r.pad {
                INVALID => {
                    invalid += 1;
                    continue;
                }
                WATERTIGHT => Tests::One(TriangleTest::Watertight),
                MOLLER_TRUMBORE => Tests::One(TriangleTest::MollerTrumbore),
                _ => Tests::Mixed,
            };
            s.tests = s.tests.and(t);
            s.bounds = s.bounds.union(r.bounds());
            s.cbounds = s.cbounds.grow(r.center2());
        }
        (s, invalid)
    };
    let merge = |(a, ia): (Refs, usize), (b, ib): (Refs, usize)| {
        let r = Refs {
            refs: Vec::new(),
            tests: a.tests.and(b.tests),
            bounds: a.bounds.union(b.bounds),
            cbounds: a.cbounds.union(b.cbounds),
        };
        (r, ia + ib)
    };
    let (mut all, invalid) = if parallel {
        par::map_chunks(&refs, REFS_CHUNK, summary)
            .into_iter()
            .reduce(merge)
            .unwrap_or_else(|| summary(&[]))
    } else {
        summary(&refs)
    };
    all.refs = refs;
    if invalid > 0 {
        all.refs.retain(|r| r.pad != INVALID);
    }
    all
}

/// The references of [`make_refs`], what they say of `as_triangle`, and their bounds.
struct Refs {
    refs: Vec<PrimRef>,
    tests: Tests,
    bounds: Bounds,
    cbounds: Bounds,
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

    /// Bins `refs` into `self`, every other reference into `spare` (then merged into `self`).
    ///
    /// PERF: neighbouring triangles usually land in the same bucket, so with one set of bins
    /// each update waits for the previous one to be stored; alternating two sets halves that
    /// chain (Embree does the same). Bunny, single-threaded build: 26.9 -> see the commit.
    #[inline(always)]
    fn add(&mut self, spare: &mut Bins, refs: &[PrimRef], map: &BinMap, bins: usize) {
        spare.reset(bins);
        let mut pairs = refs.chunks_exact(2);
        for pair in &mut pairs {
            self.add_one(&pair[0], map);
            spare.add_one(&pair[1], map);
        }
        for r in pairs.remainder() {
            self.add_one(r, map);
        }
        self.merge(spare, bins);
    }

    #[inline(always)]
    fn add_one(&mut self, r: &PrimRef, map: &BinMap) {
        let b = r.bounds();
        let k = map.bins_of(b.min + b.max);
        for (axis, &k) in k.iter().enumerate() {
            self.counts[axis][k] += 1;
            self.bounds[axis][k] = self.bounds[axis][k].union(b);
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

/// A task's reusable buffers: two sets of bins (see [`Bins::add`]), boxed as each is 3.4 KB,
/// and the buffer of [`partition`] (below [`CHUNKED_PARTITION_MIN`] references: 512 KB).
struct Scratch {
    bins: Box<Bins>,
    spare: Box<Bins>,
    part: Vec<PrimRef>,
}

impl Scratch {
    fn new() -> Self {
        Self {
            bins: Box::new(Bins::new()),
            spare: Box::new(Bins::new()),
            part: Vec::new(),
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
/// in a leaf. A set of one block or less is a leaf without pricing a plane (Embree's minimum
/// leaf size for its four-triangle leaves). A set too big for a leaf whose centres coincide is
/// split by count, and so is any set once the remaining depth budget only just fits a balanced
/// split: that keeps every tree within [`MAX_DEPTH`], the traversal stacks' bound.
fn plan(ctx: &Ctx<'_>, refs: &[PrimRef], base: usize, set: &Set, scratch: &mut Scratch) -> Plan {
    let n = set.len();
    // One pack is one test however it is split, and splitting it pays only when its two parts'
    // boxes are far smaller than its own, which scanned and modelled meshes almost never show.
    // PERF: one-thread builds 0.88-0.93 of the time before on the ten meshes (bunny, teapot,
    // sphereflake, teapot in a stadium, beetle, rocker arm, cheburashka, fandisk, homer, spot; in
    // one process, medians of 3 processes), the bunny's tree unchanged, and trace speed
    // 0.99-1.01 of before on the four peer scenes and three ray kinds.
    if n <= ctx.block.min(ctx.max_leaf) {
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
    // PERF: a set of n primitives gets min(bins, 4 + n / 20) buckets (Embree's rule): the many
    // small sets need few planes, and resetting and sweeping 3 × 16 buckets dominated their cost.
    let bins = ctx.bins.min(4 + n / 20);
    let extent = set.cbounds.max - set.cbounds.min;
    let map = BinMap::new(&set.cbounds, bins);
    let refs = &refs[set.start - base..set.end - base];
    if ctx.parallel && n >= PAR_BIN_MIN {
        *scratch = par::fold_chunks(
            refs,
            PAR_BIN_CHUNK,
            || {
                let mut b = Scratch::new();
                b.bins.reset(bins);
                b
            },
            |mut b, chunk| {
                b.bins.add(&mut b.spare, chunk, &map, bins);
                b
            },
            |mut a, b| {
                a.bins.merge(&b.bins, bins);
                a
            },
        );
    } else if n >= 64 {
        scratch.bins.reset(bins);
        scratch.bins.add(&mut scratch.spare, refs, &map, bins);
    } else {
        scratch.bins.reset(bins);
        for r in refs {
            scratch.bins.add_one(r, &map);
        }
    }
    let blocks = |count: u32| ((count as usize).div_ceil(ctx.block)) as f32;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, plane)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let (bb, bc) = (&scratch.bins.bounds[axis], &scratch.bins.counts[axis]);
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

/// Plans `set`, whose references are exactly `refs`: first, if its box centres all coincide
/// and it is too big for a leaf, it drops bit-identical copies of its triangles ([`dedup`]),
/// which shortens it; then [`plan`].
fn plan_set(ctx: &Ctx<'_>, refs: &mut [PrimRef], set: &mut Set, scratch: &mut Scratch) {
    if ctx.triangles
        && !set.unique
        && set.len() > ctx.max_leaf
        && set.cbounds.min == set.cbounds.max
    {
        let kept = dedup(ctx, refs);
        set.end = set.start + kept;
        set.unique = true;
    }
    set.plan = plan(ctx, refs, set.start, set, scratch);
}

/// Moves one reference per distinct triangle among `refs` to the front, the one with the
/// smallest input index; returns how many there are. The others are left out of the tree.
///
/// Bit-identical triangles give bit-identical answers to every ray (the same `t`, `u`, `v`;
/// the same occlusion), so only the copy with the smallest index can ever be the closest hit
/// (it wins every tie), and any copy answers an any-hit query as well as another. Left in, a
/// million copies of one triangle made one closest-hit ray test every copy, because a hit at
/// an equal `t` on a smaller index must still be looked for: 1,000,000 tests and 159k node
/// visits, 10 ms. Copies pile up in sets whose box centres coincide, which is the only place
/// this looks. Triangles with the same vertices in another order are not copies: their answers
/// may differ in the last bit.
fn dedup(ctx: &Ctx<'_>, refs: &mut [PrimRef]) -> usize {
    let key = |r: &PrimRef| {
        let t = ctx.prims.triangle(r.id);
        let bits = [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits));
        (bits, r.id)
    };
    refs.sort_by_cached_key(key);
    let mut kept = 0;
    for i in 0..refs.len() {
        if kept == 0 || key(&refs[i]).0 != key(&refs[kept - 1]).0 {
            refs.swap(kept, i);
            kept += 1;
        }
    }
    kept
}

/// Splits `set` by its plan (not [`Plan::Leaf`]), reordering its references, and plans both
/// halves.
fn split(
    ctx: &Ctx<'_>,
    refs: &mut [PrimRef],
    base: usize,
    set: &Set,
    scratch: &mut Scratch,
) -> (Set, Set) {
    let range = &mut refs[set.start - base..set.end - base];
    let n = range.len();
    let parted = match set.plan {
        Plan::Sah { axis, plane, bins } => {
            // The bucket of x = (c - lo) · scale is floor(clamp(x, 0, bins - 1)), and for
            // 1 <= plane <= bins - 1 that is below `plane` exactly when x < plane: the same
            // decision as the binning, on one axis, without the conversion.
            let map = BinMap::new(&set.cbounds, bins);
            let (lo, scale, plane) = (map.lo[axis], map.scale[axis], plane as f32);
            Some(partition_any(
                ctx.parallel,
                range,
                &mut scratch.part,
                |c2| (c2[axis] - lo) * scale < plane,
            ))
        }
        Plan::Middle => {
            let axis = set.cbounds.longest_axis();
            let middle = 0.5 * (set.cbounds.min[axis] + set.cbounds.max[axis]);
            Some(partition_any(
                ctx.parallel,
                range,
                &mut scratch.part,
                |c2| c2[axis] < middle,
            ))
        }
        Plan::Count | Plan::Leaf => None,
    };
    // A count split, and any split that left a side empty (unreachable for SAH by
    // construction; possible for the middle split of coinciding centres): half by count, and
    // the halves' bounds in a second pass.
    let (mid, lb, rb) = match parted {
        Some(p) if p.left_count > 0 && p.left_count < n => (p.left_count, p.left, p.right),
        _ => {
            let axis = set.cbounds.longest_axis();
            range.select_nth_unstable_by(n / 2, |a, b| {
                a.center2()[axis].total_cmp(&b.center2()[axis])
            });
            let (l, r) = range.split_at(n / 2);
            (n / 2, side_bounds(l), side_bounds(r))
        }
    };
    let side = |start: usize, end: usize, (bounds, cbounds): (Bounds, Bounds)| Set {
        start,
        end,
        bounds,
        cbounds,
        depth: set.depth + 1,
        plan: Plan::Leaf,
        unique: set.unique,
    };
    let mut left = side(set.start, set.start + mid, lb);
    let mut right = side(set.start + mid, set.end, rb);
    let (lrefs, rrefs) = refs[set.start - base..set.end - base].split_at_mut(mid);
    if ctx.parallel && left.len().min(right.len()) >= PAR_SUBTREE_MIN {
        // Both halves' binning at once: a wide node makes up to seven splits before its
        // children can be built in parallel, and the first ones are over large sets.
        par::join(
            || plan_set(ctx, lrefs, &mut left, scratch),
            || plan_set(ctx, rrefs, &mut right, &mut Scratch::new()),
        );
    } else {
        plan_set(ctx, lrefs, &mut left, scratch);
        plan_set(ctx, rrefs, &mut right, scratch);
    }
    (left, right)
}

/// The bounds and centre bounds of some references.
fn side_bounds(refs: &[PrimRef]) -> (Bounds, Bounds) {
    refs.iter()
        .fold((Bounds::EMPTY, Bounds::EMPTY), |(b, c), r| {
            (b.union(r.bounds()), c.grow(r.center2()))
        })
}

/// Sets at least this large are partitioned in chunks (see [`partition_any`]).
const CHUNKED_PARTITION_MIN: usize = 1 << 14;
/// The chunk size of the chunked partition.
const PARTITION_CHUNK: usize = 1 << 12;

/// Partitions `refs` by `go_left`: a set of fewer than [`CHUNKED_PARTITION_MIN`] references
/// with [`partition`] and `part` as its buffer; a larger one in fixed chunks, each partitioned
/// in place on its own ([`partition_in_place`], on rayon's threads when `parallel`), then the
/// references on the wrong side of the split point swapped pairwise. The chunks do not depend
/// on the thread count, so neither does the result, and a sequential build makes the same tree.
fn partition_any(
    parallel: bool,
    refs: &mut [PrimRef],
    part: &mut Vec<PrimRef>,
    go_left: impl Fn(Vec3A) -> bool + Sync,
) -> Parted {
    let n = refs.len();
    if n < CHUNKED_PARTITION_MIN {
        return partition(refs, room(part, n), go_left);
    }
    let parts: Vec<_> = if parallel {
        par::map_chunks_mut(refs, PARTITION_CHUNK, |c| partition_in_place(c, &go_left))
    } else {
        refs.chunks_mut(PARTITION_CHUNK)
            .map(|c| partition_in_place(c, &go_left))
            .collect()
    };
    let mut left = (Bounds::EMPTY, Bounds::EMPTY);
    let mut right = (Bounds::EMPTY, Bounds::EMPTY);
    let mut total = 0;
    // (start, end) of each chunk's right part and left part.
    let mut rights = Vec::with_capacity(parts.len());
    let mut lefts = Vec::with_capacity(parts.len());
    for (k, p) in parts.iter().enumerate() {
        let Parted {
            left_count: count,
            left: l,
            right: r,
        } = *p;
        left = (left.0.union(l.0), left.1.union(l.1));
        right = (right.0.union(r.0), right.1.union(r.1));
        total += count;
        let start = k * PARTITION_CHUNK;
        let end = (start + PARTITION_CHUNK).min(n);
        lefts.push((start, start + count));
        rights.push((start + count, end));
    }
    // Right-side references before the split point trade places, in order, with left-side
    // references after it: there are as many of one as of the other.
    let misplaced_right = rights.iter().flat_map(|&(s, e)| s.min(total)..e.min(total));
    let misplaced_left = lefts.iter().flat_map(|&(s, e)| s.max(total)..e.max(total));
    for (i, j) in misplaced_right.zip(misplaced_left) {
        refs.swap(i, j);
    }
    Parted {
        left_count: total,
        left,
        right,
    }
}

/// Moves the references whose doubled centre satisfies `go_left` to the front with a branch on
/// each one's side and no buffer, accumulating both sides' bounds and centre bounds.
///
/// The chunks of a large set use this rather than [`partition`]: a chunk with its buffer beside
/// it no longer stays in the L2 cache with the rest of the set, and on two threads a buffer as
/// large as the set cost more to allocate and fault in than the mispredictions it saved. (PERF:
/// with the buffered partition for chunks too, the sphereflake's one-thread build took 1.04 of
/// the branching one's time and its two-thread build 1.17.)
#[inline(always)]
fn partition_in_place(refs: &mut [PrimRef], go_left: impl Fn(Vec3A) -> bool) -> Parted {
    let mut left = (Bounds::EMPTY, Bounds::EMPTY);
    let mut right = (Bounds::EMPTY, Bounds::EMPTY);
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        let b = refs[i].bounds();
        let c2 = b.min + b.max;
        if go_left(c2) {
            left = (left.0.union(b), left.1.grow(c2));
            i += 1;
        } else {
            right = (right.0.union(b), right.1.grow(c2));
            j -= 1;
            refs.swap(i, j);
        }
    }
    Parted {
        left_count: i,
        left,
        right,
    }
}

/// `part`, grown to at least `n` references.
fn room(part: &mut Vec<PrimRef>, n: usize) -> &mut [PrimRef] {
    if part.len() < n {
        part.resize(n, PrimRef::ZERO);
    }
    part
}

/// Moves the references whose doubled centre satisfies `go_left` to the front, both sides in
/// their order, accumulating both sides' bounds and centre bounds on the way: `(count on the
/// left, left, right)`. `buf` holds at least as many references as `refs`.
///
/// Every reference is written both behind the read position in `refs` (where the next left one
/// goes) and to `buf` (where the next right one goes), and only the matching position advances;
/// the right ones are then copied back after the left ones. So no branch depends on the side,
/// which in scanned meshes is close to random: [`partition_in_place`] mispredicted about every
/// other reference there (`perf annotate` put a third of `split`'s time on the instructions
/// after that branch). PERF: one-thread builds with this for sets below
/// [`CHUNKED_PARTITION_MIN`], time ÷ the time with [`partition_in_place`] for every set, in one
/// process, medians of 3 to 5 processes: bunny 0.78-0.84, rocker arm 0.78, cheburashka 0.75,
/// homer 0.92, fandisk 0.94, spot 0.93, beetle 0.97, teapot 0.95; sphereflake 0.99 and teapot
/// in a stadium 1.00, whose generated triangles come in runs on one side that the branch
/// predicts. Two threads: bunny 0.67, teapot 0.92, sphereflake 0.87, stadium 0.74.
#[inline(always)]
fn partition(refs: &mut [PrimRef], buf: &mut [PrimRef], go_left: impl Fn(Vec3A) -> bool) -> Parted {
    let n = refs.len();
    let buf = &mut buf[..n];
    // Left sides in 1 and 3, right sides in 0 and 2, by the parity of the position: neighbours
    // usually go to one side, and two accumulators per side halve the chain of updates that
    // each waits for the one before.
    let mut acc = [(Bounds::EMPTY, Bounds::EMPTY); 4];
    let (mut l, mut k) = (0, 0);
    for i in 0..n {
        let x = refs[i];
        let b = x.bounds();
        let c2 = b.min + b.max;
        let left = go_left(c2);
        let a = &mut acc[usize::from(left) + 2 * (i & 1)];
        *a = (a.0.union(b), a.1.grow(c2));
        refs[l] = x;
        buf[k] = x;
        l += usize::from(left);
        k += usize::from(!left);
    }
    refs[l..].copy_from_slice(&buf[..k]);
    let join = |a: (Bounds, Bounds), b: (Bounds, Bounds)| (a.0.union(b.0), a.1.union(b.1));
    Parted {
        left_count: l,
        left: join(acc[1], acc[3]),
        right: join(acc[0], acc[2]),
    }
}

/// The result of a partition: how many references went left, and each side's bounds and
/// centre bounds.
#[derive(Clone, Copy)]
struct Parted {
    left_count: usize,
    left: (Bounds, Bounds),
    right: (Bounds, Bounds),
}

/// Emits the binary subtree of `planned` depth first (first child right after its parent).
/// `refs` holds the references from absolute index `base` on.
fn emit_binary(
    ctx: &Ctx<'_>,
    refs: &mut [PrimRef],
    base: usize,
    planned: Planned,
    out: &mut Vec<Node>,
    shape: &mut Shape,
    scratch: &mut Scratch,
) {
    let set = planned.set;
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
    let (left, right) = match planned.below {
        Some(below) => {
            let [l, r] = *below;
            (l, r)
        }
        None => {
            let (l, r) = split(ctx, refs, base, &set, scratch);
            (Planned::new(l), Planned::new(r))
        }
    };
    out.push(Node {
        bounds: set.bounds.to_aabb(),
        index: 0,
        count: 0,
        axis: axis as u8,
        pad: 0,
    });
    if ctx.parallel && left.set.len().min(right.set.len()) >= PAR_SUBTREE_MIN {
        let right_start = right.set.start;
        let (lo, hi) = refs.split_at_mut(right_start - base);
        let task = |refs: &mut [PrimRef], base: usize, s: Planned| {
            let (mut v, mut sh) = (Vec::new(), Shape::default());
            emit_binary(ctx, refs, base, s, &mut v, &mut sh, &mut Scratch::new());
            (v, sh)
        };
        let ((lv, ls), (rv, rs)) =
            par::join(|| task(lo, base, left), || task(hi, right_start, right));
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

/// The wide tree's nodes and packs as they are written: in runs, in the order a sequential build
/// writes them. The last run (`cur`) takes what this task writes itself; the runs before it are
/// finished ones: this task's own, closed when a subtree built on another thread was appended,
/// and those subtrees' runs, moved in rather than copied. [`finish`](Self::finish) copies every
/// run into place once, at the end, so a subtree built in parallel several levels down is
/// copied once, not once per level.
#[derive(Default)]
struct WideOut {
    runs: Vec<Run>,
    cur: Run,
    /// The nodes and packs in `runs`.
    nodes_before: usize,
    packs_before: usize,
}

/// A run of a [`WideOut`]: nodes and packs, and what to add to the node and pack indices in its
/// nodes' child references to number them as in the finished tree.
#[derive(Default)]
struct Run {
    nodes: Vec<WideNode>,
    packs: Vec<TriPack>,
    node_shift: usize,
    pack_shift: usize,
}

/// Where a node was reserved in a [`WideOut`], to be written once its children are known.
#[derive(Clone, Copy)]
struct Slot {
    run: usize,
    pos: usize,
}

impl Run {
    /// `c` with this run's shifts applied; leaves of references (not packs) are input positions
    /// and keep theirs.
    fn relocate(&self, c: ChildRef, packed: bool) -> ChildRef {
        if c == ChildRef::EMPTY {
            c
        } else if c.is_leaf() {
            if packed {
                let items = c.items();
                ChildRef::leaf((items.start + self.pack_shift) as u32, items.len() as u32)
            } else {
                c
            }
        } else {
            ChildRef::node((c.index() + self.node_shift) as u32)
        }
    }
}

impl WideOut {
    fn nodes_len(&self) -> usize {
        self.nodes_before + self.cur.nodes.len()
    }

    fn packs_len(&self) -> usize {
        self.packs_before + self.cur.packs.len()
    }

    /// Reserves a node, to be written with [`node_mut`](Self::node_mut); its index is
    /// [`nodes_len`](Self::nodes_len) before the call.
    fn reserve_node(&mut self) -> Slot {
        self.cur.nodes.push(WideNode::EMPTY);
        Slot {
            run: self.runs.len(),
            pos: self.cur.nodes.len() - 1,
        }
    }

    fn node_mut(&mut self, slot: Slot) -> &mut WideNode {
        if slot.run == self.runs.len() {
            &mut self.cur.nodes[slot.pos]
        } else {
            &mut self.runs[slot.run].nodes[slot.pos]
        }
    }

    /// Appends a subtree built into a `WideOut` of its own, whose root is `root`; returns the
    /// root as numbered here. Moves the subtree's runs, copying nothing.
    fn append(&mut self, sub: WideOut, root: ChildRef, packed: bool) -> ChildRef {
        let (node_base, pack_base) = (self.nodes_len(), self.packs_len());
        let mine = std::mem::take(&mut self.cur);
        self.nodes_before += mine.nodes.len();
        self.packs_before += mine.packs.len();
        self.runs.push(mine);
        for mut run in sub.runs.into_iter().chain([sub.cur]) {
            run.node_shift += node_base;
            run.pack_shift += pack_base;
            self.nodes_before += run.nodes.len();
            self.packs_before += run.packs.len();
            self.runs.push(run);
        }
        let base = Run {
            node_shift: node_base,
            pack_shift: pack_base,
            ..Run::default()
        };
        base.relocate(root, packed)
    }

    /// Trims the arrays' slack: a subtree's runs wait to be appended, and the slack of arrays
    /// grown by doubling would add up to as much as the subtrees again.
    fn shrink(&mut self) {
        self.cur.nodes.shrink_to_fit();
        self.cur.packs.shrink_to_fit();
    }

    /// The tree's nodes and packs, each run copied into place with its indices shifted (on
    /// rayon's threads: `par::extend_range` writes each element in its place). A tree built on
    /// one thread is one run and is returned as it is.
    ///
    /// PERF: appending the root's eight subtrees one after another (4.2 MB for the sphereflake)
    /// took 0.43 ms on one thread while the other waited.
    fn finish(mut self, packed: bool) -> (Vec<WideNode>, Vec<TriPack>) {
        if self.runs.is_empty() {
            // A sequential build grows both arrays by doubling; up to half of each would be
            // unused capacity for the tree's lifetime (the bunny's wide tree took 7.0 MiB on 1
            // thread and 3.9 MiB on 2). Shrinking a large allocation is a remap, not a copy.
            self.shrink();
            return (self.cur.nodes, self.cur.packs);
        }
        let (n, p) = (self.nodes_len(), self.packs_len());
        self.runs.push(self.cur);
        let runs = self.runs;
        // Where each run's nodes and packs start, and the run holding element `i`.
        let starts = |len: fn(&Run) -> usize| {
            let mut at = 0;
            runs.iter()
                .map(|r| {
                    let s = at;
                    at += len(r);
                    s
                })
                .collect::<Vec<usize>>()
        };
        let (node_start, pack_start) = (starts(|r| r.nodes.len()), starts(|r| r.packs.len()));
        let run_of = |starts: &[usize], i: usize| starts.partition_point(|&b| b <= i) - 1;
        let mut nodes = Vec::with_capacity(n);
        par::extend_range(&mut nodes, 0..n, |i| {
            let k = run_of(&node_start, i);
            // Empty runs share their start with the next run; `partition_point` finds the last
            // run starting at or before `i`, which is the one holding it.
            let r = &runs[k];
            let mut node = r.nodes[i - node_start[k]];
            for ch in &mut node.children {
                *ch = r.relocate(ChildRef(*ch), packed).0;
            }
            node
        });
        let mut packs = Vec::with_capacity(p);
        par::extend_range(&mut packs, 0..p, |i| {
            let k = run_of(&pack_start, i);
            runs[k].packs[i - pack_start[k]]
        });
        (nodes, packs)
    }
}

/// A set, and the splits already made below it (see [`presplit`]).
struct Planned {
    set: Set,
    below: Option<Box<[Planned; 2]>>,
}

impl Planned {
    fn new(set: Set) -> Self {
        Self { set, below: None }
    }
}

/// Sets at least this large have the first [`PRESPLIT_LEVELS`] levels of their split tree made
/// at once when they become a wide node (see [`presplit`]).
const PRESPLIT_MIN: usize = 1 << 12;
/// Three levels: the seven splits a balanced wide node makes.
const PRESPLIT_LEVELS: usize = 3;

/// Makes the splits below `set` down to `levels` levels at once, both halves of each split
/// concurrently when they are large and the build is parallel.
///
/// The split tree below a set does not depend on the order its splits are made in, and a wide
/// node only chooses which of them to use (the largest child first): so these splits, made
/// eagerly for every large node whether the build is parallel or not, give the same tree, and
/// splits the node does not use are kept for the child that will. PERF: opened one split at a
/// time, the root of the sphereflake kept one thread busy for 1.9 ms before its children could
/// be built in parallel; the 2-thread build was 1.46x faster than one thread, the binary tree's
/// (whose two halves run in parallel from the root on) 1.73x.
fn presplit(
    ctx: &Ctx<'_>,
    refs: &mut [PrimRef],
    base: usize,
    set: Set,
    levels: usize,
    scratch: &mut Scratch,
) -> Planned {
    if levels == 0 || set.plan == Plan::Leaf || set.len() < PRESPLIT_MIN {
        return Planned::new(set);
    }
    let (l, r) = split(ctx, refs, base, &set, scratch);
    let (pl, pr) = if ctx.parallel && l.len().min(r.len()) >= PAR_SUBTREE_MIN {
        let own = &mut refs[set.start - base..set.end - base];
        // At the right half's start, not the left half's length: dropped copies may lie between.
        let (lo, hi) = own.split_at_mut(r.start - set.start);
        par::join(
            || presplit(ctx, lo, l.start, l, levels - 1, &mut Scratch::new()),
            || presplit(ctx, hi, r.start, r, levels - 1, &mut Scratch::new()),
        )
    } else {
        (
            presplit(ctx, refs, base, l, levels - 1, scratch),
            presplit(ctx, refs, base, r, levels - 1, scratch),
        )
    };
    Planned {
        set,
        below: Some(Box::new([pl, pr])),
    }
}

/// Emits the wide subtree of `planned` and returns the reference to it: a leaf, or a node whose
/// children are the sets left after splitting the largest child until there are eight. `refs`
/// holds the references from absolute index `base` on.
fn emit_wide(
    ctx: &Ctx<'_>,
    refs: &mut [PrimRef],
    base: usize,
    planned: Planned,
    out: &mut WideOut,
    shape: &mut Shape,
    scratch: &mut Scratch,
) -> ChildRef {
    let set = planned.set;
    shape.max_depth = shape.max_depth.max(set.depth);
    if set.plan == Plan::Leaf {
        shape.leaves += 1;
        return emit_leaf(ctx, &refs[set.start - base..set.end - base], &set, out);
    }
    let planned = if planned.below.is_none() {
        presplit(ctx, refs, base, set, PRESPLIT_LEVELS, scratch)
    } else {
        planned
    };
    // Opens a set: its two halves, split now unless they were already.
    let open = |p: Planned, refs: &mut [PrimRef], scratch: &mut Scratch| match p.below {
        Some(b) => {
            let [l, r] = *b;
            (l, r)
        }
        None => {
            let (l, r) = split(ctx, refs, base, &p.set, scratch);
            (Planned::new(l), Planned::new(r))
        }
    };
    let mut kids: Vec<Planned> = Vec::with_capacity(WIDTH);
    let (l, r) = open(planned, refs, scratch);
    kids.extend([l, r]);
    while kids.len() < WIDTH {
        let mut largest: Option<(usize, f32)> = None;
        for (i, k) in kids.iter().enumerate() {
            let area = k.set.bounds.half_area();
            if k.set.plan != Plan::Leaf && largest.is_none_or(|(_, a)| area > a) {
                largest = Some((i, area));
            }
        }
        let Some((i, _)) = largest else { break };
        let (l, r) = open(kids.remove(i), refs, scratch);
        kids.insert(i, r);
        kids.insert(i, l);
    }
    let index = out.nodes_len();
    let slot = out.reserve_node();
    let mut node = WideNode::EMPTY;
    let bounds: Vec<Bounds> = kids.iter().map(|k| k.set.bounds).collect();
    let total: usize = kids.iter().map(|k| k.set.len()).sum();
    if ctx.parallel && total >= PAR_WIDE_MIN {
        // Each child into its own arrays, concurrently; then appended in order, which is where a
        // sequential build would have written them. Every child is a task, the small ones too:
        // left to this thread, they would keep it busy while the other has nothing to take.
        let mut slices = Vec::with_capacity(kids.len());
        let mut rest = refs;
        let mut at = base;
        for k in kids {
            let (_, tail) = std::mem::take(&mut rest).split_at_mut(k.set.start - at);
            let (mine, tail) = tail.split_at_mut(k.set.len());
            at = k.set.end;
            slices.push((mine, k));
            rest = tail;
        }
        let parts: Vec<(ChildRef, WideOut, Shape)> = par::map_vec(slices, |(slice, k)| {
            let mut o = WideOut::default();
            let mut sh = Shape::default();
            let start = k.set.start;
            let c = emit_wide(ctx, slice, start, k, &mut o, &mut sh, &mut Scratch::new());
            o.shrink();
            (c, o, sh)
        });
        for (i, (c, o, sh)) in parts.into_iter().enumerate() {
            shape.merge(sh);
            let c = out.append(o, c, ctx.test.is_some());
            set_child(&mut node, i, &bounds[i], c);
        }
    } else {
        for (i, k) in kids.into_iter().enumerate() {
            let c = emit_wide(ctx, refs, base, k, out, shape, scratch);
            set_child(&mut node, i, &bounds[i], c);
        }
    }
    *out.node_mut(slot) = node;
    ChildRef::node(index as u32)
}

/// A leaf: its triangles packed four to a pack, or its range of references.
fn emit_leaf(ctx: &Ctx<'_>, range: &[PrimRef], set: &Set, out: &mut WideOut) -> ChildRef {
    match ctx.test {
        Some(test) => {
            let first = out.packs_len();
            for chunk in range.chunks(PACK) {
                let mut tris = [(Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO), 0u32); PACK];
                for (slot, r) in tris.iter_mut().zip(chunk) {
                    let t = ctx.prims.triangle(r.id);
                    *slot = (t, r.id);
                }
                out.cur.packs.push(TriPack::new(&tris[..chunk.len()], test));
            }
            ChildRef::leaf(first as u32, (out.packs_len() - first) as u32)
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

//! Stream traversal of the wide tree: a batch of scattered rays walks it together, node by
//! node ([`Accel::intersect_stream`](rt_core::Accel::intersect_stream)).
//!
//! The technique is the dynamic ray stream traversal of Barringer & Akenine-Möller (2014,
//! "Dynamic ray stream traversal") on an 8-wide tree:
//! - the rays of a chunk (at most [`CHUNK`]) start as one list at the root;
//! - at a node, every ray of its list is tested against the node's eight children with its own
//!   slab test ([`slab_lanes`], the single ray's [`slab8`](crate::kernels::slab8)) up to its
//!   own best hit so far, and written into the list of each child it enters, branch-free;
//! - the children's lists are pushed nearest first by the mean entry distance of their rays
//!   (any order for occlusion), so most rays still walk near to far;
//! - at a leaf, each ray of its list tests the leaf's triangle packs with its single ray's leaf
//!   test, from its best hit so far.
//!
//! A single ray's walk is a chain of dependent steps (load a node, test it, pick a child,
//! load that): the CPU waits on each. A node's list is many independent tests of one node,
//! which the CPU overlaps, and no ray keeps a stack of its own or branches on its own
//! children's count.
//!
//! Exact, as the bundle walk: a ray's closest hit lies in every box on the path to its leaf,
//! and the ray's own slab test with a best `t` no nearer than that hit enters each of them
//! (within [`SLAB_FAR_SCALE`](rt_core::SLAB_FAR_SCALE), as the single walk allows), so the ray
//! tests the primitive; every hit it records is a true hit of its single ray's test, kept by
//! the same tie rule, so the closest is its single ray's answer, bit for bit. An occlusion ray
//! is blocked when any of its hits is found, as its single ray is.

use crate::kernels::{self, RayData, Wide};
use crate::node::{ChildRef, WIDTH, WideNode};
use crate::traverse::{self, Leaves, WIDE_STACK};
use rt_core::glam::Vec3;
use rt_core::{AnyHit, ClosestHit, Hit, Ray, Shear, Stack, Stats};
use rt_simd::bundle::octant;
use rt_simd::{Simd, WithLanes, slab_lanes};
use std::cell::RefCell;

/// The rays a stream walks at once: a longer batch walks in chunks of this many, so that the
/// scratch stays a fixed size.
// PERF: the bunny's 786,432 incoherent rays, one thread, rays per stream (with `ALONE` 32):
// 4,096 ran 0.77x the single rays' speed, 16,384 0.79x, 65,536 (with `ALONE` 4) 0.58x; a
// stream's rays and records then outgrow the caches.
pub(crate) const CHUNK: usize = 4096;

/// A node's list of at most this many rays walks on ray by ray (each by the single ray's walk
/// of the subtree): too few rays to share the node's costs.
// PERF: the bunny's incoherent rays, one thread, 16,384 rays per stream: every list streamed
// (0) ran 0.69x the single rays' speed, 4 0.77x, 16 0.75x, 64 0.95x (`compare --stream`,
// noisy: ±15% between runs).
const ALONE: usize = 32;

/// What a stream keeps per ray and per node, reused by every stream on a thread.
pub(crate) struct Scratch {
    /// The lists of rays (indices into the chunk) waiting at the nodes on the stack, one after
    /// another in the order they were pushed: the top entry's list is the last.
    lists: Vec<u16>,
    /// The lists of a node's children while its rays are sorted into them: child `c`'s from
    /// `c * CHUNK`.
    split: Vec<u16>,
    /// Each ray's best hit so far, as [`ClosestHit::record`] keeps it; an occlusion ray that
    /// is blocked has a `prim` other than `u32::MAX`.
    pub best: Vec<Hit>,
    /// Each ray's shear for the watertight test.
    shear: Vec<Shear>,
    /// What each ray's slab test reads, in one record: origin, reciprocal direction, `t_min`
    /// and its best hit's `t`, kept up to date.
    slab: Vec<[f32; 8]>,
    /// How many of the root's rays point into each direction octant.
    octants: [u32; 8],
}

impl Scratch {
    fn new() -> Self {
        Self {
            lists: Vec::new(),
            split: vec![0; WIDTH * CHUNK],
            best: Vec::new(),
            shear: Vec::new(),
            slab: Vec::new(),
            octants: [0; 8],
        }
    }

    /// Readies a stream of `rays` (at most [`CHUNK`]): each valid ray listed at the root, with
    /// no hit yet over its whole interval, in one list per direction octant (the lists' lengths
    /// in `octants`, in octant order). Returns whether any is valid.
    pub fn start(&mut self, rays: &[Ray]) -> bool {
        debug_assert!(rays.len() <= CHUNK);
        self.lists.clear();
        self.best.clear();
        self.shear.clear();
        self.slab.clear();
        self.octants = [0; 8];
        for ray in rays {
            self.best.push(ClosestHit::new(ray).record());
            let (o, inv) = (ray.origin, ray.inv_dir());
            self.slab
                .push([o.x, o.y, o.z, inv.x, inv.y, inv.z, ray.t_min, ray.t_max]);
            let valid = ray.is_valid();
            let dir = if valid { ray.dir() } else { Vec3::Z };
            self.shear.push(Shear::new(dir));
            if valid {
                self.octants[octant(ray)] += 1;
            }
        }
        // The valid rays sorted by octant (a counting sort, each octant in ray order).
        let mut at = [0usize; 8];
        for o in 1..8 {
            at[o] = at[o - 1] + self.octants[o - 1] as usize;
        }
        let valid = at[7] + self.octants[7] as usize;
        self.lists.resize(valid, 0);
        for (i, ray) in rays.iter().enumerate() {
            if ray.is_valid() {
                let o = octant(ray);
                self.lists[at[o]] = i as u16;
                at[o] += 1;
            }
        }
        valid > 0
    }
}

thread_local! {
    static SCRATCH: RefCell<Option<Scratch>> = const { RefCell::new(None) };
}

/// Runs `f` with this thread's scratch (a fresh one if the thread's is in use, as by a stream
/// started from inside another).
pub(crate) fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut kept) => f(kept.get_or_insert_with(Scratch::new)),
        Err(_) => f(&mut Scratch::new()),
    })
}

/// The stream walk's stack: eight root entries, then at most seven more per level.
const STACK: usize = WIDE_STACK + 2 * WIDTH;

/// One stream through [`wide_stream`] with an instruction set's operations.
pub(crate) struct WideStream<'a, L, S, const ANY: bool> {
    pub nodes: &'a [WideNode],
    pub leaves: &'a L,
    pub rays: &'a [Ray],
    /// Whether a ray walking alone sorts the children it enters ([`crate::Ablation`]).
    pub sort: bool,
    pub scratch: &'a mut Scratch,
    pub stats: &'a mut S,
}

impl<L: Leaves, S: Stats, const ANY: bool> WithLanes for WideStream<'_, L, S, ANY> {
    type Out = ();
    #[inline(always)]
    fn run<X: Simd<4> + Simd<8>>(self, simd: X) {
        wide_stream::<X, L, S, ANY>(
            simd,
            self.nodes,
            self.leaves,
            self.rays,
            self.sort,
            self.scratch,
            self.stats,
        );
    }
}

/// The stream traversal core, shared by closest hit (`ANY = false`) and occlusion: walks the
/// rays [`Scratch::start`] listed, leaving each ray's answer in `sc.best`. Counts a node visit
/// per ray and node (or leaf) it tests, as its single ray would count them.
#[inline(always)]
pub(crate) fn wide_stream<X: Wide, L: Leaves, S: Stats, const ANY: bool>(
    simd: X,
    nodes: &[WideNode],
    leaves: &L,
    rays: &[Ray],
    sort: bool,
    sc: &mut Scratch,
    stats: &mut S,
) {
    // Each node pushes at most its eight children after its own entry is popped, and the root
    // starts with a list per octant: the rays of one octant order children alike, so one
    // order per list suits most of its rays.
    // PERF: AMD Zen 4, one thread, `compare --stream -s bvh-stream -j 1`, one list at the root
    // -> a list per octant: the bunny's incoherent rays 6.86 -> 6.05 nodes and 4.24 -> 3.51
    // triangles a ray (single rays: 5.49 and 3.34), the rocker arm's 8.22 -> 7.12 and 7.04 ->
    // 5.55 (6.32 and 5.28); stream ÷ single rays 0.85 -> 0.83 and 0.77 -> 0.90, diffuse
    // bounces 1.07 -> 0.94 and 0.93 -> 0.92 (runs swing ±15%).
    let mut stack = Stack::<(u32, u32, u32), { STACK }>::new();
    // Pushed in list order, so that the top entry's list is the last, as the walk needs.
    let mut start = 0;
    for &n in &sc.octants {
        if n > 0 {
            stack.push((ChildRef::node(0).0, start, n));
        }
        start += n;
    }
    while let Some((child, start, len)) = stack.pop() {
        let (child, list) = (ChildRef(child), start as usize..(start + len) as usize);
        if child.is_leaf() {
            for k in list {
                let i = usize::from(sc.lists[k]);
                if ANY && sc.best[i].prim != u32::MAX {
                    continue;
                }
                stats.node_visit();
                test_leaf::<X, L, S, ANY>(simd, leaves, child, &rays[i], sc, i, stats);
            }
            sc.lists.truncate(start as usize);
            continue;
        }
        if (len as usize) <= ALONE {
            // Too few rays to share the node's load: each walks the subtree alone.
            for k in list {
                let i = usize::from(sc.lists[k]);
                walk_alone::<X, L, S, ANY>(
                    simd, nodes, child, leaves, &rays[i], sort, sc, i, stats,
                );
            }
            sc.lists.truncate(start as usize);
            continue;
        }
        let node = &nodes[child.index()];
        let mut count = [0usize; WIDTH];
        let mut entry_sum = Simd::<8>::splat(simd, 0.0);
        for k in list {
            let i = usize::from(sc.lists[k]);
            if ANY && sc.best[i].prim != u32::MAX {
                continue;
            }
            stats.node_visit();
            let r = &sc.slab[i];
            let splat = |x| Simd::<8>::splat(simd, x);
            let boxes = rt_simd::SlabRay {
                origin: [splat(r[0]), splat(r[1]), splat(r[2])],
                inv_dir: [splat(r[3]), splat(r[4]), splat(r[5])],
                t_min: splat(r[6]),
            };
            let (entered, t0) = slab_lanes::<8, X>(simd, &node.bounds, &boxes, r[7]);
            let bits = Simd::<8>::bits(simd, entered);
            // Written into every child's list, kept only where entered: no branch on the
            // children a ray enters, which go either way for scattered rays.
            for (c, split) in sc.split.chunks_exact_mut(CHUNK).enumerate() {
                split[count[c]] = i as u16;
                count[c] += (bits >> c & 1) as usize;
            }
            if !ANY {
                let zero = Simd::<8>::splat(simd, 0.0);
                entry_sum =
                    Simd::<8>::add(simd, entry_sum, Simd::<8>::select(simd, entered, t0, zero));
            }
        }
        sc.lists.truncate(start as usize);
        push_children::<X, ANY>(simd, node, &count, entry_sum, sc, &mut stack);
    }
}

/// Pushes the lists of `node`'s children that some ray enters: for a closest hit farthest
/// first by their rays' mean entry distance, so the nearest comes off the stack next.
#[inline(always)]
fn push_children<X: Wide, const ANY: bool>(
    simd: X,
    node: &WideNode,
    count: &[usize; WIDTH],
    entry_sum: <X as Simd<8>>::V,
    sc: &mut Scratch,
    stack: &mut Stack<(u32, u32, u32), { STACK }>,
) {
    let mut order = [(0.0f32, 0usize); WIDTH];
    let mut n = 0;
    let sums = Simd::<8>::store(simd, entry_sum);
    for c in 0..WIDTH {
        if count[c] > 0 {
            order[n] = (if ANY { 0.0 } else { sums[c] / count[c] as f32 }, c);
            n += 1;
        }
    }
    if !ANY {
        // Farthest first: an insertion sort of at most eight.
        for k in 1..n {
            let e = order[k];
            let mut j = k;
            while j > 0 && order[j - 1].0 < e.0 {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = e;
        }
    }
    for &(_, c) in &order[..n] {
        let start = sc.lists.len();
        sc.lists
            .extend_from_slice(&sc.split[c * CHUNK..][..count[c]]);
        stack.push((node.children[c], start as u32, count[c] as u32));
    }
}

/// Ray `i` of the stream through the subtree of node `child` alone, by the single ray's walk,
/// from its best hit so far.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn walk_alone<X: Wide, L: Leaves, S: Stats, const ANY: bool>(
    simd: X,
    nodes: &[WideNode],
    child: ChildRef,
    leaves: &L,
    ray: &Ray,
    sort: bool,
    sc: &mut Scratch,
    i: usize,
    stats: &mut S,
) {
    let (root, shear) = (child.index(), Some(sc.shear[i]));
    if ANY {
        if sc.best[i].prim != u32::MAX {
            return;
        }
        let mut q = AnyHit::new(ray);
        traverse::wide_from(simd, nodes, root, leaves, ray, shear, sort, &mut q, stats);
        if let Some(prim) = q.blocker() {
            sc.best[i].prim = prim;
        }
    } else {
        let mut q = ClosestHit::resume(sc.best[i]);
        traverse::wide_from(simd, nodes, root, leaves, ray, shear, sort, &mut q, stats);
        sc.best[i] = q.record();
        sc.slab[i][7] = sc.best[i].t;
    }
}

/// Ray `i` of the stream through leaf `child`'s items, from its best hit so far.
#[inline(always)]
fn test_leaf<X: Wide, L: Leaves, S: Stats, const ANY: bool>(
    simd: X,
    leaves: &L,
    child: ChildRef,
    ray: &Ray,
    sc: &mut Scratch,
    i: usize,
    stats: &mut S,
) {
    let r = RayData::with_shear(simd, ray, kernels::box_ray(simd, ray), sc.shear[i]);
    if ANY {
        let mut q = AnyHit::new(ray);
        leaves.test(simd, child.items(), &r, ray, &mut q, stats);
        if let Some(prim) = q.blocker() {
            sc.best[i].prim = prim;
        }
    } else {
        let mut q = ClosestHit::resume(sc.best[i]);
        leaves.test(simd, child.items(), &r, ray, &mut q, stats);
        sc.best[i] = q.record();
        sc.slab[i][7] = sc.best[i].t;
    }
}

//! The traversals: near-child-first over the binary tree, and over the wide tree with SIMD slab
//! and triangle tests. Each has one generic core for every ray query ([`RayQuery`]): closest
//! hit, any hit, filters, all hits.

use crate::kernels::{self, RayData, Wide};
use crate::node::Node;
use crate::node::{ChildRef, TriPack, WIDTH, WideNode};
use crate::{Items, MAX_DEPTH};
use rt_core::Stack;
use rt_core::glam::Vec3;
use rt_core::query::BLOCKS;
use rt_core::trace::{self, Event, Place};
use rt_core::{
    AnyHit, ClosestHit, Hit, PrimHit, Primitive, Ray, RayQuery, SLAB_FAR_SCALE, Shear, Stats,
    Triangle, TriangleTest, leaf,
};
use rt_simd::{Lanes, Simd, WithLanes};
use std::ops::ControlFlow;
use std::ops::Range;

/// The binary tree's traversal core, for any query `Q`.
///
/// At an interior node both children's boxes are tested against `[t_min, q.t_far()]`; the
/// nearer child is visited next and the farther one is pushed with its entry distance, and
/// skipped when popped if the query's far end has come closer than that entry meanwhile (for a
/// closest hit: a closer hit was found; front-to-back traversal; the comparison allows
/// [`SLAB_FAR_SCALE`] of rounding, as the box test does, so a primitive tying with the best hit
/// is still found). The stack holds at most
/// one entry per tree level, and the builder bounds the depth by `MAX_DEPTH`, so a fixed
/// array suffices.
// PERF: kept out of line: inlined into the query beside every wide traversal, it ran 1.16x
// (bunny) and 1.21x (sphereflake) slower than the same loop written alone; out of line it
// runs 1.03x and 1.00x of it (`cargo bench -p rt-benches --bench stats -- stats-sink/`).
#[inline(never)]
pub(crate) fn binary<P: Primitive, S: Stats, Q: RayQuery>(
    nodes: &[Node],
    items: &Items<P>,
    ray: &Ray,
    q: &mut Q,
    stats: &mut S,
) {
    binary_walk(nodes, items, ray, q, stats);
}

/// [`binary`]'s closest hit written into `out`, the caller's slot, rather than copied there
/// (`simd::dispatch_into` says why that copy waits).
#[inline(never)]
pub(crate) fn binary_into<P: Primitive, S: Stats>(
    nodes: &[Node],
    items: &Items<P>,
    ray: &Ray,
    stats: &mut S,
    out: &mut Option<Hit>,
) {
    let mut q = ClosestHit::new(ray);
    binary_walk(nodes, items, ray, &mut q, stats);
    *out = q.hit();
}

/// The body of [`binary`] and [`binary_into`].
#[inline(always)]
fn binary_walk<P: Primitive, S: Stats, Q: RayQuery>(
    nodes: &[Node],
    items: &Items<P>,
    ray: &Ray,
    q: &mut Q,
    stats: &mut S,
) {
    if items.ids.is_empty() || nodes[0].bounds.intersect(ray, q.t_far()).is_none() {
        return;
    }
    let mut stack = Stack::<(u32, f32), MAX_DEPTH>::new();
    let mut current = 0usize;
    loop {
        stats.node_visit();
        let node = &nodes[current];
        trace::report(stats, || {
            let (t0, t1) = node
                .bounds
                .intersect(ray, q.t_far())
                .unwrap_or((f32::NAN, f32::NAN));
            let i = current as u32;
            Event::Enter {
                place: if node.is_leaf() {
                    Place::Leaf(i)
                } else {
                    Place::Node(i)
                },
                t0,
                t1,
                bounds: Some(node.bounds),
            }
        });
        if node.is_leaf() {
            // PERF: one bounds check per leaf instead of two per primitive: bunny primary rays
            // 8.76 -> 9.20 Mrays/s single-threaded (`cargo bench -p rt-benches --bench trace`).
            let range = node.prim_range();
            for (prim, &id) in items.prims[range.clone()].iter().zip(&items.ids[range]) {
                if leaf::offer_hit(prim, id, ray, q, stats).is_break() {
                    return;
                }
            }
        } else {
            let (a, b) = (current + 1, node.index as usize);
            let ta = nodes[a].bounds.entry(ray, q.t_far());
            let tb = nodes[b].bounds.entry(ray, q.t_far());
            let (near, t_near, far, t_far) = if ta <= tb {
                (a, ta, b, tb)
            } else {
                (b, tb, a, ta)
            };
            if S::TRACE {
                for (c, t) in [(near, t_near), (far, t_far)] {
                    if t != f32::INFINITY {
                        let place = Place::Node(c as u32);
                        stats.event(Event::Child { place, t });
                    }
                }
            }
            if t_near != f32::INFINITY {
                if t_far != f32::INFINITY {
                    stack.push((far as u32, t_far));
                    trace::report(stats, || Event::Push {
                        place: Place::Node(far as u32),
                        t: t_far,
                    });
                }
                current = near;
                continue;
            }
            trace::report(stats, || Event::Note("the ray enters neither child's box"));
        }
        // Pop the next subtree that can still hold a hit within the query's far end.
        loop {
            let Some((index, t_entry)) = stack.pop() else {
                trace::report(stats, || Event::Note("stack empty: done"));
                return;
            };
            let skipped = t_entry > q.t_far() * SLAB_FAR_SCALE;
            trace::report(stats, || Event::Pop {
                place: Place::Node(index),
                t: t_entry,
                skipped,
            });
            if !skipped {
                current = index as usize;
                break;
            }
        }
    }
}

/// Entries of the wide traversal's stack: each wide level pushes at most seven siblings, and the
/// builder keeps the tree at most [`MAX_DEPTH`] levels deep.
pub(crate) const WIDE_STACK: usize = (WIDTH - 1) * MAX_DEPTH;

/// How the leaves of a wide tree are tested: triangle packs with a SIMD kernel, triangle packs
/// one triangle at a time through the scalar test (the reference the kernels are tested
/// against), or primitives of any type.
pub(crate) trait Leaves {
    /// Tests the leaf's items against the ray up to `q.t_far()` and offers `q` the hits (for
    /// an occlusion query, the first only). Returns true when the query ends the walk.
    fn test<X: Wide, S: Stats, Q: RayQuery>(
        &self,
        simd: X,
        items: Range<usize>,
        r: &RayData<X>,
        ray: &Ray,
        q: &mut Q,
        stats: &mut S,
    ) -> bool;

    /// Tests the leaf's items against the lanes `mask` of a bundle, each lane exactly as its
    /// single ray's [`Leaves::test`] would, keeping each lane's best hit in `lanes`; with
    /// `ANY`, returns the lanes blocked. This default tests lane by lane with
    /// [`Leaves::test`]; triangle packs for the watertight test override it to test one
    /// triangle against a vector of lanes at a time.
    #[inline(always)]
    fn test_lanes<X: Wide, S: Stats, const ANY: bool>(
        &self,
        simd: X,
        items: Range<usize>,
        lanes: &mut Lanes,
        mask: u64,
        stats: &mut S,
    ) -> u64 {
        lane_by_lane::<Self, X, S, ANY>(self, simd, items, lanes, mask, stats)
    }
}

/// [`Leaves::test_lanes`] lane by lane: each lane of `mask` through `leaves`' single-ray test,
/// from its best hit so far.
#[inline(always)]
fn lane_by_lane<L: Leaves + ?Sized, X: Wide, S: Stats, const ANY: bool>(
    leaves: &L,
    simd: X,
    items: Range<usize>,
    lanes: &mut Lanes,
    mask: u64,
    stats: &mut S,
) -> u64 {
    let mut blocked = 0;
    let mut m = mask;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let ray = lanes.ray(i);
        let r = RayData::with_shear(simd, &ray, kernels::box_ray(simd, &ray), lanes.shear(i));
        if ANY {
            let mut q = AnyHit::new(&ray);
            leaves.test(simd, items.clone(), &r, &ray, &mut q, stats);
            if let Some(prim) = q.blocker() {
                lanes.block(i, prim);
                blocked |= 1 << i;
            }
        } else {
            let mut q = ClosestHit::resume(lanes.best(i));
            leaves.test(simd, items.clone(), &r, &ray, &mut q, stats);
            lanes.offer_hit(i, q.record());
        }
    }
    blocked
}

/// Starts reading node `c` into the caches, if it is one (not a leaf): all four of its cache
/// lines, whose loads the slab test would otherwise issue only when the walk gets there. The
/// walk calls it for every child a ray enters, as Embree's does, so that the reads of a
/// node's children overlap.
// PERF: Intel Emerald Rapids, one thread, private harness (`compare`'s filled-view primary
// rays, 500k incoherent rays, the primary hits' shadow rays), best of 5 passes, two
// alternating runs each, Mrays/s, without -> with: the bunny primary 7.76 7.89 -> 8.11 8.29,
// incoherent 4.55 4.43 -> 4.79 4.84, shadow 6.31 6.39 -> 6.43 6.50; the rocker arm 10.47
// 10.43 -> 10.64 10.68, 4.33 4.30 -> 4.49 4.48, 7.37 7.39 -> 7.50 7.48; the beetle 10.32 10.40
// -> 10.66 10.69, 5.10 5.15 -> 5.33 5.35, 6.09 6.13 -> 6.20 6.20; the teapot 11.56 11.62 ->
// 11.91 11.91, 6.13 6.21 -> 6.37 6.33, 8.84 8.81 -> 8.96 8.97. Prefetching a leaf's triangle
// packs as well (2, 3 or 6 lines) gained nothing more, nor did prefetching in the bundle walk
// (the bunny's shadow rays in 8×8 tiles 21.3 21.1 -> 20.2 21.0).
#[inline(always)]
fn prefetch_node(nodes: &[WideNode], c: ChildRef) {
    if !c.is_leaf() {
        rt_simd::prefetch(&nodes[c.index()..], 0, 4);
    }
}

/// [`prefetch_node`] without a branch on the kind of child, which goes either way for
/// scattered rays: a leaf asks for the root, which is in the caches already. For the children a
/// closest-hit ray enters.
// PERF: Intel Emerald Rapids, one thread, private harness, best of 5 passes, three alternating
// runs, Mrays/s, with the branch -> without: incoherent rays, random soup 1.83 1.83 1.83 -> 1.88
// 1.88 1.88, the teapot 6.24 6.10 6.05 -> 6.17 6.22 6.24, woody 13.30 13.14 13.28 -> 13.32 13.27
// 13.34, the bunny 5.87 5.72 5.78 -> 5.75 5.79 5.83; primary rays within ±1%. Shadow rays,
// which push every child entered, ran 1-2% slower without the branch, so they keep it.
#[inline(always)]
fn prefetch_entered(nodes: &[WideNode], c: ChildRef) {
    let i = if c.is_leaf() { 0 } else { c.index() };
    if let Some(node) = nodes.get(i..) {
        rt_simd::prefetch(node, 0, 4);
    }
}

/// Sorts `k[..n]` in descending order: by sorting networks of compare-exchanges for two to
/// eight keys (min and max, no branch on the keys). Slots `n..` must hold zeros.
///
/// The walk's keys are a child's entry distance bits above its reference: for the distances
/// of rays with `t_min >= 0` (never negative) the bits order as the numbers do. Any order
/// would give the same answers (a popped child is skipped by its own stored distance), so
/// keys that order differently (a negative `t_min`) cost only speed.
// PERF: against an insertion sort of (reference, distance) pairs, whose comparisons branch at
// random for incoherent rays. Intel Emerald Rapids, one thread, private harness, best of 5
// passes, two alternating runs, Mrays/s, incoherent rays: the bunny 4.96 4.98 -> 5.24 5.28,
// the teapot 6.40 6.43 -> 6.86 6.85, the rocker arm 4.51 4.57 -> 4.89 4.90, spot 6.24 6.23 ->
// 6.71 6.66; primary rays -1% to +4%, shadow rays (which do not sort) unchanged. Networks up
// to four keys with insertion beyond ran 0-1% slower than this; a branch-free rank sort
// (each key's slot the count of keys above it) 10% slower on primary and incoherent rays.
#[inline(always)]
fn sort_descending(k: &mut [u64; WIDTH], n: usize) {
    let cx = |k: &mut [u64; WIDTH], a: usize, b: usize| {
        let (x, y) = (k[a], k[b]);
        k[a] = x.max(y);
        k[b] = x.min(y);
    };
    match n {
        0 | 1 => {}
        2 => cx(k, 0, 1),
        3 => {
            cx(k, 0, 1);
            cx(k, 1, 2);
            cx(k, 0, 1);
        }
        4 => {
            cx(k, 0, 1);
            cx(k, 2, 3);
            cx(k, 0, 2);
            cx(k, 1, 3);
            cx(k, 1, 2);
        }
        // Five to eight keys: the 19 compare-exchanges that sort eight (Knuth, TAOCP vol. 3,
        // §5.3.4), the slots past `n` holding zeros, which sort last.
        _ => {
            for layer in [
                &[(0, 2), (1, 3), (4, 6), (5, 7)][..],
                &[(0, 4), (1, 5), (2, 6), (3, 7)],
                &[(0, 1), (2, 3), (4, 5), (6, 7)],
                &[(2, 4), (3, 5)],
                &[(1, 4), (3, 6)],
                &[(1, 2), (3, 4), (5, 6)],
            ] {
                for &(a, b) in layer {
                    cx(k, a, b);
                }
            }
        }
    }
}

/// Triangle packs and the kernel that tests them (`MT`: Möller–Trumbore, else watertight).
pub(crate) struct Packs<'a, const MT: bool> {
    pub packs: &'a [TriPack],
}

impl<const MT: bool> Leaves for Packs<'_, MT> {
    #[inline(always)]
    fn test<X: Wide, S: Stats, Q: RayQuery>(
        &self,
        simd: X,
        items: Range<usize>,
        r: &RayData<X>,
        _: &Ray,
        q: &mut Q,
        stats: &mut S,
    ) -> bool {
        for pack in &self.packs[items] {
            for _ in 0..pack.len() {
                stats.prim_test();
            }
            let h = if MT {
                kernels::moller_trumbore4(simd, pack, r, q.t_far())
            } else {
                kernels::watertight4(simd, pack, r, q.t_far())
            };
            if S::TRACE {
                let t = Simd::<4>::store(simd, h.t);
                for (lane, &id) in pack.ids[..pack.len()].iter().enumerate() {
                    let hit = (h.mask & 1 << lane != 0).then_some(t[lane]);
                    if Q::OCCLUSION {
                        trace::blocked(stats, id, hit.is_some());
                    } else {
                        trace::tested(stats, id, hit);
                    }
                }
            }
            if Q::OCCLUSION && h.mask != 0 {
                let _ = q.offer(pack.ids[h.mask.trailing_zeros() as usize], BLOCKS);
                return true;
            }
            let mut mask = h.mask;
            if mask != 0 {
                let (t, u, v) = (
                    Simd::<4>::store(simd, h.t),
                    Simd::<4>::store(simd, h.u),
                    Simd::<4>::store(simd, h.v),
                );
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let hit = PrimHit {
                        t: t[lane],
                        u: u[lane],
                        v: v[lane],
                    };
                    if q.offer(pack.ids[lane], hit).is_break() {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Watertight packs test each triangle against a vector of lanes at a time ([`Lanes`],
    /// rt-core's eight- or sixteen-lane kernel) where the leaf's lanes fill the vectors they
    /// occupy well enough,
    /// else each lane alone against four triangles at a time, as its single ray does. Both give
    /// each lane the bits of the scalar test. Möller–Trumbore packs test lane by lane.
    // PERF: bundles ÷ single rays, primary rays in 8×8 tiles, one thread, medians of 5
    // passes, two alternating runs: the teapot in a stadium (large triangles, leaves reached by
    // many lanes) 1.80 and 1.82 lane by lane, 2.27 and 2.28 with this choice, 2.29 and 2.22
    // with eight lanes at a time everywhere; the bunny 2.27 and 2.67 (noisy), 2.07 and 2.12,
    // 1.93 and 2.02.
    #[inline(always)]
    fn test_lanes<X: Wide, S: Stats, const ANY: bool>(
        &self,
        simd: X,
        items: Range<usize>,
        lanes: &mut Lanes,
        mask: u64,
        stats: &mut S,
    ) -> u64 {
        // A vector of lanes per kernel call pays where the lanes fill the vectors they occupy:
        // a triangle costs one call per occupied vector ([`Lanes::steps`]), against one
        // four-triangle call per pack for each lane alone.
        let packs = &self.packs[items.clone()];
        let vectors = lanes.steps(mask);
        let triangles: usize = packs.iter().map(|p| p.len()).sum();
        if MT || triangles * vectors > packs.len() * mask.count_ones() as usize {
            return lane_by_lane::<Self, X, S, ANY>(self, simd, items, lanes, mask, stats);
        }
        let mut blocked = 0;
        for pack in packs {
            for k in 0..pack.len() {
                let vertex = |v: usize| {
                    Vec3::new(
                        pack.rows[3 * v][k],
                        pack.rows[3 * v + 1][k],
                        pack.rows[3 * v + 2][k],
                    )
                };
                let tri = Triangle::new(vertex(0), vertex(1), vertex(2));
                if ANY {
                    blocked |= lanes.occluded(&tri, pack.ids[k], mask & !blocked, stats);
                    if mask & !blocked == 0 {
                        return blocked;
                    }
                } else {
                    lanes.intersect(&tri, pack.ids[k], mask, stats);
                }
            }
        }
        blocked
    }
}

/// Triangle packs tested one lane at a time with the scalar functions: the reference.
pub(crate) struct ScalarPacks<'a> {
    pub packs: &'a [TriPack],
    pub test: TriangleTest,
}

impl Leaves for ScalarPacks<'_> {
    fn test<X: Wide, S: Stats, Q: RayQuery>(
        &self,
        _: X,
        items: Range<usize>,
        r: &RayData<X>,
        ray: &Ray,
        q: &mut Q,
        stats: &mut S,
    ) -> bool {
        for pack in &self.packs[items] {
            for lane in 0..pack.len() {
                stats.prim_test();
                let row = |k: usize| pack.row(k, lane);
                let t_far = q.t_far();
                let hit = match self.test {
                    TriangleTest::Watertight => Triangle::new(row(0), row(1), row(2))
                        .intersect_sheared(&r.shear, ray, t_far),
                    TriangleTest::MollerTrumbore => {
                        rt_core::moller_trumbore_edges(row(0), row(1), row(2), ray, t_far)
                    }
                };
                if Q::OCCLUSION {
                    trace::blocked(stats, pack.ids[lane], hit.is_some());
                } else {
                    trace::tested(stats, pack.ids[lane], hit.map(|p| p.t));
                }
                if let Some(p) = hit {
                    let p = if Q::OCCLUSION { BLOCKS } else { p };
                    if q.offer(pack.ids[lane], p).is_break() || Q::OCCLUSION {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// Primitives of any type, in leaf order, with their input indices.
pub(crate) struct Prims<'a, P> {
    pub prims: &'a [P],
    pub ids: &'a [u32],
}

impl<P: Primitive> Leaves for Prims<'_, P> {
    #[inline(always)]
    fn test<X: Wide, S: Stats, Q: RayQuery>(
        &self,
        _: X,
        items: Range<usize>,
        _: &RayData<X>,
        ray: &Ray,
        q: &mut Q,
        stats: &mut S,
    ) -> bool {
        let mut items = self.prims[items.clone()].iter().zip(&self.ids[items]);
        items.any(|(prim, &id)| leaf::offer_hit(prim, id, ray, q, stats) == ControlFlow::Break(()))
    }
}

/// How a trace names a child of the wide tree: a node by its index, a leaf by its first item.
fn place(c: ChildRef) -> Place {
    if c.is_leaf() {
        Place::Leaf(c.items().start as u32)
    } else {
        Place::Node(c.index() as u32)
    }
}

/// One ray through [`wide`] with an instruction set's operations ([`rt_simd::Isa::wide`] runs
/// it inside a frame compiled for them).
pub(crate) struct WideRay<'a, L, S, Q> {
    pub nodes: &'a [WideNode],
    pub leaves: &'a L,
    pub ray: &'a Ray,
    pub sort: bool,
    pub q: &'a mut Q,
    pub stats: &'a mut S,
}

impl<L: Leaves, S: Stats, Q: RayQuery> WithLanes for WideRay<'_, L, S, Q> {
    type Out = ();
    #[inline(always)]
    fn run<X: Simd<4> + Simd<8>>(self, simd: X) {
        wide(
            simd,
            self.nodes,
            self.leaves,
            self.ray,
            self.sort,
            self.q,
            self.stats,
        );
    }
}

/// [`WideRay`] for a closest hit written into `out`, the caller's slot: the path of a bundle of
/// one ray.
///
/// A returned answer comes back through a hidden pointer, field by field in 4-byte stores. A
/// caller that copies it on into a slice reads it back at once with wider loads, which the CPU
/// cannot forward from those stores, so the copy waits for the stores to retire. Written in
/// place, there is no copy to wait for. The single-ray query keeps its return value: routed
/// through an answer slot of its own, it is the one that copies (2.5% slower on the bunny).
// PERF: a bundle of one ray over a single-ray call, wide tree, geometric mean of four scenes
// (`cargo bench -p rt-benches --bench bundle_of_one`): 1.043 with the copy, 1.007 in place.
pub(crate) struct WideRayInto<'a, L, S> {
    pub nodes: &'a [WideNode],
    pub leaves: &'a L,
    pub ray: &'a Ray,
    pub sort: bool,
    pub stats: &'a mut S,
    pub out: &'a mut Option<Hit>,
}

impl<L: Leaves, S: Stats> WithLanes for WideRayInto<'_, L, S> {
    type Out = ();
    #[inline(always)]
    fn run<X: Simd<4> + Simd<8>>(self, simd: X) {
        let mut q = ClosestHit::new(self.ray);
        wide(
            simd,
            self.nodes,
            self.leaves,
            self.ray,
            self.sort,
            &mut q,
            self.stats,
        );
        *self.out = q.hit();
    }
}

/// The wide traversal core, shared by every ray query.
/// `sort = false` skips sorting the children a closest-hit ray enters (a switch to measure what
/// the sorting gains; see [`Ablation::sort_children`](crate::Ablation::sort_children)). It is a
/// value rather than a type parameter: as one, it compiled a second copy of every closest-hit
/// walk (for each leaf test, instruction set and statistics sink) to save a branch that goes
/// the same way on every node of a run.
///
/// Each visit tests all children of a node with one slab test, which the next round of the loop
/// reads: the root's is made first, the visits of nodes popped or chosen make the others.
/// Closest hit: the children entered are sorted by entry distance; the nearest is visited next
/// and the others pushed with their distances, farthest first, and skipped when popped if they
/// start beyond the query's far end (allowing [`SLAB_FAR_SCALE`], as the box test does), which
/// for a closest hit is the best hit found meanwhile. Every query but occlusion walks this way.
/// Occlusion ([`RayQuery::OCCLUSION`]): no sorting (measured slower: it found hits no sooner);
/// the children are pushed in lane order, and the first hit ends the walk. Leaves are tested
/// when popped, like nodes.
#[inline(always)]
pub(crate) fn wide<X: Wide, L: Leaves, S: Stats, Q: RayQuery>(
    simd: X,
    nodes: &[WideNode],
    leaves: &L,
    ray: &Ray,
    sort: bool,
    q: &mut Q,
    stats: &mut S,
) {
    wide_from(simd, nodes, 0, leaves, ray, None, sort, q, stats);
}

/// [`wide`] over the subtree of node `root` only, with the ray's shear for the watertight test
/// if it is known: how a stream (`stream.rs`) hands a ray on to walk alone where few rays go
/// together.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn wide_from<X: Wide, L: Leaves, S: Stats, Q: RayQuery>(
    simd: X,
    nodes: &[WideNode],
    root: usize,
    leaves: &L,
    ray: &Ray,
    shear: Option<Shear>,
    sort: bool,
    q: &mut Q,
    stats: &mut S,
) {
    // PERF: the root is tested before the triangle tests' part of the ray is set up, which a
    // ray that misses every child never needs: single-threaded, interleaved runs of both builds,
    // bunny primary rays 1.04x and incoherent 1.03x as fast, shadow rays unchanged.
    // PERF: and that test's answer is the root's visit, rather than testing the root again in
    // the loop. Intel Emerald Rapids, one thread, private harness (filled view's primary rays,
    // 500k incoherent rays, the primary hits' shadow rays), best of 5 passes, three
    // alternating runs, Mrays/s, before -> after: woody primary 18.22 18.05 17.41 -> 19.74
    // 19.71 19.82, incoherent 11.09 11.07 10.99 -> 12.22 12.26 12.26; the bunny 8.55 8.48 8.39
    // -> 8.98 8.91 8.93, 5.27 5.16 5.21 -> 5.48 5.40 5.44, shadow 6.59 6.56 6.52 -> 6.85 6.86
    // 6.82; the teapot 10.56 10.50 10.28 -> 11.02 11.16 11.01, 5.54 5.41 5.45 -> 5.84 5.77
    // 5.81; random soup 3.25 3.23 3.24 -> 3.35 3.37 3.36, 1.68 1.71 1.70 -> 1.77 1.77 1.77.
    // Moving the pushes of the sorted children into a helper of their own ran 1-3% slower on
    // incoherent rays (the bunny, the teapot; five alternating runs), so they stay inline.
    let boxes = kernels::box_ray(simd, ray);
    stats.node_visit();
    trace::report(stats, || Event::Enter {
        place: Place::Node(root as u32),
        t0: ray.t_min,
        t1: f32::INFINITY,
        bounds: None,
    });
    let (mut mask, mut t_entry) = kernels::slab8(simd, &nodes[root], &boxes, q.t_far());
    if mask == 0 {
        trace::report(stats, || {
            Event::Note("the ray misses every child box of the root")
        });
        return;
    }
    let r = match shear {
        Some(shear) => RayData::with_shear(simd, ray, boxes, shear),
        None => RayData::new(simd, ray, boxes),
    };
    let mut stack = Stack::<(u32, f32), WIDE_STACK>::new();
    let mut node = &nodes[root];
    loop {
        // `node`'s children the ray enters (`mask`, entered at `t_entry`): the one to visit
        // next, if any, the others pushed.
        let t_children = if S::TRACE {
            Simd::<8>::store(simd, t_entry)
        } else {
            [0.0; 8]
        };
        report_children(node, mask, &t_children, stats);
        let mut next = None;
        if Q::OCCLUSION {
            let mut m = mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                stack.push((node.children[i], 0.0));
                prefetch_node(nodes, node.child(i));
                report_push(stats, node.child(i), t_children[i]);
            }
        } else if mask & mask.wrapping_sub(1) == 0 {
            // No child entered, or one: visited next without sorting.
            if mask != 0 {
                let i = mask.trailing_zeros() as usize;
                next = Some((node.child(i), t_children[i]));
            }
        } else if !sort {
            // Unsorted (only to measure what sorting gains): the first child entered next,
            // the others pushed in lane order with their entry distances.
            let t_entry = Simd::<8>::store(simd, t_entry);
            let first = mask.trailing_zeros() as usize;
            let mut m = mask & (mask - 1);
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                stack.push((node.children[i], t_entry[i]));
            }
            next = Some((node.child(first), t_entry[first]));
        } else {
            // The entered children sorted farthest first, by keys of the entry distance's
            // bits above the child reference.
            let t_entry = Simd::<8>::store(simd, t_entry);
            let mut k = [0u64; WIDTH];
            let mut n = 0;
            let mut m = mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                k[n] = u64::from(t_entry[i].to_bits()) << 32 | u64::from(node.children[i]);
                prefetch_entered(nodes, node.child(i));
                n += 1;
            }
            sort_descending(&mut k, n);
            // Each key decoded where it is used: decoding all eight slots into an array first
            // cost instructions on every sorted node. PERF: AMD Zen 3, rt-bvh ÷ Embree 3 medium
            // in one process (9 interleaved passes, geometric mean of three runs over the bunny,
            // the teapot, the rocker arm and the sphereflake): primary 0.890 -> 0.918,
            // incoherent 0.867 -> 0.878 (shadow rays, which do not sort, 0.947 -> 0.948);
            // 811 -> 801 instructions per bunny primary ray (cachegrind).
            let entry = |k: u64| (k as u32, f32::from_bits((k >> 32) as u32));
            for &key in &k[..n - 1] {
                let h = entry(key);
                stack.push(h);
                report_push(stats, ChildRef(h.0), h.1);
            }
            let (c, t) = entry(k[n - 1]);
            next = Some((ChildRef(c), t));
        }
        // Visit `next`, or what the stack holds: leaves until a node is reached, whose
        // children's slab test feeds the next round.
        loop {
            let (current, t_current) = match next.take() {
                Some(c) => c,
                None => match pop_next(&mut stack, q, stats) {
                    Some(c) => c,
                    None => return,
                },
            };
            stats.node_visit();
            trace::report(stats, || Event::Enter {
                place: place(current),
                t0: t_current,
                t1: f32::INFINITY,
                bounds: None,
            });
            if !current.is_leaf() {
                node = &nodes[current.index()];
                (mask, t_entry) = kernels::slab8(simd, node, &r.boxes, q.t_far());
                break;
            }
            if leaves.test(simd, current.items(), &r, ray, q, stats) {
                return;
            }
        }
    }
}

/// Pops the next subtree that can still hold a hit within the query's far end (any, for an
/// occlusion query), skipping the others; `None` when the stack is empty.
#[inline(always)]
fn pop_next<S: Stats, Q: RayQuery, const N: usize>(
    stack: &mut Stack<(u32, f32), N>,
    q: &Q,
    stats: &mut S,
) -> Option<(ChildRef, f32)> {
    loop {
        let Some((child, t)) = stack.pop() else {
            trace::report(stats, || Event::Note("stack empty: done"));
            return None;
        };
        let skipped = !Q::OCCLUSION && t > q.t_far() * SLAB_FAR_SCALE;
        trace::report(stats, || Event::Pop {
            place: place(ChildRef(child)),
            t,
            skipped,
        });
        if !skipped {
            return Some((ChildRef(child), t));
        }
    }
}

/// Reports to a trace the children of `node` in `mask` with their entry distances.
#[inline(always)]
fn report_children<S: Stats>(node: &WideNode, mask: u32, t: &[f32; 8], stats: &mut S) {
    if S::TRACE {
        let mut m = mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            let (place, t) = (place(node.child(i)), t[i]);
            stats.event(Event::Child { place, t });
        }
    }
}

/// Reports to a trace a child pushed with its entry distance.
#[inline(always)]
fn report_push<S: Stats>(stats: &mut S, c: ChildRef, t: f32) {
    trace::report(stats, || Event::Push { place: place(c), t });
}

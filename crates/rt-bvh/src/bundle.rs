//! Bundle traversal of the wide tree: up to 64 rays of one direction octant walk the tree
//! together ([`rt_core::bundle`]).
//!
//! The technique is the interval-culled packet traversal of Wald, Boulos & Shirley (2007, "Ray
//! tracing deformable scenes using dynamic bounding volume hierarchies") on an 8-wide tree, with
//! per-lane masks as in Overbeck et al. (2008, "Large ray packets for real-time Whitted ray
//! tracing") rather than a first-active index:
//! - at a node, one vector test bounds the whole bundle against all eight children
//!   ([`interval8`]: interval arithmetic over the lanes' origins and reciprocal directions), and
//!   culls the children no lane can enter;
//! - each child left is tested against the active lanes, eight lanes per vector, with each lane's
//!   own slab arithmetic (the single ray's [`slab8`](crate::kernels::slab8), lane by lane), giving
//!   the exact mask of lanes that enter it; when all lanes start from one point (a camera's),
//!   only leaves are, and an inner child takes all active lanes, as Embree's coherent packets
//!   do: from one origin the interval bound is nearly as tight as the lanes' own tests;
//! - children are visited nearest first by their interval entry bound, pushed with their lane
//!   masks; a leaf of watertight triangle packs tests each triangle against a vector of lanes
//!   at a time (rt-core's [`Lanes`], eight or sixteen wide, ray-parallel as Embree's packet
//!   kernels are) where its lanes fill enough vectors, else each lane alone with its single
//!   ray's leaf test (triangle-parallel, four triangles at a time), as `Leaves::test_lanes`
//!   decides.
//!
//! So every lane tests a superset of the primitives its single ray tests (the interval test is
//! conservative, see [`rt_simd::Bundle::may_enter`], and the lane tests are the single ray's),
//! each with the single ray's arithmetic, and keeps the best by the same tie rule: its answer is
//! the single ray's, bit for bit.

use crate::kernels::Wide;
use crate::node::{ChildRef, Node, WIDTH, WideNode};
use crate::traverse::{Leaves, WIDE_STACK};
use crate::{Items, MAX_DEPTH};
use rt_core::Stack;
use rt_core::{Primitive, SLAB_FAR_SCALE, Stats};
use rt_simd::bundle::narrow;
use rt_simd::{BUNDLE_LANES, Bundle, Lanes, Simd, WithLanes};

/// The most the lanes' directions may spread ([`Bundle::direction_spread`], about radians) for
/// the bundle to walk together; wider bundles go singly.
// PERF: without a bound (and without `walk_groups`' test of a run's first rays), incoherent
// rays walked as bundles of a sixth of their lanes at 0.49-0.64x the speed of single rays
// (`compare --rays incoherent --bundle 8x8 -j 1`: teapot in a stadium, sphereflake, bunny).
// PERF: shadow rays of the sphereflake's filled view in 8x8 tiles, bundles ÷ single rays
// (`compare --scene sphereflake --rays shadow --bundle 8x8 -j 1`): at 0.08, a quarter of the
// rays went singly and the bundles ran at 1.44x (wide BVH), 1.60x (binary BVH), 1.29x
// (kd-tree), 1.87x (octree); at 1.0, 1.77x, 2.11x, 1.44x, 2.51x; at 2.0 or without a bound, no
// better. Rays in random directions rarely reach this test (`walk_groups` sends runs whose
// first rays point apart singly), and were 0.98-1.00x at every bound tried.
pub(crate) const MAX_SPREAD: f32 = 1.0;

/// The most the lanes' origins may spread, as a share of the tree's box's longest side (the
/// origins' box's longest side against it), for the bundle to walk together; wider bundles go
/// singly. Lanes from scattered points part ways near their origins, where the tree is finest,
/// even when they all aim at one light: a bundle then walks the union of its lanes' paths.
// PERF: AMD Zen 4, one thread, wide BVH, without a bound -> 0.25. A path tracer's shadow rays
// after a bounce (scattered over the bunny, toward one light): batch ÷ single rays 0.77 ->
// 0.98 (`cargo xtask render --integrator path --scene ../shared/meshes/stanford-bunny.obj
// --width 1024 --height 768 --samples 8 --depth 5 -j 1`, each call paired; depth 1, two runs
// each; 0.1 and 0.05 gave 0.94-0.96). A camera's shadow rays in 8×8 tiles (`cargo xtask compare
// --rays shadow --bundle 8x8 -s bvh -j 1`, bundles ÷ single rays, two runs each): the
// sphereflake 1.91 1.79 -> 1.77 1.65 (9.3% of its rays then go singly: tiles across its
// spheres' depths), the teapot in a stadium 1.81 2.56 -> 2.44 2.92 and the rocker arm 2.70
// 2.75 -> 2.42 2.83 (0.0% and 0.5% singly: noise), the bunny 2.16 -> 2.12.
pub(crate) const MAX_ORIGIN_SPREAD: f32 = 0.25;

/// Vectors of eight lanes in a bundle of [`BUNDLE_LANES`].
const GROUPS: usize = BUNDLE_LANES / 8;

/// The interval test of all eight children against the bundle: a bit mask of the children some
/// lane may enter, and a lower bound of every lane's entry distance into each. `one_origin`:
/// whether all lanes start from one point, which halves the products. Lane by lane of
/// the children, this is [`Bundle::may_enter`] (the same operations; see there why it is
/// conservative).
#[inline(always)]
fn interval8<X: Simd<8>>(
    s: X,
    node: &WideNode,
    b: &Bundle,
    t_hi: f32,
    one_origin: bool,
) -> (u32, [f32; WIDTH]) {
    let lb = b.lane_bounds();
    let mut t0 = s.splat(lb.t_min_lo);
    let mut t1 = s.splat(t_hi);
    for a in 0..3 {
        let negative = b.octant() >> a & 1 != 0;
        let (near, far) = if negative { (a + 3, a) } else { (a, a + 3) };
        let (lo, hi) = (s.splat(lb.inv_dir_lo[a]), s.splat(lb.inv_dir_hi[a]));
        let (o_lo, o_hi) = (s.splat(lb.origin_lo[a]), s.splat(lb.origin_hi[a]));
        let near = s.load(&node.bounds[near]);
        let far = s.load(&node.bounds[far]);
        if one_origin {
            // The lanes' origins are one point, so `near - o_lo` and `near - o_hi` are the
            // same numbers and half the products below repeat: the same bounds.
            // PERF: close views, private harness, one thread, medians of five alternating
            // runs, Mrays/s: the sphereflake 38.0 -> 38.2, the bunny 42.2 -> 42.2, the teapot
            // 62.4 -> 63.0, the teapot in a stadium 68.8 -> 70.7.
            let n = s.sub(near, o_lo);
            let f = s.sub(far, o_lo);
            t0 = s.max(s.min(s.mul(n, lo), s.mul(n, hi)), t0);
            t1 = s.min(s.max(s.mul(f, lo), s.mul(f, hi)), t1);
            continue;
        }
        let (n0, n1) = (s.sub(near, o_hi), s.sub(near, o_lo));
        let near_lo = s.min(
            s.min(s.mul(n0, lo), s.mul(n0, hi)),
            s.min(s.mul(n1, lo), s.mul(n1, hi)),
        );
        let (f0, f1) = (s.sub(far, o_hi), s.sub(far, o_lo));
        let far_hi = s.max(
            s.max(s.mul(f0, lo), s.mul(f0, hi)),
            s.max(s.mul(f1, lo), s.mul(f1, hi)),
        );
        t0 = s.max(near_lo, t0);
        t1 = s.min(far_hi, t1);
    }
    let mask = s.bits(s.le(t0, s.mul(t1, s.splat(SLAB_FAR_SCALE))));
    (mask, s.store(t0))
}

/// For each child in `children`, the lanes of `active` that enter it: each lane's own slab test
/// against its own best `t` (`t_max`), eight lanes per vector, the operations of
/// [`slab8`](crate::kernels::slab8) in the same order.
#[inline(always)]
fn lanes_entering<X: Simd<8>>(
    s: X,
    node: &WideNode,
    children: u32,
    b: &Bundle,
    t_max: &[f32; BUNDLE_LANES],
    active: u64,
    one_origin: bool,
) -> [u64; WIDTH] {
    let mut lanes = [0u64; WIDTH];
    let octant = b.octant();
    let rows = |a: usize| {
        let negative = octant >> a & 1 != 0;
        if negative { (a + 3, a) } else { (a, a + 3) }
    };
    let rows = [rows(0), rows(1), rows(2)];
    // With one origin, each plane's distance from it is the same for every lane: taken once
    // per node for all eight children, here, instead of in every vector of lanes. A lane whose
    // origin is the other zero than `origin_lo`'s may get the other zero for a plane at zero,
    // which changes no comparison below: the mask is the lanes' own.
    // PERF: the filled views at half the distance (97.5%, 79.5%, 94.2% and 100% of the rays
    // hit), primary rays in 8×8 tiles, one thread, medians of five alternating runs of a
    // private harness, Mrays/s: the teapot 71.8 -> 74.5, the bunny 53.3 -> 54.6, the
    // sphereflake 41.2 -> 42.4, the teapot in a stadium 75.6 -> 75.7.
    let lb = b.lane_bounds();
    let plane = |row: usize, a: usize| {
        let d = s.sub(s.load(&node.bounds[row]), s.splat(lb.origin_lo[a]));
        s.store(d)
    };
    let (near_d, far_d) = if one_origin {
        (
            [
                plane(rows[0].0, 0),
                plane(rows[1].0, 1),
                plane(rows[2].0, 2),
            ],
            [
                plane(rows[0].1, 0),
                plane(rows[1].1, 1),
                plane(rows[2].1, 2),
            ],
        )
    } else {
        ([[0.0; WIDTH]; 3], [[0.0; WIDTH]; 3])
    };
    for g in 0..GROUPS {
        let group = (active >> (8 * g)) as u8;
        if group == 0 {
            continue;
        }
        let at = |v: &[f32; BUNDLE_LANES]| s.load(&v.as_chunks::<8>().0[g]);
        let o = [at(&b.origin[0]), at(&b.origin[1]), at(&b.origin[2])];
        let inv = [at(&b.inv_dir[0]), at(&b.inv_dir[1]), at(&b.inv_dir[2])];
        let (t_min, t_max) = (at(&b.t_min), at(t_max));
        let mut m = children;
        while m != 0 {
            let c = m.trailing_zeros() as usize;
            m &= m - 1;
            let mut t0 = t_min;
            let mut t1 = t_max;
            for a in 0..3 {
                let (tn, tf) = if one_origin {
                    (
                        s.mul(s.splat(near_d[a][c]), inv[a]),
                        s.mul(s.splat(far_d[a][c]), inv[a]),
                    )
                } else {
                    let (near, far) = rows[a];
                    (
                        s.mul(s.sub(s.splat(node.bounds[near][c]), o[a]), inv[a]),
                        s.mul(s.sub(s.splat(node.bounds[far][c]), o[a]), inv[a]),
                    )
                };
                t0 = s.max(tn, t0);
                t1 = s.min(tf, t1);
            }
            let hit = s.bits(s.le(t0, s.mul(t1, s.splat(SLAB_FAR_SCALE)))) & group as u32;
            lanes[c] |= (hit as u64) << (8 * g);
        }
    }
    lanes
}

/// The children of `node` that are leaves (as a bit mask; empty slots count too, but no lane
/// enters their empty boxes).
#[inline(always)]
fn leaf_children(node: &WideNode) -> u32 {
    let mut leaves = 0;
    for (c, &child) in node.children.iter().enumerate() {
        leaves |= u32::from(ChildRef(child).is_leaf()) << c;
    }
    leaves
}

/// One bundle through [`wide_bundle`] with an instruction set's operations
/// ([`rt_simd::Isa::wide`] runs it inside a frame compiled for them).
pub(crate) struct WideBundle<'a, 'b, L, S, const ANY: bool> {
    pub nodes: &'a [WideNode],
    pub leaves: &'a L,
    pub bundle: &'a Bundle,
    pub lanes: &'a mut Lanes<'b>,
    pub stats: &'a mut S,
}

impl<L: Leaves, S: Stats, const ANY: bool> WithLanes for WideBundle<'_, '_, L, S, ANY> {
    type Out = ();
    #[inline(always)]
    fn run<X: Simd<4> + Simd<8>>(self, simd: X) {
        wide_bundle::<X, L, S, ANY>(
            simd,
            self.nodes,
            self.leaves,
            self.bundle,
            self.lanes,
            self.stats,
        );
    }
}

/// The bundle traversal core, shared by closest hit (`ANY = false`) and any hit (`ANY = true`):
/// records each lane's hits in `lanes`.
#[inline(always)]
pub(crate) fn wide_bundle<X: Wide, L: Leaves, S: Stats, const ANY: bool>(
    simd: X,
    nodes: &[WideNode],
    leaves: &L,
    b: &Bundle,
    lanes: &mut Lanes,
    stats: &mut S,
) {
    let mut stack = Stack::<(u32, u64, f32), WIDE_STACK>::new();
    let (mut current, mut active) = (ChildRef::node(0), b.all_lanes());
    // Lanes still tracing: an any-hit lane leaves at its first hit.
    let mut live = b.all_lanes();
    let mut t_hi = lanes.far_end();
    // Lanes from one point (a camera's) have an interval bound nearly as tight as each lane's
    // own test, so inner children skip the lanes' tests.
    // PERF: inner children's lanes taken whole, against each lane tested (private harness,
    // one thread, filled views, 8×8 tiles, two alternating runs, Mrays/s): primary rays of
    // the teapot 42.3 -> 46.4, the sphereflake 35.3 -> 37.5, the teapot in a stadium 43.7
    // -> 48.3, the rocker arm 37.8 -> 42.9; but the sphereflake's shadow rays, whose origins
    // spread over its spheres, 18.8 -> 7.2, and the stadium's 69 -> 61: so only for one
    // origin.
    let one_origin = {
        let lb = b.lane_bounds();
        lb.origin_lo == lb.origin_hi
    };
    loop {
        stats.node_visit();
        stats.bundle_lanes(b.len() as u32, active.count_ones());
        if !current.is_leaf() {
            let node = &nodes[current.index()];
            let (children, t_entry) = interval8(simd, node, b, t_hi, one_origin);
            // The children whose lanes are found exactly, each lane by its own slab test: all
            // of them, or with one origin only the leaves. The others take every active lane,
            // a superset of those that enter (which is all exactness needs), narrowed at the
            // leaves below them.
            let exact = if one_origin {
                children & leaf_children(node)
            } else {
                children
            };
            let mut entering = if exact != 0 {
                lanes_entering(simd, node, exact, b, lanes.best_t(), active, one_origin)
            } else {
                [0; WIDTH]
            };
            let mut m = children & !exact;
            while m != 0 {
                let c = m.trailing_zeros() as usize;
                m &= m - 1;
                entering[c] = active;
            }
            // The children some lane enters, farthest first, by their entry bound (any hit: in
            // lane order).
            let mut order = [(0u32, 0u64, 0.0f32); WIDTH];
            let mut n = 0;
            let mut m = children;
            while m != 0 {
                let c = m.trailing_zeros() as usize;
                m &= m - 1;
                if entering[c] == 0 {
                    continue;
                }
                let e = (node.children[c], entering[c], t_entry[c]);
                let mut j = n;
                while !ANY && j > 0 && order[j - 1].2 < e.2 {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = e;
                n += 1;
            }
            if n > 0 {
                for &e in &order[..n - 1] {
                    stack.push(e);
                }
                (current, active) = (ChildRef(order[n - 1].0), order[n - 1].1);
                continue;
            }
        } else {
            live &= !leaves.test_lanes::<X, S, ANY>(simd, current.items(), lanes, active, stats);
            if ANY && live == 0 {
                return;
            }
            t_hi = lanes.far_end();
        }
        // Pop the next subtree that some live lane may still need.
        loop {
            let Some((child, entered, t)) = stack.pop() else {
                return;
            };
            let entered = entered & live;
            if entered != 0 && (ANY || t <= t_hi * SLAB_FAR_SCALE) {
                (current, active) = (ChildRef(child), entered);
                break;
            }
        }
    }
}

/// The binary tree's bundle walk: the packet traversal of Wald, Boulos & Shirley (2007) with a
/// lane mask per stack entry, as rt-kdtree's over its cells. At each node
/// [`narrow`] keeps the lanes that may enter its box: all of them when
/// the first active lane's own slab test enters it, none when the bundle's interval bound
/// rules it out, else each lane's own test. Children go nearest first along their split axis
/// in the bundle's octant. At a leaf each primitive is tested against the lanes that reached
/// it, eight lanes per step ([`Lanes`]).
///
/// Exact, as the wide tree's walk: a lane's closest hit lies in every box on the path to its
/// leaf, and the lane's own slab test, with a best `t` no nearer than that hit, enters each of
/// them (within [`SLAB_FAR_SCALE`], as the single walk allows), so the lane tests the
/// primitive; every hit it records is a true hit of its own test, so the closest by the tie
/// rule is its single ray's answer.
#[inline(always)]
pub(crate) fn binary_bundle<P: Primitive, S: Stats, const ANY: bool>(
    nodes: &[Node],
    items: &Items<P>,
    b: &Bundle,
    lanes: &mut Lanes,
    stats: &mut S,
) {
    // One far child waits per level at most, and the builder bounds the depth.
    let mut stack = [(0u32, 0u64); MAX_DEPTH + 1];
    stack[0] = (0, b.all_lanes());
    let mut sp = 1;
    let mut live = b.all_lanes();
    let mut t_hi = lanes.far_end();
    while sp > 0 {
        sp -= 1;
        let (index, entered) = stack[sp];
        let node = &nodes[index as usize];
        let active = narrow(b, lanes, &node.bounds, entered & live, t_hi, false);
        if active == 0 {
            continue;
        }
        stats.node_visit();
        stats.bundle_lanes(b.len() as u32, active.count_ones());
        if node.is_leaf() {
            let range = node.prim_range();
            for (prim, &id) in items.prims[range.clone()].iter().zip(&items.ids[range]) {
                if ANY {
                    live &= !lanes.occluded(prim, id, active & live, stats);
                    if active & live == 0 {
                        break;
                    }
                } else {
                    lanes.intersect(prim, id, active, stats);
                }
            }
            if live == 0 {
                return;
            }
            t_hi = lanes.far_end();
            continue;
        }
        // Pushed far first, so the child the lanes reach first comes off next.
        let (first, second) = (index + 1, node.index);
        let (near, far) = if b.octant() >> node.axis & 1 == 0 {
            (first, second)
        } else {
            (second, first)
        };
        stack[sp] = (far, active);
        stack[sp + 1] = (near, active);
        sp += 2;
    }
}

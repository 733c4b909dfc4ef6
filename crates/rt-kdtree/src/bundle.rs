//! Bundles through the kd-tree: packet traversal for rays that share their direction signs
//! (Wald 2004, "Realtime ray tracing and interactive global illumination", §7), with a lane mask
//! per stack entry.
//!
//! All lanes of a bundle point the same way along every axis, so at each split plane the child
//! on the side the lanes come from is the near child for all of them: one order of the children
//! is front to back for every lane. Wald's packets carry each lane's interval `[t0, t1]` down the
//! tree; here the walk carries each node's cell (cut from the scene box by the planes above it)
//! and the mask of lanes that enter it, and the lanes are tested against the cell itself:
//! - one interval test bounds the whole bundle against the cell ([`Bundle::may_enter`]) and
//!   skips it for all lanes at once;
//! - otherwise the first active lane's own slab test against the cell, with its own best hit
//!   so far, and when that fails every active lane's ([`Bundle::lanes_entering`], eight lanes
//!   per step), gives the lanes that go on ([`narrow`]).
//!   Once the first lane stops entering, a lane that found a hit before the cell drops out
//!   there, as its single walk stops, so a bundle whose lanes hit at different depths does not
//!   drag every lane down every path.
//!
//! Lanes that would disagree at a plane (one passes only on the near side, another only on the
//! far side) need no special case: each child is entered by the lanes whose slab test reaches
//! its cell (and perhaps some more, which only test primitives they cannot hit). A lane lying in a split plane reaches both cells, as the in-plane rule of the single
//! walk has it (a cell is closed, so its boundary plane belongs to both sides).
//!
//! Exact: the builder lists a primitive in every leaf whose closed cell it overlaps, so a lane's
//! closest true hit lies in the cell of a leaf that lists its primitive; the lane's slab test
//! enters that cell at or before the hit (within [`SLAB_FAR_SCALE`](rt_core::SLAB_FAR_SCALE),
//! as the single walk allows), so the leaf is tested for the lane. Every hit a lane records is a
//! true hit of its own test (the shared eight-lane kernel, [`test_primitives`]), so the closest
//! of them (ties to the smaller primitive) is the single walk's answer, bit for bit.
//!
//! Bundles whose directions spread more than [`MAX_SPREAD`] go singly, as their lanes would share
//! few cells.

use crate::{KdTree, MAX_DEPTH};
use rt_core::{Aabb, Hit, Primitive, Ray, Stats};
use rt_simd::bundle::{Bundle, LaneMailbox, Lanes, narrow, test_primitives};

/// The most the lanes' directions may spread ([`Bundle::direction_spread`], about radians) for
/// the bundle to walk together.
// PERF: shadow rays of the sphereflake's filled view in 8x8 tiles, bundles ÷ single rays
// (`compare --scene sphereflake --rays shadow --bundle 8x8 -j 1`): at 0.08, a quarter of the
// rays went singly and the bundles ran at 1.44x (wide BVH), 1.60x (binary BVH), 1.29x
// (kd-tree), 1.87x (octree); at 1.0, 1.77x, 2.11x, 1.44x, 2.51x; at 2.0 or without a bound, no
// better. Rays in random directions rarely reach this test (`walk_groups` sends runs whose
// first rays point apart singly), and were 0.98-1.00x at every bound tried.
pub const MAX_SPREAD: f32 = 1.0;

impl<P: Primitive> KdTree<P> {
    /// The bundle queries ([`walk_groups`](rt_simd::bundle::walk_groups)): each bundle whose
    /// directions stay within [`MAX_SPREAD`] walked as a packet, every other ray walked alone by
    /// the tree's own single-ray traversal.
    pub(crate) fn bundle_query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        order: Option<&[u32]>,
        stats: &mut S,
        answer: impl FnMut(usize, Option<Hit>),
    ) {
        rt_simd::bundle::walk_groups_ordered::<S, ANY>(
            rays,
            slots,
            order,
            stats,
            |ray, stats| rt_simd::bundle::single::<_, S, ANY>(self, ray, stats),
            |b| {
                b.route(&self.bounds, |b| {
                    !self.refs.is_empty() && b.direction_spread() <= MAX_SPREAD
                })
            },
            // Inlined, so that the walk is compiled with the vector instructions `walk_groups` runs
            // with (`Isa::run`).
            #[inline(always)]
            |b, lanes, stats| {
                self.packet::<S, ANY>(b, lanes, stats);
                0
            },
            answer,
        );
    }

    /// The packet walk of bundle `b`, recording hits in `lanes`: front to back in the bundle's
    /// octant, each stack entry a node, its cell and the lanes that entered its parent.
    #[inline(always)]
    fn packet<S: Stats, const ANY: bool>(&self, b: &Bundle, lanes: &mut Lanes, stats: &mut S) {
        let nodes = &self.nodes[..];
        let mut mailbox = LaneMailbox::new();
        // One far child waits per level at most, and the builder bounds the depth.
        let mut stack = [(0u32, 0u64, Aabb::EMPTY); MAX_DEPTH + 1];
        stack[0] = (0, b.all_lanes(), self.bounds);
        let mut sp = 1;
        let mut live = b.all_lanes();
        let mut t_hi = lanes.far_end();
        while sp > 0 {
            sp -= 1;
            let (index, entered, cell) = stack[sp];
            let node = &nodes[index as usize];
            if node.is_leaf() && node.count() == 0 {
                continue;
            }
            // PERF: the first-lane rule at leaves too. Exact masks at leaves (every lane's own
            // test) traced the filled views' primary rays slower: bunny 12.6 against 13.1
            // Mrays/s, teapot.obj 26.0 against 28.0 (one thread, 8×8 tiles, alternating runs).
            let active = narrow(b, lanes, &cell, entered & live, t_hi, false);
            if active == 0 {
                continue;
            }
            stats.node_visit();
            stats.bundle_lanes(b.len() as u32, active.count_ones());
            if node.is_leaf() {
                let ids = &self.refs[node.index()..node.index() + node.count()];
                let blocked = test_primitives::<P, S, ANY>(
                    &self.prims,
                    ids,
                    (b, t_hi),
                    lanes,
                    active,
                    &mut mailbox,
                    stats,
                );
                live &= !blocked;
                if live == 0 {
                    return;
                }
                t_hi = lanes.far_end();
                continue;
            }
            let (a, split, first) = (node.axis(), node.split(), node.index() as u32);
            let (mut below, mut above) = (cell, cell);
            below.max[a] = split;
            above.min[a] = split;
            // Pushed far first, so the child the lanes reach first comes off next.
            let (near, far) = if b.octant() >> a & 1 == 0 {
                ((first, below), (first + 1, above))
            } else {
                ((first + 1, above), (first, below))
            };
            stack[sp] = (far.0, active, far.1);
            stack[sp + 1] = (near.0, active, near.1);
            sp += 2;
        }
    }
}

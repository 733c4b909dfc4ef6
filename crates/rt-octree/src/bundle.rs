//! Bundles through the octree: a packet walk in the bundle's direction octant.
//!
//! All lanes of a bundle share their direction signs, so one child order is front to back for
//! every lane: child `k` in ray order (bit `a` set for the far half along axis `a`) is child
//! `k ^ octant` of the block. The walk keeps one stack for the whole bundle, each entry with
//! the lanes that entered its parent, narrowed at each node ([`narrow`]): the first of them
//! tested against the node's box with its own slab test and, when it fails and at every leaf,
//! all of them with theirs; a node none can enter before the farthest best hit of the bundle is
//! culled for all at once ([`Bundle::may_enter`], an interval bound that is conservative for
//! every lane's slab test). A leaf's primitives are tested against its lanes, eight per vector
//! step, each skipped when no lane can enter its box ([`test_primitives`]), with one mailbox
//! for the bundle. Any-hit lanes leave at their first hit.
//!
//! Exact: a lane's closest true hit lies in the closed box of a leaf that lists its primitive
//! (the builder lists a primitive in every child it reaches, with a margin); the lane's slab
//! test enters that box at or before the hit, so the bundle's bound does, and the leaf is
//! tested for the lane. Every hit a lane records is a true hit of its own test, so the closest
//! of them (ties to the smaller index) is the single walk's answer. The child boxes come from
//! the builder's own midpoints.
//!
//! Bundles whose directions spread more than [`MAX_SPREAD`] go singly: their lanes share few
//! nodes.

use crate::Octree;
use crate::builder::MAX_DEPTH;
use crate::node::{Node, child_box, midpoint};
use rt_core::{Aabb, Hit, Primitive, Ray, Stats};
use rt_simd::bundle::{Bundle, LaneMailbox, Lanes, narrow, test_primitives};

/// The most the lanes' slopes across their major axis may spread, summed over the two other
/// axes (about radians) for the bundle to walk together.
// PERF: shadow rays of the sphereflake's filled view in 8x8 tiles, bundles ÷ single rays
// (`compare --scene sphereflake --rays shadow --bundle 8x8 -j 1`): at 0.08, a quarter of the
// rays went singly and the bundles ran at 1.44x (wide BVH), 1.60x (binary BVH), 1.29x
// (kd-tree), 1.87x (octree); at 1.0, 1.77x, 2.11x, 1.44x, 2.51x; at 2.0 or without a bound, no
// better. Rays in random directions rarely reach this test (`walk_groups` sends runs whose
// first rays point apart singly), and were 0.98-1.00x at every bound tried.
pub const MAX_SPREAD: f32 = 1.0;

/// Stack entries: eight children per level pushed at most.
const STACK: usize = 8 * (MAX_DEPTH as usize + 1);

impl<P: Primitive> Octree<P> {
    /// The bundle queries ([`walk_groups`](rt_simd::bundle::walk_groups)): each bundle whose
    /// directions stay within [`MAX_SPREAD`] walked as a packet, every other ray walked alone.
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
            |b| b.route(&self.bounds, |b| !self.refs.is_empty() && coherent(b)),
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

    /// The packet walk of bundle `b`, recording hits in `lanes`.
    #[inline(always)]
    fn packet<S: Stats, const ANY: bool>(&self, b: &Bundle, lanes: &mut Lanes, stats: &mut S) {
        let mut mailbox = LaneMailbox::new();
        let flip = b.octant();
        let mut stack = [(Node::leaf(0, 0), 0u64, Aabb::EMPTY); STACK];
        stack[0] = (self.root, b.all_lanes(), self.bounds);
        let mut sp = 1;
        let mut live = b.all_lanes();
        // Every lane's best hit so far is at most this (lanes only get closer).
        let mut t_hi = lanes.far_end();
        while sp > 0 {
            sp -= 1;
            let (node, entered, bx) = stack[sp];
            if node.is_empty_leaf() {
                continue;
            }
            let leaf = node.children().is_none();
            let active = narrow(b, lanes, &bx, entered & live, t_hi, leaf);
            if active == 0 {
                continue;
            }
            stats.node_visit();
            stats.bundle_lanes(b.len() as u32, active.count_ones());
            match node.children() {
                Some(block) => {
                    let mid = midpoint(&bx);
                    let children = &self.blocks[block].0;
                    // Pushed far to near, so the nearest child in ray order comes off first.
                    for k in (0..8).rev() {
                        let i = k ^ flip;
                        stack[sp] = (children[i], active, child_box(&bx, mid, i));
                        sp += 1;
                    }
                }
                None => {
                    let ids = &self.refs[node.references()];
                    live &= !test_primitives::<P, S, ANY>(
                        &self.prims,
                        ids,
                        (b, t_hi),
                        lanes,
                        active,
                        &mut mailbox,
                        stats,
                    );
                    if live == 0 {
                        return;
                    }
                    t_hi = lanes.far_end();
                }
            }
        }
    }
}

/// Whether the lanes' directions stay within [`MAX_SPREAD`] of each other.
fn coherent(b: &Bundle) -> bool {
    b.direction_spread() <= MAX_SPREAD
}

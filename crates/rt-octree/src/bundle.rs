//! Bundles through the octree: a packet walk in the bundle's direction octant.
//!
//! All lanes of a bundle share their direction signs, so one child order is front to back for
//! every lane: child `k` in ray order (bit `a` set for the far half along axis `a`) is child
//! `k ^ octant` of the block. The walk keeps one stack for the whole bundle and culls a node for
//! all lanes at once when none can enter its box before the farthest best hit of the bundle
//! ([`Bundle::may_enter`], an interval bound that is conservative for every lane's slab test).
//! A leaf's primitives are tested against the live lanes, eight per vector step, each skipped
//! when no lane can enter its box ([`test_primitives`]), with one mailbox for the bundle.
//!
//! Exact: a lane's closest true hit lies in the closed box of a leaf that lists its primitive
//! (the builder lists a primitive in every child it reaches, with a margin); the lane's slab
//! test enters that box at or before the hit, so the bundle's bound does, and the leaf is
//! tested for the lane. Every hit a lane records is a true hit of its own test, so the closest
//! of them (ties to the smaller index) is the single walk's answer. The child boxes come from
//! the builder's own midpoints.
//!
//! Bundles whose directions spread more than [`MAX_SPREAD`] go singly: with no per-lane
//! intervals, a spread bundle visits the union of its lanes' nodes.

use crate::Octree;
use crate::builder::MAX_DEPTH;
use crate::node::{Node, child_box, midpoint};
use rt_core::bundle::{Bundle, LaneMailbox, Lanes, test_primitives};
use rt_core::{Aabb, Hit, Primitive, Ray, Stats};

/// The most the lanes' slopes across their major axis may spread, summed over the two other
/// axes (about 0.08 radians) for the bundle to walk together.
pub const MAX_SPREAD: f32 = 0.08;

/// Stack entries: eight children per level pushed at most.
const STACK: usize = 8 * (MAX_DEPTH as usize + 1);

impl<P: Primitive> Octree<P> {
    /// The bundle queries ([`walk_groups`](rt_core::bundle::walk_groups)): each bundle whose
    /// directions stay within [`MAX_SPREAD`] walked as a packet, every other ray walked alone.
    pub(crate) fn bundle_query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        stats: &mut S,
        answer: impl FnMut(usize, Option<Hit>),
    ) {
        rt_core::bundle::walk_groups::<S, ANY>(
            rays,
            slots,
            stats,
            |ray, stats| self.walk::<S, ANY>(ray, stats),
            |b| !self.refs.is_empty() && coherent(b),
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
        let mut stack = [(Node::leaf(0, 0), Aabb::EMPTY); STACK];
        stack[0] = (self.root, self.bounds);
        let mut sp = 1;
        let mut live = b.all_lanes();
        while sp > 0 {
            sp -= 1;
            let (node, bx) = stack[sp];
            if node.is_empty_leaf() {
                continue;
            }
            // Every live lane's best hit so far is at most this (lanes only get closer).
            let t_hi = far_end(lanes, live);
            if !b.may_enter(&bx, t_hi) {
                continue;
            }
            stats.node_visit();
            stats.bundle_lanes(b.len() as u32, live.count_ones());
            match node.children() {
                Some(block) => {
                    let mid = midpoint(&bx);
                    let children = &self.blocks[block].0;
                    // Pushed far to near, so the nearest child in ray order comes off first.
                    for k in (0..8).rev() {
                        let i = k ^ flip;
                        stack[sp] = (children[i], child_box(&bx, mid, i));
                        sp += 1;
                    }
                }
                None => {
                    let ids = &self.refs[node.references()];
                    let t = (b, t_hi);
                    live &= !test_primitives::<P, S, ANY>(
                        &self.prims,
                        ids,
                        t,
                        lanes,
                        live,
                        &mut mailbox,
                        stats,
                    );
                    if live == 0 {
                        return;
                    }
                }
            }
        }
    }
}

/// The largest best `t` of the `live` lanes.
#[inline(always)]
fn far_end(lanes: &Lanes, live: u64) -> f32 {
    let mut t = f32::NEG_INFINITY;
    let mut m = live;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        t = t.max(lanes.t(i));
    }
    t
}

/// Whether the lanes' directions stay within [`MAX_SPREAD`] of each other, from the bundle's
/// bounds alone (constant time, so rays in random directions cost little before they go
/// singly): the spread of the slopes `d_a / d_major = inv_major / inv_a` over the corners of the
/// reciprocals' intervals, summed over the two minor axes.
fn coherent(b: &Bundle) -> bool {
    let spread: f32 = b
        .slope_bounds(b.major_axis())
        .iter()
        .map(|(lo, hi)| hi - lo)
        .sum();
    spread <= MAX_SPREAD
}

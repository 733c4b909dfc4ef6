//! What every structure does in a leaf or cell: test a list of primitives against the ray, or
//! offer them to a box query.
//!
//! Structures that reference a primitive from several cells (kd-trees, grids, octrees) share
//! this loop, with a per-ray record of what was tested ([`Seen`]) to test each primitive once;
//! the BVH, whose leaves own their primitives, needs none.

use crate::query::BLOCKS;
use crate::trace::{self, Event};
use crate::{BoxQuery, Mailbox, Primitive, Ray, RayQuery, Stats, Visited};
use std::ops::ControlFlow;

/// How a walk remembers the primitives it has tested, so that a primitive listed in several
/// cells is tested once: a [`Mailbox`] of the last few (enough for closest and any hits, which
/// a second test cannot change), or [`Visited`], every one (for queries that must see each hit
/// once, [`RayQuery::REPEATABLE`] being false).
pub trait Seen {
    /// True the first time `id` is seen (test it), false after (skip it).
    fn first_visit(&mut self, id: u32) -> bool;
}

impl<const N: usize> Seen for Mailbox<N> {
    #[inline(always)]
    fn first_visit(&mut self, id: u32) -> bool {
        !self.check_and_insert(id)
    }
}

impl Seen for Visited {
    #[inline(always)]
    fn first_visit(&mut self, id: u32) -> bool {
        Visited::first_visit(self, id)
    }
}

/// Tests the primitives `ids` (indices into `prims`) against `[ray.t_min, query.t_far()]` and
/// offers `query` each hit ([`offer_hit`]); `Break` when the query ends the walk. With
/// `dedupe`, primitives `seen` before are skipped and reported to `stats` as mailbox skips.
#[inline(always)]
pub fn test_primitives<P: Primitive, S: Stats, Q: RayQuery, M: Seen>(
    prims: &[P],
    ids: &[u32],
    ray: &Ray,
    query: &mut Q,
    seen: &mut M,
    dedupe: bool,
    stats: &mut S,
) -> ControlFlow<()> {
    for &id in ids {
        if dedupe && !seen.first_visit(id) {
            stats.mailbox_skip();
            trace::report(stats, || Event::Skip { prim: id });
            continue;
        }
        offer_hit(&prims[id as usize], id, ray, query, stats)?;
    }
    ControlFlow::Continue(())
}

/// Tests primitive `id` against `[ray.t_min, query.t_far()]`, counting the test, and offers
/// `query` its hit; `Break` when the query ends the walk, which an
/// [occlusion](RayQuery::OCCLUSION) query does at its first hit (offered as [`BLOCKS`]).
#[inline(always)]
pub fn offer_hit<P: Primitive, S: Stats, Q: RayQuery>(
    prim: &P,
    id: u32,
    ray: &Ray,
    query: &mut Q,
    stats: &mut S,
) -> ControlFlow<()> {
    stats.prim_test();
    if Q::OCCLUSION {
        let blocks = prim.occludes(ray, query.t_far());
        trace::blocked(stats, id, blocks);
        if blocks {
            let _ = query.offer(id, BLOCKS);
            return ControlFlow::Break(());
        }
        return ControlFlow::Continue(());
    }
    let hit = prim.intersect(ray, query.t_far());
    trace::tested(stats, id, hit.map(|h| h.t));
    match hit {
        Some(h) => query.offer(id, h),
        None => ControlFlow::Continue(()),
    }
}

/// Offers a box query the primitives `ids` (indices into `prims`) of a leaf or cell, each only
/// the first time this query meets it (`seen`), reporting tests and skips to `stats`: what
/// structures that list a primitive in several cells do in each cell a box query reaches.
/// `Break` as soon as the query stops.
#[inline(always)]
pub fn offer_once<P, Q: BoxQuery<P>, S: Stats>(
    prims: &[P],
    ids: &[u32],
    seen: &mut Visited,
    query: &mut Q,
    stats: &mut S,
) -> ControlFlow<()> {
    for &id in ids {
        if !seen.first_visit(id) {
            stats.mailbox_skip();
            continue;
        }
        stats.prim_test();
        query.test(&prims[id as usize], id)?;
    }
    ControlFlow::Continue(())
}

/// The one ray walk of a structure that lists a primitive in several cells (a kd-tree, a grid,
/// an octree), over a record of the primitives it has tested ([`Seen`]): [`walk_once`] runs it
/// with the record its query needs.
pub trait CellWalk {
    /// How many primitives the cells index (primitive indices are below it).
    fn prim_count(&self) -> usize;

    /// The walk for `query`, which skips the primitives `seen` has seen (see
    /// [`test_primitives`]).
    fn walk<Q: RayQuery, S: Stats, M: Seen>(
        &self,
        ray: &Ray,
        query: &mut Q,
        seen: &mut M,
        stats: &mut S,
    );
}

/// [`Accel::ray_query`](crate::Accel::ray_query) of a [`CellWalk`]: the walk with a
/// [`Mailbox`] of the last `N` primitives for a [repeatable](RayQuery::REPEATABLE) query (a
/// closest or any hit, which a second test cannot change), else with [`Visited`], every
/// primitive (all hits, counts and filters see each hit once). An invalid ray walks nothing.
#[inline(always)]
pub fn walk_once<W: CellWalk, const N: usize, Q: RayQuery, S: Stats>(
    cells: &W,
    ray: &Ray,
    query: &mut Q,
    stats: &mut S,
) {
    // Outside the precondition (NaN, huge origins, ...): answer at once, walk nothing.
    if !ray.is_valid() {
        return;
    }
    if Q::REPEATABLE {
        cells.walk(ray, query, &mut Mailbox::<N>::new(), stats);
    } else {
        Visited::with(cells.prim_count(), |seen| {
            cells.walk(ray, query, seen, stats)
        });
    }
}

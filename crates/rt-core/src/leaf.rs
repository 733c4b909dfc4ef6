//! What every structure does in a leaf or cell: test a list of primitives against the ray, or
//! offer them to a box query.
//!
//! Structures that reference a primitive from several cells (kd-trees, grids, octrees) share
//! this loop, with a per-ray [`Mailbox`] to test each primitive once; the BVH, whose leaves own
//! their primitives, needs no mailbox.

use crate::trace::{self, Event};
use crate::{BoxQuery, Hit, Mailbox, Primitive, Ray, Stats, Visited};
use std::ops::ControlFlow;

/// The "no hit yet" record of a ray whose interval ends at `t_max`.
#[inline(always)]
pub fn no_hit(t_max: f32) -> Hit {
    Hit {
        prim: u32::MAX,
        t: t_max,
        u: 0.0,
        v: 0.0,
    }
}

/// Tests the primitives `ids` (indices into `prims`) against `[ray.t_min, best.t]`, keeping
/// the closest hit in `best` (ties to the smaller index). With `ANY`, returns true at the first
/// hit instead (its index in `best.prim`). With `use_mailbox`, primitives among the last `N`
/// this ray tested are skipped and reported to `stats` as mailbox skips.
#[inline(always)]
pub fn test_primitives<P: Primitive, S: Stats, const ANY: bool, const N: usize>(
    prims: &[P],
    ids: &[u32],
    ray: &Ray,
    best: &mut Hit,
    mailbox: &mut Mailbox<N>,
    use_mailbox: bool,
    stats: &mut S,
) -> bool {
    for &id in ids {
        if use_mailbox && mailbox.check_and_insert(id) {
            stats.mailbox_skip();
            trace::report(stats, || Event::Skip { prim: id });
            continue;
        }
        stats.prim_test();
        let prim = &prims[id as usize];
        if ANY {
            let blocks = prim.occludes(ray, best.t);
            trace::blocked(stats, id, blocks);
            if blocks {
                best.prim = id;
                return true;
            }
            continue;
        }
        let hit = prim.intersect(ray, best.t);
        trace::tested(stats, id, hit.map(|h| h.t));
        if let Some(h) = hit
            && Hit::beats(h.t, id, best.t, best.prim)
        {
            *best = Hit {
                prim: id,
                t: h.t,
                u: h.u,
                v: h.v,
            };
        }
    }
    false
}

/// The answer a walk that kept `best` (starting from [`no_hit`]) returns: `None` if nothing was
/// hit; for `ANY` queries the hit with `t` set to NaN, since the first hit found need not be the
/// closest.
#[inline(always)]
pub fn answer<const ANY: bool>(best: Hit) -> Option<Hit> {
    (best.prim != u32::MAX).then_some(if ANY {
        Hit {
            t: f32::NAN,
            ..best
        }
    } else {
        best
    })
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

//! Ray queries beyond the closest and any hit: every structure's all hits, hit counts and
//! filtered queries answer exactly as brute force's.

use crate::Probe;
use rt_core::{Accel, Counters, Hit, NoStats, PrimHit, Primitive, Ray, RayQuery};
use std::fmt;
use std::ops::ControlFlow;

/// A disagreement between a structure and brute force on one ray's all-hits, count or filtered
/// query.
#[derive(Clone, Debug)]
pub struct HitsMismatch {
    /// Which query disagreed, as a call (`"all_hits"`, `"count_hits"`, ...).
    pub query: &'static str,
    /// The ray.
    pub ray: Ray,
    /// What brute force answered.
    pub expected: Box<[Hit]>,
    /// What the structure answered.
    pub got: Box<[Hit]>,
    /// More about the failure, when there is more to say (else empty).
    pub detail: Box<str>,
}

impl fmt::Display for HitsMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Each hit as (primitive, t).
        let prims = |h: &[Hit]| h.iter().map(|h| (h.prim, h.t)).collect::<Vec<_>>();
        write!(
            f,
            "{} disagrees with brute force\n  ray: {}\n  rays-file line: {}\n  expected {} hits on {:?}\n  got      {} hits on {:?}",
            self.query,
            self.ray.to_rust(),
            self.ray.to_line(),
            self.expected.len(),
            prims(&self.expected),
            self.got.len(),
            prims(&self.got),
        )?;
        if !self.detail.is_empty() {
            write!(f, "\n  {}", self.detail)?;
        }
        Ok(())
    }
}

/// The most rays of one case whose all-hits, count and filtered queries the kit checks.
pub(crate) const HITS_RAYS: usize = 64;

/// A filter as the kit names it: a plain function of the primitive and the hit.
pub type Filter = fn(u32, &PrimHit) -> bool;

/// The filters the kit runs: one by primitive (a per-primitive mask, or the primitive a
/// secondary ray leaves), one by surface coordinate (an alpha mask).
pub const FILTERS: [(&str, Filter); 2] = [
    ("|prim, _| prim % 3 != 1", |prim, _| prim % 3 != 1),
    ("|_, hit| hit.u < 0.5", |_, hit| hit.u < 0.5),
];

/// Whether two lists of hits name the same primitives with agreeing hits ([`Hit::agree`]),
/// whatever their order.
fn same_hits(a: &[Hit], b: &[Hit]) -> bool {
    let key = |h: &[Hit]| {
        let mut h = h.to_vec();
        h.sort_by_key(|h| h.prim);
        h
    };
    let (a, b) = (key(a), key(b));
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| Hit::agree(Some(*x), Some(*y)))
}

/// A query that checks what it is offered: every hit inside the ray's interval and each
/// primitive once; it stops the walk at offer `stop_at` (never for `usize::MAX`) and records
/// anything offered after that.
struct Watch {
    t_min: f32,
    t_max: f32,
    stop_at: usize,
    offered: Vec<Hit>,
    after_stop: usize,
}

impl RayQuery for Watch {
    fn t_far(&self) -> f32 {
        self.t_max
    }
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        if self.offered.len() >= self.stop_at {
            self.after_stop += 1;
            return ControlFlow::Break(());
        }
        self.offered.push(Hit {
            prim,
            t: hit.t,
            u: hit.u,
            v: hit.v,
        });
        if self.offered.len() == self.stop_at {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}

/// Compares `accel`'s ray queries beyond the closest and any hit, on every ray, with the answers
/// made from `prims` (the primitives it was built from) one by one: [`Accel::all_hits`] (the same primitives with agreeing hits, sorted by `t`, each
/// primitive once, all within the ray's interval), [`Accel::count_hits`], the same list through
/// [`Accel::ray_query`] with counters, a query that stops at its first offer (offered one of
/// the hits, and nothing after it stopped), and [`Accel::intersect_filtered`] and
/// [`Accel::occluded_filtered`] with each of [`FILTERS`]. Invalid rays must get no hit from any
/// of them.
///
/// # Errors
/// The first [`HitsMismatch`].
pub fn compare_hits<A: Accel>(
    accel: &A,
    prims: &[A::Prim],
    rays: &[Ray],
) -> Result<(), HitsMismatch> {
    compare_hits_probed(accel, prims, rays, &Probe::default())
}

/// Every hit of `ray` on the valid primitives of `prims`, each tested alone: the definition
/// the structures' all-hits queries are held to (none for an invalid ray).
pub fn hits_one_by_one<P: Primitive>(prims: &[P], ray: &Ray) -> Vec<Hit> {
    if !ray.is_valid() {
        return Vec::new();
    }
    let mut hits: Vec<Hit> = (0..prims.len())
        .filter(|&i| prims[i].is_valid())
        .filter_map(|i| {
            let h = prims[i].intersect(ray, ray.t_max)?;
            Some(Hit {
                prim: i as u32,
                t: h.t,
                u: h.u,
                v: h.v,
            })
        })
        .collect();
    // `+ 0.0` turns -0 into +0, which the tie rule counts as equal.
    hits.sort_by(|a, b| {
        (a.t + 0.0)
            .total_cmp(&(b.t + 0.0))
            .then(a.prim.cmp(&b.prim))
    });
    hits
}

pub(crate) fn compare_hits_probed<A: Accel>(
    accel: &A,
    prims: &[A::Prim],
    rays: &[Ray],
    probe: &Probe,
) -> Result<(), HitsMismatch> {
    for ray in rays {
        probe.tracing(ray);
        let mismatch = |query, expected: &[Hit], got: &[Hit], detail: String| HitsMismatch {
            query,
            ray: *ray,
            expected: expected.into(),
            got: got.into(),
            detail: detail.into(),
        };
        let expected = hits_one_by_one(prims, ray);
        let got = accel.all_hits(ray);
        if !same_hits(&expected, &got) {
            return Err(mismatch("all_hits", &expected, &got, String::new()));
        }
        let sorted = got
            .windows(2)
            .all(|w| (w[0].t, w[0].prim) < (w[1].t, w[1].prim));
        if !sorted {
            let why = "the hits must be sorted by t, ties by primitive, each primitive once";
            return Err(mismatch("all_hits", &expected, &got, why.into()));
        }
        let count = accel.count_hits(ray);
        if count != expected.len() {
            let why = format!("count_hits is {count}");
            return Err(mismatch("count_hits", &expected, &got, why));
        }
        // Every offer checked as it comes: inside the interval, each primitive once.
        let mut watch = Watch {
            t_min: ray.t_min,
            t_max: ray.t_max,
            stop_at: usize::MAX,
            offered: Vec::new(),
            after_stop: 0,
        };
        accel.ray_query(ray, &mut watch, &mut Counters::default());
        let outside = watch
            .offered
            .iter()
            .find(|h| !(h.t >= watch.t_min && h.t <= watch.t_max));
        if let Some(h) = outside {
            let why = format!(
                "primitive {} was offered at t = {}, outside the ray's interval",
                h.prim, h.t
            );
            return Err(mismatch("ray_query", &expected, &watch.offered, why));
        }
        if !same_hits(&expected, &watch.offered) {
            let why = "each hit must be offered once (counted with Counters)".to_string();
            return Err(mismatch("ray_query", &expected, &watch.offered, why));
        }
        let mut first = Watch {
            stop_at: 1,
            offered: Vec::new(),
            after_stop: 0,
            ..watch
        };
        accel.ray_query(ray, &mut first, &mut NoStats);
        let wrong = first.offered.len() != usize::from(!expected.is_empty())
            || first.after_stop != 0
            || first
                .offered
                .iter()
                .any(|h| !expected.iter().any(|e| e.prim == h.prim));
        if wrong {
            let why = format!(
                "a query that stops at its first offer must get one of the hits and nothing \
                 after it stopped; {} offered after the stop",
                first.after_stop
            );
            return Err(mismatch(
                "ray_query (stopping)",
                &expected,
                &first.offered,
                why,
            ));
        }
        for (name, filter) in FILTERS {
            let kept: Vec<Hit> = expected
                .iter()
                .copied()
                .filter(|h| {
                    filter(
                        h.prim,
                        &PrimHit {
                            t: h.t,
                            u: h.u,
                            v: h.v,
                        },
                    )
                })
                .collect();
            // The sorted list's first is the closest by the tie rule.
            let want = kept.first().copied();
            let got = accel.intersect_filtered(ray, filter);
            if !Hit::agree(want, got) {
                let why = format!("with filter {name}: expected {want:?}, got {got:?}");
                return Err(mismatch(
                    "intersect_filtered",
                    &kept,
                    &Vec::from_iter(got),
                    why,
                ));
            }
            let occluded = accel.occluded_filtered(ray, filter);
            if occluded != want.is_some() {
                let why = format!("with filter {name}: occluded_filtered is {occluded}");
                return Err(mismatch("occluded_filtered", &kept, &[], why));
            }
        }
    }
    Ok(())
}

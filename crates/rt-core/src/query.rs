//! Ray queries: what a structure's ray traversal works for.
//!
//! Every structure has one ray walk, [`Accel::ray_query`](crate::Accel::ray_query), which
//! visits the boxes or cells a ray crosses and offers each hit it finds to a [`RayQuery`]. The
//! query decides what to keep and how far the walk must still go: its [`t_far`](RayQuery::t_far)
//! is the far end of the part of the ray still wanted, and boxes or cells that start beyond it
//! are skipped. The queries the library answers are instances of it:
//!
//! | query | keeps | `t_far` | stops |
//! | --- | --- | --- | --- |
//! | [`ClosestHit`] ([`Accel::intersect`](crate::Accel::intersect)) | the best hit by [`Hit::beats`] | the best hit's `t` | never early |
//! | [`AnyHit`] ([`Accel::occluded`](crate::Accel::occluded)) | the first blocker | the ray's end | at the first hit |
//! | [`Filtered`] ([`Accel::intersect_filtered`](crate::Accel::intersect_filtered)) | what the inner query keeps of the hits the filter accepts | the inner query's | as the inner query |
//! | [`AllHits`] ([`Accel::all_hits`](crate::Accel::all_hits)) | every hit | the ray's end | never early |
//!
//! A query of one's own is a type that implements [`RayQuery`]; every structure then runs it
//! with no change to the structure. The example counts hits and stops the walk at the third:
//!
//! ```
//! use rt_core::{Accel, BruteForce, NoStats, PrimHit, Ray, RayQuery, Triangle, glam::Vec3};
//! use std::ops::ControlFlow;
//!
//! struct AtMostThree { t_far: f32, hits: u32 }
//! impl RayQuery for AtMostThree {
//!     fn t_far(&self) -> f32 { self.t_far }
//!     fn offer(&mut self, _prim: u32, _hit: PrimHit) -> ControlFlow<()> {
//!         self.hits += 1;
//!         if self.hits == 3 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
//!     }
//! }
//!
//! // Five parallel triangles along the z axis.
//! let tris: Vec<Triangle> = (0..5)
//!     .map(|z| z as f32)
//!     .map(|z| Triangle::new(Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(0.0, 1.0, z)))
//!     .collect();
//! let accel = BruteForce::build(&tris, &());
//! let ray = Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z);
//! let mut query = AtMostThree { t_far: ray.t_max, hits: 0 };
//! accel.ray_query(&ray, &mut query, &mut NoStats);
//! assert_eq!(query.hits, 3); // five hits wait at t = 1 ..= 5; the walk stopped at the third
//! ```
//!
//! # What a structure promises
//! For a valid ray ([`Ray::is_valid`](crate::Ray::is_valid)) and a query whose `t_far` starts
//! at or below `ray.t_max`, [`Accel::ray_query`](crate::Accel::ray_query) offers every valid
//! primitive hit in `[ray.t_min, t_far]`, with `t_far` read as it stands when the primitive is
//! tested, and each such hit once ([`RayQuery::REPEATABLE`] relaxes that), until an offer
//! returns [`ControlFlow::Break`]. The hits are those of
//! [`Primitive::intersect`](crate::Primitive) with `t_max = t_far`, bit for bit. The order is
//! the structure's own: roughly front to back for the trees and grids, and not sorted by `t`.
//! An invalid ray is offered nothing.

use crate::{Hit, PrimHit};
use std::ops::ControlFlow;

/// What a ray traversal ([`Accel::ray_query`](crate::Accel::ray_query)) works for: the far end
/// of the part of the ray still wanted, and a decision on each hit found.
///
/// See the [module documentation](self) for the contract and an example.
pub trait RayQuery {
    /// True for a query that asks only whether anything is hit, and takes the first hit found:
    /// a structure then runs the cheaper yes-or-no test [`Primitive::occludes`], may visit boxes
    /// in any order, and ends the walk after the first offer, whose `t`, `u` and `v` are NaN.
    /// [`AnyHit`] sets it; a query that needs the hit's coordinates (a filter that reads them)
    /// leaves it `false`.
    ///
    /// [`Primitive::occludes`]: crate::Primitive::occludes
    const OCCLUSION: bool = false;

    /// True for a query to which a second offer of the same hit changes nothing, as for a
    /// closest or any hit. Structures that list a primitive in several cells (kd-trees, grids,
    /// octrees) then remember only the last few primitives tested and may offer one again;
    /// for other queries they remember every primitive the walk has tested, so that each hit is
    /// offered once.
    const REPEATABLE: bool = false;

    /// True for a query to which a hit on a bit-identical copy of a primitive changes nothing
    /// once the primitive's own hit was offered (the copy has a larger index and the same `t`,
    /// `u`, `v`), as for a closest hit (ties go to the smaller index) or an any hit. A
    /// structure that stores such copies once (rt-bvh does) then offers the stored one alone.
    const COPIES_CHANGE_NOTHING: bool = false;

    /// The far end of the part of the ray still wanted: hits beyond it are not offered, and
    /// boxes or cells that start beyond it are skipped. It starts at or below the ray's
    /// `t_max` and must never grow during a walk.
    fn t_far(&self) -> f32;

    /// A hit on primitive `prim` (its index in the build input) with `t` in
    /// `[ray.t_min, t_far()]`; `Break` ends the walk.
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()>;
}

/// A query behind a mutable reference is a query, so wrappers can hold a borrowed one.
impl<Q: RayQuery + ?Sized> RayQuery for &mut Q {
    const OCCLUSION: bool = Q::OCCLUSION;
    const REPEATABLE: bool = Q::REPEATABLE;
    const COPIES_CHANGE_NOTHING: bool = Q::COPIES_CHANGE_NOTHING;
    #[inline(always)]
    fn t_far(&self) -> f32 {
        (**self).t_far()
    }
    #[inline(always)]
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        (**self).offer(prim, hit)
    }
}

/// The closest hit: the query behind [`Accel::intersect`](crate::Accel::intersect). It keeps
/// the hit that [`Hit::beats`] the others and shrinks `t_far` to it, so the walk skips
/// everything behind.
#[derive(Clone, Copy, Debug)]
pub struct ClosestHit {
    best: Hit,
}

impl ClosestHit {
    /// No hit yet, searching the ray's whole interval.
    #[inline(always)]
    pub fn new(ray: &crate::Ray) -> Self {
        Self {
            best: Hit {
                prim: u32::MAX,
                t: ray.t_max,
                u: 0.0,
                v: 0.0,
            },
        }
    }

    /// The closest hit offered, if any.
    #[inline(always)]
    pub fn hit(&self) -> Option<Hit> {
        (self.best.prim != u32::MAX).then_some(self.best)
    }

    /// Goes on from `record`, the best hit so far as [`record`](ClosestHit::record) gives it
    /// (for a walk that resumes another's work, such as a bundle's lane continuing alone).
    #[inline(always)]
    pub fn resume(record: Hit) -> Self {
        Self { best: record }
    }

    /// The best hit so far as a plain record: `prim` is `u32::MAX` while nothing is hit, and
    /// `t` is then the end of the interval.
    #[inline(always)]
    pub fn record(&self) -> Hit {
        self.best
    }
}

impl RayQuery for ClosestHit {
    const REPEATABLE: bool = true;
    const COPIES_CHANGE_NOTHING: bool = true;
    #[inline(always)]
    fn t_far(&self) -> f32 {
        self.best.t
    }
    #[inline(always)]
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        if Hit::beats(hit.t, prim, self.best.t, self.best.prim) {
            self.best = Hit {
                prim,
                t: hit.t,
                u: hit.u,
                v: hit.v,
            };
        }
        ControlFlow::Continue(())
    }
}

/// Whether anything is hit: the query behind [`Accel::occluded`](crate::Accel::occluded). It
/// is an occlusion query ([`RayQuery::OCCLUSION`]): the walk ends at the first hit found.
#[derive(Clone, Copy, Debug)]
pub struct AnyHit {
    t_max: f32,
    blocker: Option<u32>,
}

impl AnyHit {
    /// Nothing found yet, searching the ray's whole interval.
    #[inline(always)]
    pub fn new(ray: &crate::Ray) -> Self {
        Self {
            t_max: ray.t_max,
            blocker: None,
        }
    }

    /// Whether a hit was found.
    #[inline(always)]
    pub fn occluded(&self) -> bool {
        self.blocker.is_some()
    }

    /// The primitive found to block the ray: the first the walk met, which need not be the
    /// closest.
    #[inline(always)]
    pub fn blocker(&self) -> Option<u32> {
        self.blocker
    }
}

impl RayQuery for AnyHit {
    const OCCLUSION: bool = true;
    const REPEATABLE: bool = true;
    const COPIES_CHANGE_NOTHING: bool = true;
    #[inline(always)]
    fn t_far(&self) -> f32 {
        self.t_max
    }
    #[inline(always)]
    fn offer(&mut self, prim: u32, _: PrimHit) -> ControlFlow<()> {
        self.blocker = Some(prim);
        ControlFlow::Break(())
    }
}

/// A query that sees only the hits a filter accepts: the filter gets the primitive and the hit
/// (`t`, `u`, `v`) and answers whether the hit counts. What
/// [`Accel::intersect_filtered`](crate::Accel::intersect_filtered) and
/// [`Accel::occluded_filtered`](crate::Accel::occluded_filtered) run.
///
/// The filter must answer the same for the same primitive and hit: a structure may offer a hit
/// twice to a [repeatable](RayQuery::REPEATABLE) query, and the order of the offers is the
/// structure's own. Since the filter reads the hit's coordinates, a filtered any-hit query is
/// not an [occlusion](RayQuery::OCCLUSION) query: it runs the full primitive test, front to
/// back as a closest hit does, and stops at the first hit the filter accepts.
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
/// // Two triangles, one behind the other; the filter rejects primitive 0.
/// let tri = |z| Triangle::new(Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(0.0, 1.0, z));
/// let accel = BruteForce::build(&[tri(1.0), tri(2.0)], &());
/// let ray = Ray::new(Vec3::ZERO, Vec3::Z);
/// assert_eq!(accel.intersect(&ray).unwrap().prim, 0);
/// assert_eq!(accel.intersect_filtered(&ray, |prim, _| prim != 0).unwrap().prim, 1);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Filtered<Q, F> {
    /// The query that receives the accepted hits.
    pub inner: Q,
    filter: F,
}

impl<Q: RayQuery, F: FnMut(u32, &PrimHit) -> bool> Filtered<Q, F> {
    /// `inner`, offered only the hits `filter` accepts.
    #[inline(always)]
    pub fn new(inner: Q, filter: F) -> Self {
        Self { inner, filter }
    }
}

impl<Q: RayQuery, F: FnMut(u32, &PrimHit) -> bool> RayQuery for Filtered<Q, F> {
    const REPEATABLE: bool = Q::REPEATABLE;
    #[inline(always)]
    fn t_far(&self) -> f32 {
        self.inner.t_far()
    }
    #[inline(always)]
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        if (self.filter)(prim, &hit) {
            self.inner.offer(prim, hit)
        } else {
            ControlFlow::Continue(())
        }
    }
}

/// Every hit in the ray's interval: the query behind [`Accel::all_hits`](crate::Accel::all_hits)
/// and [`Accel::count_hits`](crate::Accel::count_hits). Each primitive the ray meets is listed
/// once, with its hit as [`Primitive::intersect`](crate::Primitive) reports it; a ray through an
/// edge or vertex that several triangles share lists each triangle whose test reports the hit
/// (the watertight test reports all of them, so none is missed).
#[derive(Clone, Debug)]
pub struct AllHits {
    t_max: f32,
    hits: Vec<Hit>,
}

impl AllHits {
    /// No hit yet, searching the ray's whole interval.
    pub fn new(ray: &crate::Ray) -> Self {
        Self {
            t_max: ray.t_max,
            hits: Vec::new(),
        }
    }

    /// The hits, in the order the walk found them.
    pub fn hits(&self) -> &[Hit] {
        &self.hits
    }

    /// The hits sorted by `t`, ties by primitive index.
    pub fn into_sorted(mut self) -> Vec<Hit> {
        // `+ 0.0` turns -0 into +0, which `Hit::beats` counts as equal.
        self.hits.sort_unstable_by(|a, b| {
            (a.t + 0.0)
                .total_cmp(&(b.t + 0.0))
                .then(a.prim.cmp(&b.prim))
        });
        self.hits
    }
}

impl RayQuery for AllHits {
    #[inline]
    fn t_far(&self) -> f32 {
        self.t_max
    }
    #[inline]
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        self.hits.push(Hit {
            prim,
            t: hit.t,
            u: hit.u,
            v: hit.v,
        });
        ControlFlow::Continue(())
    }
}

/// The number of hits in the ray's interval, each primitive once: what
/// [`Accel::count_hits`](crate::Accel::count_hits) runs, without keeping the hits.
#[derive(Clone, Copy, Debug)]
pub struct CountHits {
    t_max: f32,
    /// The hits counted so far.
    pub count: usize,
}

impl CountHits {
    /// Nothing counted yet, over the ray's whole interval.
    pub fn new(ray: &crate::Ray) -> Self {
        Self {
            t_max: ray.t_max,
            count: 0,
        }
    }
}

impl RayQuery for CountHits {
    #[inline]
    fn t_far(&self) -> f32 {
        self.t_max
    }
    #[inline]
    fn offer(&mut self, _: u32, _: PrimHit) -> ControlFlow<()> {
        self.count += 1;
        ControlFlow::Continue(())
    }
}

/// A query offered each primitive's hit once, for a walk that may meet a primitive again (one
/// listed in several cells) and remembers only the last few it tested: it passes the first
/// offer of each primitive to the inner query and drops the others, so it is
/// [repeatable](RayQuery::REPEATABLE) whatever the inner query is. The labs' walks run
/// all hits, counts and filters through it; the structures remember every primitive with
/// [`Visited`](crate::Visited) instead ([`leaf::walk_once`](crate::leaf::walk_once)).
///
/// ```
/// use rt_core::query::{AllHits, Deduplicated, RayQuery};
/// use rt_core::{PrimHit, Ray, glam::Vec3};
/// let ray = Ray::new(Vec3::ZERO, Vec3::Z);
/// let mut all = AllHits::new(&ray);
/// let mut once = Deduplicated::new(&mut all);
/// let hit = PrimHit { t: 1.0, u: 0.25, v: 0.25 };
/// for prim in [4, 7, 4] {
///     let _ = once.offer(prim, hit); // primitive 4 met again in a second cell
/// }
/// assert_eq!(all.hits().len(), 2);
/// ```
#[derive(Debug)]
pub struct Deduplicated<Q> {
    inner: Q,
    offered: Vec<u32>,
}

impl<Q: RayQuery> Deduplicated<Q> {
    /// `inner`, offered each primitive once.
    pub fn new(inner: Q) -> Self {
        Self {
            inner,
            offered: Vec::new(),
        }
    }
}

impl<Q: RayQuery> RayQuery for Deduplicated<Q> {
    const OCCLUSION: bool = Q::OCCLUSION;
    const REPEATABLE: bool = true;
    #[inline]
    fn t_far(&self) -> f32 {
        self.inner.t_far()
    }
    #[inline]
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        // A ray hits few primitives: a scan of those offered is enough.
        if self.offered.contains(&prim) {
            return ControlFlow::Continue(());
        }
        self.offered.push(prim);
        self.inner.offer(prim, hit)
    }
}

/// The hit an [occlusion](RayQuery::OCCLUSION) walk offers: it ran the yes-or-no test, so
/// nothing is known but that the primitive blocks the ray.
pub const BLOCKS: PrimHit = PrimHit {
    t: f32::NAN,
    u: f32::NAN,
    v: f32::NAN,
};

/// A ray query run as the box query of the box around the part of the ray inside `bounds`: the
/// default [`Accel::ray_query`](crate::Accel::ray_query), for structures that implement only
/// the box (or ball) traversal. Every primitive the ray hits there meets that box, widened for
/// rounding, so the box query offers it; each primitive offered is tested against the ray.
/// After a `Break` nothing more is tested.
pub(crate) struct RayOfBox<'a, Q> {
    query: &'a mut Q,
    ray: &'a crate::Ray,
    bounds: crate::Aabb,
    done: bool,
    /// The primitives whose hits were offered, for a query that wants each once (a box query
    /// may offer a primitive again).
    offered: Vec<u32>,
}

impl<'a, Q: RayQuery> RayOfBox<'a, Q> {
    /// The box around `ray` from `t_min` to `query.t_far()` cut to `scene`, or `None` if the
    /// ray misses `scene` or is invalid.
    pub(crate) fn new(ray: &'a crate::Ray, query: &'a mut Q, scene: &crate::Aabb) -> Option<Self> {
        if !ray.is_valid() {
            return None;
        }
        let (t0, t1) = scene.intersect(ray, query.t_far())?;
        let (a, b) = (ray.at(t0), ray.at(t1));
        // The hit points lie on the segment up to rounding in the primitive tests and in
        // `at`, whose error follows the origin's and the step's size, not the point's (an
        // origin at 10¹² reaching a scene at 1): widen by a relative 2⁻¹⁶ of the largest of
        // them, far above either.
        let step = ray.dir().abs().max_element() * t0.abs().max(t1.abs());
        let size = a
            .abs()
            .max(b.abs())
            .max_element()
            .max(ray.origin.abs().max_element() + step);
        let pad = glam::Vec3::splat(size * (1.0 / 65536.0) + f32::MIN_POSITIVE);
        let bounds = crate::Aabb::new(a.min(b) - pad, a.max(b) + pad);
        Some(Self {
            query,
            ray,
            bounds,
            done: false,
            offered: Vec::new(),
        })
    }

    #[inline]
    fn keep<T: FnOnce(f32) -> Option<PrimHit>, B: FnOnce(f32) -> bool>(
        &mut self,
        id: u32,
        intersect: T,
        occludes: B,
    ) -> ControlFlow<()> {
        if self.done {
            return ControlFlow::Break(());
        }
        let t_far = self.query.t_far();
        if !Q::REPEATABLE {
            // Only hits are recorded, and a ray has few: a scan is enough for this fallback.
            if self.offered.contains(&id) {
                return ControlFlow::Continue(());
            }
        }
        let flow = if Q::OCCLUSION {
            if occludes(t_far) {
                let _ = self.query.offer(id, BLOCKS);
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        } else if let Some(hit) = intersect(t_far) {
            if !Q::REPEATABLE {
                self.offered.push(id);
            }
            self.query.offer(id, hit)
        } else {
            ControlFlow::Continue(())
        };
        self.done = flow.is_break();
        flow
    }
}

impl<P: crate::Primitive, Q: RayQuery> crate::BoxQuery<P> for RayOfBox<'_, Q> {
    fn bounds(&self) -> crate::Aabb {
        self.bounds
    }
    fn test(&mut self, prim: &P, id: u32) -> ControlFlow<()> {
        let ray = self.ray;
        self.keep(id, |t| prim.intersect(ray, t), |t| prim.occludes(ray, t))
    }
    /// A triangle kept in a structure's own layout is tested watertight, the default test: a
    /// structure that keeps triangles of another test this way must implement its own
    /// [`Accel::ray_query`](crate::Accel::ray_query).
    fn test_triangle(&mut self, v: [glam::Vec3; 3], id: u32) -> ControlFlow<()> {
        let (ray, tri) = (self.ray, crate::Triangle::new(v[0], v[1], v[2]));
        self.keep(
            id,
            |t| tri.intersect_watertight(ray, t),
            |t| tri.intersect_watertight(ray, t).is_some(),
        )
    }
}

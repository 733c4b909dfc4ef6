//! Any structure as a trait object: [`DynAccel`].

use crate::query::{AllHits, AnyHit, ClosestHit, Filtered, RayOfBox, RayQuery};
use crate::trace::Trace;
use crate::{
    Aabb, Accel, BallQuery, BoxQuery, BuildStats, Counters, Hit, NoStats, PointHit, PrimHit,
    Primitive, Ray, Region,
};
use glam::Vec3;
use std::ops::ControlFlow;

/// Any [`Accel`] as a trait object: a structure chosen at run time, bottom levels of several
/// kinds in one two-level scene (rt-instance's `Instance`), a row of the shootout, the
/// structure a renderer traces. Every `Accel` is one.
///
/// Every method ends in `_dyn` or `_all`, so that calling a structure's own [`Accel`] methods
/// is never ambiguous where both traits are in scope. The single queries take `Some(counters)`
/// to count their events and `None` to run the uncounted traversal. The `_all` methods answer a whole slice of queries in one call: their
/// loop is compiled for the structure, so a caller crossing the trait object once per slice pays
/// no dynamic dispatch per ray.
///
/// ```
/// use rt_core::{Accel, BruteForce, DynAccel, Ray, Triangle, glam::Vec3};
///
/// let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y)];
/// let chosen: Box<dyn DynAccel<Triangle>> = Box::new(BruteForce::build(&tris, &()));
/// let rays = [Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z), Ray::new(Vec3::X * 5.0, Vec3::Z)];
/// let mut hits = [None; 2];
/// chosen.intersect_all(&rays, &mut hits, None);
/// assert_eq!(hits.map(|h| h.map(|h| h.prim)), [Some(0), None]);
/// ```
pub trait DynAccel<P>: Send + Sync {
    /// [`Accel::NAME`].
    fn name(&self) -> &'static str;
    /// [`Accel::bounds`].
    fn bounds_dyn(&self) -> Aabb;
    /// [`Accel::memory_bytes`].
    fn memory_bytes_dyn(&self) -> usize;
    /// [`Accel::build_stats`].
    fn build_stats_dyn(&self) -> BuildStats;
    /// [`Accel::regions`], collected.
    fn regions_dyn(&self) -> Vec<Region>;
    /// [`Accel::intersect`], counted into `counters` if given.
    fn intersect_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> Option<Hit>;
    /// [`Accel::occluded`], counted into `counters` if given.
    fn occluded_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> bool;
    /// [`Accel::ball_query`], counted into `counters` if given.
    fn ball_query_dyn(&self, query: &mut dyn BallQuery<P>, counters: Option<&mut Counters>);
    /// [`Accel::box_query`], counted into `counters` if given. The default, for wrappers that
    /// implement only [`ball_query_dyn`](DynAccel::ball_query_dyn), runs the ball query of the
    /// ball around the box, as [`Accel::box_query`]'s default does.
    fn box_query_dyn(&self, mut query: &mut dyn BoxQuery<P>, counters: Option<&mut Counters>) {
        if let Some(mut ball) = crate::overlap::BallOfBox::new(&mut query) {
            self.ball_query_dyn(&mut ball, counters);
        }
    }
    /// [`Accel::all_hits`], counted into `counters` if given. The default, for wrappers that
    /// implement only the box (or ball) query, runs [`Accel::ray_query`]'s default through
    /// [`box_query_dyn`](DynAccel::box_query_dyn).
    fn all_hits_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> Vec<Hit>
    where
        P: Primitive,
    {
        let mut query = AllHits::new(ray);
        by_boxes(self, ray, &mut query, counters);
        query.into_sorted()
    }
    /// [`Accel::intersect_filtered`], counted into `counters` if given; the default as for
    /// [`all_hits_dyn`](DynAccel::all_hits_dyn).
    fn intersect_filtered_dyn(
        &self,
        ray: &Ray,
        filter: &mut dyn FnMut(u32, &PrimHit) -> bool,
        counters: Option<&mut Counters>,
    ) -> Option<Hit>
    where
        P: Primitive,
    {
        let mut query = Filtered::new(ClosestHit::new(ray), filter);
        by_boxes(self, ray, &mut query, counters);
        query.inner.hit()
    }
    /// [`Accel::occluded_filtered`], counted into `counters` if given; the default as for
    /// [`all_hits_dyn`](DynAccel::all_hits_dyn).
    fn occluded_filtered_dyn(
        &self,
        ray: &Ray,
        filter: &mut dyn FnMut(u32, &PrimHit) -> bool,
        counters: Option<&mut Counters>,
    ) -> bool
    where
        P: Primitive,
    {
        let mut query = Filtered::new(AnyHit::new(ray), filter);
        by_boxes(self, ray, &mut query, counters);
        query.inner.occluded()
    }
    /// [`Accel::ray_query`] for a query behind a trait object ([`DynRayQuery`]), counted into
    /// `counters` if given: the structure's one ray walk, for any query. The default, for
    /// wrappers that implement only the box (or ball) query, runs [`Accel::ray_query`]'s
    /// default through [`box_query_dyn`](DynAccel::box_query_dyn).
    fn ray_query_dyn(&self, ray: &Ray, query: &mut dyn DynRayQuery, counters: Option<&mut Counters>)
    where
        P: Primitive,
    {
        with_flags(
            query,
            ByBoxes {
                s: self,
                ray,
                counters,
                prim: std::marker::PhantomData,
            },
        );
    }
    /// One closest-hit (`any == false`) or any-hit query with every step of its walk recorded
    /// ([`Trace`]); an any-hit answer is `Some` with primitive `u32::MAX` when occluded.
    fn trace_dyn(&self, ray: &Ray, any: bool) -> (Option<Hit>, Trace);
    /// [`Accel::intersect`] for each ray into the same slot of `out` (as many as both have),
    /// counted into `counters` if given.
    fn intersect_all(&self, rays: &[Ray], out: &mut [Option<Hit>], counters: Option<&mut Counters>);
    /// [`Accel::occluded`] for each ray into the same slot of `out` (as many as both have),
    /// counted into `counters` if given.
    fn occluded_all(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>);
    /// [`Accel::intersect_bundle`]: the rays traced as the structure's bundles, counted into
    /// `counters` if given (as the [`bundle`](crate::bundle) module describes). The default,
    /// for wrappers that trace no bundles, is [`intersect_all`](DynAccel::intersect_all), each
    /// ray counted as traced singly.
    fn intersect_bundle_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        mut counters: Option<&mut Counters>,
    ) {
        if let Some(c) = counters.as_deref_mut() {
            c.single_rays += rays.len().min(out.len()) as u64;
        }
        self.intersect_all(rays, out, counters);
    }
    /// [`Accel::occluded_bundle`], counted into `counters` if given. The default is
    /// [`occluded_all`](DynAccel::occluded_all), each ray counted as traced singly.
    fn occluded_bundle_dyn(
        &self,
        rays: &[Ray],
        out: &mut [bool],
        mut counters: Option<&mut Counters>,
    ) {
        if let Some(c) = counters.as_deref_mut() {
            c.single_rays += rays.len().min(out.len()) as u64;
        }
        self.occluded_all(rays, out, counters);
    }
    /// [`Accel::intersect_stream`]: the rays traced as the structure's streams, counted into
    /// `counters` if given. The default, for wrappers that trace no streams, is
    /// [`intersect_all`](DynAccel::intersect_all).
    fn intersect_stream_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        self.intersect_all(rays, out, counters);
    }
    /// [`Accel::occluded_stream`], counted into `counters` if given. The default is
    /// [`occluded_all`](DynAccel::occluded_all).
    fn occluded_stream_dyn(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        self.occluded_all(rays, out, counters);
    }
    /// [`Accel::closest_point`] for each `(point, max_distance)` into the same slot of `out` (as
    /// many as both have), counted into `counters` if given.
    fn closest_points_all(
        &self,
        points: &[(Vec3, f32)],
        out: &mut [Option<PointHit>],
        counters: Option<&mut Counters>,
    );
}

/// A ray query through a structure's box query: [`Accel::ray_query`]'s default, for a
/// structure known only as a trait object.
fn by_boxes<P: Primitive, D: DynAccel<P> + ?Sized, Q: RayQuery>(
    s: &D,
    ray: &Ray,
    query: &mut Q,
    counters: Option<&mut Counters>,
) {
    if let Some(mut q) = RayOfBox::new(ray, query, &s.bounds_dyn()) {
        s.box_query_dyn(&mut q, counters);
    }
}

/// A [`RayQuery`] behind a trait object: its constants as methods, so that a structure seen as a
/// [`DynAccel`] runs any query ([`DynAccel::ray_query_dyn`]). Every `RayQuery` is one.
pub trait DynRayQuery {
    /// [`RayQuery::OCCLUSION`].
    fn occlusion(&self) -> bool;
    /// [`RayQuery::REPEATABLE`].
    fn repeatable(&self) -> bool;
    /// [`RayQuery::t_far`].
    fn t_far(&self) -> f32;
    /// [`RayQuery::offer`].
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()>;
}

impl<Q: RayQuery> DynRayQuery for Q {
    fn occlusion(&self) -> bool {
        Q::OCCLUSION
    }
    fn repeatable(&self) -> bool {
        Q::REPEATABLE
    }
    fn t_far(&self) -> f32 {
        RayQuery::t_far(self)
    }
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        RayQuery::offer(self, prim, hit)
    }
}

/// A [`DynRayQuery`] as a [`RayQuery`] with its constants `O` ([`RayQuery::OCCLUSION`]) and `R`
/// ([`RayQuery::REPEATABLE`]).
struct Flagged<'a, const O: bool, const R: bool>(&'a mut dyn DynRayQuery);

impl<const O: bool, const R: bool> RayQuery for Flagged<'_, O, R> {
    const OCCLUSION: bool = O;
    const REPEATABLE: bool = R;
    #[inline]
    fn t_far(&self) -> f32 {
        self.0.t_far()
    }
    #[inline]
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        self.0.offer(prim, hit)
    }
}

/// A walk to run with a query of a type known at compile time.
trait QueryWalk {
    fn run<Q: RayQuery>(self, query: &mut Q);
}

/// Runs `walk` with `query` as a [`RayQuery`] whose constants are the query's flags: one of four
/// instances of the walk, chosen at run time.
fn with_flags(query: &mut dyn DynRayQuery, walk: impl QueryWalk) {
    match (query.occlusion(), query.repeatable()) {
        (false, false) => walk.run(&mut Flagged::<false, false>(query)),
        (false, true) => walk.run(&mut Flagged::<false, true>(query)),
        (true, false) => walk.run(&mut Flagged::<true, false>(query)),
        (true, true) => walk.run(&mut Flagged::<true, true>(query)),
    }
}

/// [`DynAccel::ray_query_dyn`]'s default: the ray query through the box query.
struct ByBoxes<'a, P, D: ?Sized> {
    s: &'a D,
    ray: &'a Ray,
    counters: Option<&'a mut Counters>,
    prim: std::marker::PhantomData<P>,
}

impl<P: Primitive, D: DynAccel<P> + ?Sized> QueryWalk for ByBoxes<'_, P, D> {
    fn run<Q: RayQuery>(self, query: &mut Q) {
        by_boxes(self.s, self.ray, query, self.counters);
    }
}

/// A structure's own ray walk, counted into `counters` if given.
struct Walk<'a, A> {
    a: &'a A,
    ray: &'a Ray,
    counters: Option<&'a mut Counters>,
}

impl<A: Accel> QueryWalk for Walk<'_, A> {
    fn run<Q: RayQuery>(self, query: &mut Q) {
        ray_query_counted(self.a, self.ray, query, self.counters);
    }
}

/// [`Accel::ray_query`] counted into `counters` if given.
fn ray_query_counted<A: Accel, Q: RayQuery>(
    a: &A,
    ray: &Ray,
    query: &mut Q,
    counters: Option<&mut Counters>,
) {
    match counters {
        Some(c) => a.ray_query(ray, query, c),
        None => a.ray_query(ray, query, &mut NoStats),
    }
}

impl<A: Accel> DynAccel<A::Prim> for A {
    fn name(&self) -> &'static str {
        A::NAME
    }

    fn bounds_dyn(&self) -> Aabb {
        Accel::bounds(self)
    }

    fn memory_bytes_dyn(&self) -> usize {
        Accel::memory_bytes(self)
    }

    fn build_stats_dyn(&self) -> BuildStats {
        Accel::build_stats(self)
    }

    fn regions_dyn(&self) -> Vec<Region> {
        let mut out = Vec::new();
        Accel::regions(self, &mut |r| out.push(r));
        out
    }

    #[inline]
    fn intersect_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> Option<Hit> {
        match counters {
            Some(c) => self.intersect_with(ray, c),
            None => self.intersect_with(ray, &mut NoStats),
        }
    }

    #[inline]
    fn occluded_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> bool {
        match counters {
            Some(c) => self.occluded_with(ray, c),
            None => self.occluded_with(ray, &mut NoStats),
        }
    }

    fn ball_query_dyn(
        &self,
        mut query: &mut dyn BallQuery<A::Prim>,
        counters: Option<&mut Counters>,
    ) {
        match counters {
            Some(c) => self.ball_query(&mut query, c),
            None => self.ball_query(&mut query, &mut NoStats),
        }
    }

    fn box_query_dyn(
        &self,
        mut query: &mut dyn BoxQuery<A::Prim>,
        counters: Option<&mut Counters>,
    ) {
        match counters {
            Some(c) => self.box_query(&mut query, c),
            None => self.box_query(&mut query, &mut NoStats),
        }
    }

    fn all_hits_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> Vec<Hit> {
        let mut query = AllHits::new(ray);
        ray_query_counted(self, ray, &mut query, counters);
        query.into_sorted()
    }

    fn intersect_filtered_dyn(
        &self,
        ray: &Ray,
        filter: &mut dyn FnMut(u32, &PrimHit) -> bool,
        counters: Option<&mut Counters>,
    ) -> Option<Hit> {
        let mut query = Filtered::new(ClosestHit::new(ray), filter);
        ray_query_counted(self, ray, &mut query, counters);
        query.inner.hit()
    }

    fn occluded_filtered_dyn(
        &self,
        ray: &Ray,
        filter: &mut dyn FnMut(u32, &PrimHit) -> bool,
        counters: Option<&mut Counters>,
    ) -> bool {
        let mut query = Filtered::new(AnyHit::new(ray), filter);
        ray_query_counted(self, ray, &mut query, counters);
        query.inner.occluded()
    }

    fn ray_query_dyn(
        &self,
        ray: &Ray,
        query: &mut dyn DynRayQuery,
        counters: Option<&mut Counters>,
    ) {
        with_flags(
            query,
            Walk {
                a: self,
                ray,
                counters,
            },
        );
    }

    fn trace_dyn(&self, ray: &Ray, any: bool) -> (Option<Hit>, Trace) {
        let mut trace = Trace::default();
        let answer = if any {
            self.occluded_with(ray, &mut trace).then_some(Hit {
                prim: u32::MAX,
                t: f32::NAN,
                u: 0.0,
                v: 0.0,
            })
        } else {
            self.intersect_with(ray, &mut trace)
        };
        (answer, trace)
    }

    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        let pairs = out.iter_mut().zip(rays);
        match counters {
            Some(c) => pairs.for_each(|(o, r)| *o = self.intersect_with(r, c)),
            None => pairs.for_each(|(o, r)| *o = self.intersect_with(r, &mut NoStats)),
        }
    }

    fn occluded_all(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        let pairs = out.iter_mut().zip(rays);
        match counters {
            Some(c) => pairs.for_each(|(o, r)| *o = self.occluded_with(r, c)),
            None => pairs.for_each(|(o, r)| *o = self.occluded_with(r, &mut NoStats)),
        }
    }

    fn intersect_bundle_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        match counters {
            Some(c) => self.intersect_bundle_with(rays, out, c),
            None => self.intersect_bundle_with(rays, out, &mut NoStats),
        }
    }

    fn occluded_bundle_dyn(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        match counters {
            Some(c) => self.occluded_bundle_with(rays, out, c),
            None => self.occluded_bundle_with(rays, out, &mut NoStats),
        }
    }

    fn intersect_stream_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        match counters {
            Some(c) => self.intersect_stream_with(rays, out, c),
            None => self.intersect_stream_with(rays, out, &mut NoStats),
        }
    }

    fn occluded_stream_dyn(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        match counters {
            Some(c) => self.occluded_stream_with(rays, out, c),
            None => self.occluded_stream_with(rays, out, &mut NoStats),
        }
    }

    fn closest_points_all(
        &self,
        points: &[(Vec3, f32)],
        out: &mut [Option<PointHit>],
        counters: Option<&mut Counters>,
    ) {
        let pairs = out.iter_mut().zip(points);
        match counters {
            Some(c) => pairs.for_each(|(o, &(p, max))| *o = self.closest_point_with(p, max, c)),
            None => pairs.for_each(|(o, &(p, max))| *o = self.closest_point(p, max)),
        }
    }
}

/// Compiles [`DynAccel`] of a structure type over [`Triangle`](crate::Triangle)s and
/// [`Shape`](crate::Shape)s into the crate that invokes it, in debug and test builds: each
/// structure crate invokes it once, for its own type, behind its `share-dyn` feature, which the
/// crates that make those trait objects turn on (a crate that never makes one compiles none).
///
/// Why: a trait object's methods are compiled in the crate that makes the object, for every type
/// it is made of, and the shootout, the renderer and the tests of every structure each make the
/// same ones. Where rustc shares generic code between crates (opt-level 0 and 1: debug and test
/// builds), a crate links an upstream crate's copy instead of compiling its own, so with one copy
/// in the structure's crate the others compile none. Optimised builds do not share generic code,
/// so there a copy here would only add build time: the function exists only with debug
/// assertions on, which is how a crate's source can tell a debug or test build.
// PERF: `cargo test --workspace --no-run`, the workspace's own crates only (dependencies built),
// AMD Zen 4, two cores, before -> after: 498 s -> 338 s, 986 -> 654 seconds of compiling;
// rt-shootout 275 -> 75 s, rt-bvh's tests 182 -> 60 s, rt-render's 126 -> 6 s. The copy costs
// rt-bvh's own debug build (opt-level 0) 1.0 -> 6.3 s, hence the feature.
#[macro_export]
#[doc(hidden)]
macro_rules! share_dyn_accel {
    ($ty:ident) => {
        /// Makes this crate compile its structure's `DynAccel`, so that crates using it share
        /// that copy (see `rt_core::share_dyn_accel!`).
        #[cfg(debug_assertions)]
        #[doc(hidden)]
        // Never inlined: rustc would compile so small a function only where it is called.
        #[inline(never)]
        pub fn __shared_dyn_accel<'a>(
            triangles: &'a $ty<$crate::Triangle>,
            shapes: &'a $ty<$crate::Shape>,
        ) -> (
            &'a dyn $crate::DynAccel<$crate::Triangle>,
            &'a dyn $crate::DynAccel<$crate::Shape>,
        ) {
            (triangles, shapes)
        }
    };
}

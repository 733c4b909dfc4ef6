//! The trait every acceleration structure implements.

use crate::{
    Aabb, AllHits, AnyHit, BallQuery, BoxQuery, ClosestHit, ClosestPointQuery, CountHits, Filtered,
    Geometry, Hit, NoStats, OverlapQuery, PointHit, PrimHit, Primitive, Ray, RayQuery, Stats,
};
use glam::Vec3;
use std::fmt::Debug;

/// Shape of a built structure, reported by [`Accel::build_stats`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildStats {
    /// Nodes (or cells) in the structure, leaves included.
    pub nodes: usize,
    /// Leaves (or non-empty cells).
    pub leaves: usize,
    /// Leaves holding no primitive.
    pub empty_leaves: usize,
    /// Depth of the deepest leaf; the root has depth 0.
    pub max_depth: usize,
    /// Primitive references held by all leaves (more than `valid_prims` when a structure stores a
    /// primitive in several leaves).
    pub prim_refs: usize,
    /// Primitives the structure kept (the valid ones; see [`Primitive::is_valid`]).
    pub valid_prims: usize,
    /// Structure-specific figures, named, for reports.
    pub extra: Vec<(&'static str, f64)>,
}

impl BuildStats {
    /// Average primitive references per non-empty leaf.
    pub fn avg_prims_per_leaf(&self) -> f64 {
        let full = self.leaves - self.empty_leaves;
        if full == 0 {
            0.0
        } else {
            self.prim_refs as f64 / full as f64
        }
    }

    /// References per kept primitive (1 for structures that never duplicate).
    pub fn duplication(&self) -> f64 {
        if self.valid_prims == 0 {
            0.0
        } else {
            self.prim_refs as f64 / self.valid_prims as f64
        }
    }
}

/// One node or cell of a built structure, as [`Accel::regions`] describes it: for drawings of
/// the structure (`cargo xtask draw`) and for teaching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// The part of space the node or cell covers (for a BVH, the box around its primitives).
    pub bounds: crate::Aabb,
    /// Its depth: 0 for the root (and for every cell of a uniform grid).
    pub depth: u32,
    /// How many primitive references a leaf or cell lists; `None` for an interior node or a
    /// cell refined by a nested grid.
    pub prims: Option<u32>,
    /// For an interior node that cuts its box with a plane (a kd-tree's split): the axis and
    /// the plane's coordinate.
    pub split: Option<(usize, f32)>,
}

/// A ray-tracing acceleration structure over primitives of type [`Accel::Prim`].
///
/// # What a structure implements
/// Six methods are required: [`presets`](Accel::presets), [`build`](Accel::build),
/// [`bounds`](Accel::bounds), [`ball_query`](Accel::ball_query),
/// [`memory_bytes`](Accel::memory_bytes) and [`build_stats`](Accel::build_stats). With them every
/// query answers, through the ball walk. A structure overrides one walk per kind of query to
/// make it fast, and every query of that kind comes from that walk:
/// - [`ray_query`](Accel::ray_query), the ray walk: closest hit, any hit, filters, all hits and
///   counts are its queries ([`RayQuery`]);
/// - [`box_query`](Accel::box_query), the box walk behind box overlap;
/// - [`intersect_bundle_with`](Accel::intersect_bundle_with) and
///   [`occluded_bundle_with`](Accel::occluded_bundle_with), the packet walks of many rays;
/// - and, to build straight from indexed buffers or to be drawn,
///   [`build_from`](Accel::build_from) and [`regions`](Accel::regions).
///
/// The other methods derive from those, and a structure leaves them as they are: the
/// conformance kit checks a structure's walks through them (an override would be checked in
/// place of the walk it hides), and users call them.
///
/// # Contract
/// Checked for every implementation by the conformance kit (the `rt-conformance` crate):
/// - [`intersect`](Accel::intersect) returns exactly what [`BruteForce`](crate::BruteForce)
///   returns: the hit with the smallest `t` in `[ray.t_min, ray.t_max]`, ties broken by the
///   smallest primitive index ([`Hit::beats`]);
/// - [`occluded`](Accel::occluded) is true exactly when `intersect` would return a hit, and may
///   stop at the first one it finds;
/// - [`ray_query`](Accel::ray_query) offers a [`RayQuery`] every hit in the ray's interval
///   that the [`query`](crate::query) module's contract names, which makes
///   [`intersect_filtered`](Accel::intersect_filtered), [`all_hits`](Accel::all_hits) and
///   [`count_hits`](Accel::count_hits) exactly brute force's;
/// - [`closest_point`](Accel::closest_point) returns exactly what `BruteForce` returns: the
///   primitive nearest to the point within the maximum distance, ties broken by the smallest
///   index ([`PointHit::beats`]), which follows from [`ball_query`](Accel::ball_query) offering
///   every primitive its contract names;
/// - invalid primitives ([`Primitive::is_valid`]) are never hit;
/// - building and tracing never panic and never loop, whatever the input.
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
/// let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
/// let accel = BruteForce::build(&tris, &Default::default());
/// let hit = accel.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z)).unwrap();
/// assert_eq!((hit.prim, hit.t), (0, 1.0));
/// ```
pub trait Accel: Sized + Send + Sync {
    /// The primitive type stored.
    type Prim: Primitive;
    /// Build parameters; `Default` is the recommended preset.
    type Params: Clone + Debug + Default + Send + Sync;

    /// Short name used for reports (`"bvh"`, `"kdtree"`, ...).
    const NAME: &'static str;

    /// Named parameter presets, the default first. `compare` names rows `NAME` for the first and
    /// `NAME-preset` for the others.
    fn presets() -> Vec<(&'static str, Self::Params)>;

    /// Builds the structure over `prims`; indices in hits refer to this slice.
    fn build(prims: &[Self::Prim], params: &Self::Params) -> Self;

    /// Builds the structure over the primitives of `geometry`: a slice, a
    /// [`Mesh`](crate::Mesh), or an [`IndexedTriangles`](crate::IndexedTriangles) view of
    /// buffers the caller has; indices in hits refer to its numbering.
    ///
    /// The default collects the primitives into a vector and calls [`build`](Accel::build).
    /// Every structure of this workspace overrides it to read them straight into the layout it
    /// keeps, so building from a mesh makes no triangle list in between.
    ///
    /// ```
    /// use rt_core::{Accel, BruteForce, Mesh, Ray, glam::Vec3};
    /// let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
    /// let accel = BruteForce::build_from(&mesh, &());
    /// assert_eq!(accel.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z)).unwrap().t, 1.0);
    /// ```
    fn build_from<G: Geometry<Prim = Self::Prim> + ?Sized>(
        geometry: &G,
        params: &Self::Params,
    ) -> Self {
        Self::build(&geometry.to_vec(), params)
    }

    /// Offers `query` every valid primitive the ray hits in `[ray.t_min, query.t_far()]`: the one
    /// ray traversal behind closest hits, any hits, filters, all hits and counts, reporting
    /// events to `stats`. The [`query`](crate::query) module states the contract (each hit once
    /// unless the query is [repeatable](RayQuery::REPEATABLE), until an offer returns `Break`)
    /// and shows a query of one's own.
    ///
    /// The default runs [`box_query`](Accel::box_query) with the box around the part of the ray
    /// inside [`bounds`](Accel::bounds) and tests each primitive offered against the ray: correct
    /// for any structure whose box (or ball) query is, but it offers everything near that box.
    /// Every structure of this workspace overrides it with its own walk. A structure whose box
    /// query offers pre-processed triangles of a test other than the watertight one must
    /// override it.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if let Some(mut q) = crate::query::RayOfBox::new(ray, query, &self.bounds()) {
            self.box_query(&mut q, stats);
        }
    }

    /// The closest hit, reporting traversal events to `stats`: [`ray_query`](Accel::ray_query)
    /// with [`ClosestHit`].
    #[inline]
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        let mut query = ClosestHit::new(ray);
        self.ray_query(ray, &mut query, stats);
        query.hit()
    }

    /// Whether anything is hit in the ray's interval, reporting events to `stats`:
    /// [`ray_query`](Accel::ray_query) with [`AnyHit`].
    #[inline]
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        let mut query = AnyHit::new(ray);
        self.ray_query(ray, &mut query, stats);
        query.occluded()
    }

    /// The closest hit.
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.intersect_with(ray, &mut NoStats)
    }

    /// Whether anything is hit in the ray's interval (for shadow rays).
    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_with(ray, &mut NoStats)
    }

    /// The closest hit among those `filter` accepts: it sees each candidate's primitive and
    /// hit (`t`, `u`, `v`) and answers whether it counts, so a hit it rejects lets the ray go on
    /// (see [`Filtered`]: the filter must answer the same when asked again). A filter that
    /// accepts everything compiles to the plain [`intersect`](Accel::intersect).
    ///
    /// ```
    /// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
    /// let tri = |z| Triangle::new(Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(0.0, 1.0, z));
    /// let accel = BruteForce::build(&[tri(1.0), tri(2.0)], &());
    /// // A secondary ray leaving primitive 0 must not hit it again.
    /// let ray = Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::Z);
    /// let hit = accel.intersect_filtered(&ray, |prim, _| prim != 0).unwrap();
    /// assert_eq!((hit.prim, hit.t), (1, 1.0));
    /// ```
    #[inline]
    fn intersect_filtered<F: FnMut(u32, &PrimHit) -> bool>(
        &self,
        ray: &Ray,
        filter: F,
    ) -> Option<Hit> {
        let mut query = Filtered::new(ClosestHit::new(ray), filter);
        self.ray_query(ray, &mut query, &mut NoStats);
        query.inner.hit()
    }

    /// Whether the ray hits anything `filter` accepts in its interval (for shadow rays through
    /// alpha-masked leaves): the walk stops at the first accepted hit.
    #[inline]
    fn occluded_filtered<F: FnMut(u32, &PrimHit) -> bool>(&self, ray: &Ray, filter: F) -> bool {
        let mut query = Filtered::new(AnyHit::new(ray), filter);
        self.ray_query(ray, &mut query, &mut NoStats);
        query.inner.occluded()
    }

    /// Every hit in the ray's interval, sorted by `t` (ties by primitive index), each
    /// primitive once: see [`AllHits`].
    ///
    /// ```
    /// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
    /// let tri = |z| Triangle::new(Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(0.0, 1.0, z));
    /// let accel = BruteForce::build(&[tri(3.0), tri(1.0), tri(2.0)], &());
    /// let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    /// let prims: Vec<u32> = accel.all_hits(&ray).iter().map(|h| h.prim).collect();
    /// assert_eq!(prims, [1, 2, 0]);
    /// assert_eq!(accel.count_hits(&ray), 3);
    /// ```
    fn all_hits(&self, ray: &Ray) -> Vec<Hit> {
        let mut query = AllHits::new(ray);
        self.ray_query(ray, &mut query, &mut NoStats);
        query.into_sorted()
    }

    /// How many primitives the ray hits in its interval: the length of
    /// [`all_hits`](Accel::all_hits), counted without keeping the hits.
    fn count_hits(&self, ray: &Ray) -> usize {
        let mut query = CountHits::new(ray);
        self.ray_query(ray, &mut query, &mut NoStats);
        query.count
    }

    /// The closest hit of each ray of `rays`, into the same slot of `out`, reporting events to
    /// `stats`: as many rays as both slices have slots (the rest of the longer one is left
    /// alone; nothing panics on a length mismatch).
    ///
    /// Every answer is exactly what [`intersect_with`](Accel::intersect_with) returns for that
    /// ray: the same primitive and the same bits of `t`, `u` and `v`. The default does exactly
    /// that, one ray at a time ([`intersect_each`]); a
    /// structure that traces coherent rays together overrides it and counts as the
    /// [`bundle`](crate::bundle) module describes.
    #[inline]
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        intersect_each(self, rays, out, stats);
    }

    /// Whether anything is hit in each ray's interval, into the same slot of `out`: as many rays
    /// as both slices have slots, each answer exactly [`occluded_with`](Accel::occluded_with)'s.
    #[inline]
    fn occluded_bundle_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        occluded_each(self, rays, out, stats);
    }

    /// [`intersect_bundle_with`](Accel::intersect_bundle_with) for the rays `order` lists, taken
    /// in its order: bundles are made of rays that come together in `order`, and the answer of
    /// ray `order[k]` goes to `out[order[k]]`. Entries at or past the shorter slice's length
    /// are ignored, and slots no entry names are left alone. This is how
    /// [`bundle::intersect_image`](crate::bundle::intersect_image) traces rays that come in
    /// image order by tiles, without moving them.
    ///
    /// Every answer is the single ray's, as for `intersect_bundle_with`. The default gathers
    /// the rays a few hundred at a time and answers them with `intersect_bundle_with`; a
    /// structure whose bundles gather the rays themselves overrides it.
    #[inline]
    fn intersect_bundle_ordered_with<S: Stats>(
        &self,
        rays: &[Ray],
        order: &[u32],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        let gather = |r: &[Ray], o: &mut [Option<Hit>], s: &mut S| {
            self.intersect_bundle_with(r, o, s);
        };
        in_order(rays, order, out, stats, gather);
    }

    /// [`occluded_bundle_with`](Accel::occluded_bundle_with) for the rays `order` lists, in its
    /// order, as [`intersect_bundle_ordered_with`](Accel::intersect_bundle_ordered_with).
    #[inline]
    fn occluded_bundle_ordered_with<S: Stats>(
        &self,
        rays: &[Ray],
        order: &[u32],
        out: &mut [bool],
        stats: &mut S,
    ) {
        let gather = |r: &[Ray], o: &mut [bool], s: &mut S| self.occluded_bundle_with(r, o, s);
        in_order(rays, order, out, stats, gather);
    }

    /// [`intersect_bundle_with`](Accel::intersect_bundle_with), uncounted.
    ///
    /// ```
    /// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
    /// let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y)];
    /// let accel = BruteForce::build(&tris, &());
    /// // An 8×8 tile of parallel rays, half of them beside the triangle.
    /// let rays: Vec<Ray> = (0..64)
    ///     .map(|i| Ray::new(Vec3::new((i % 8) as f32 * 0.25 - 1.0, 0.0, -2.0), Vec3::Z))
    ///     .collect();
    /// let mut hits = vec![None; rays.len()];
    /// accel.intersect_bundle(&rays, &mut hits);
    /// assert_eq!(hits[3].map(|h| (h.prim, h.t)), Some((0, 2.0)));
    /// assert!(hits.iter().zip(&rays).all(|(h, r)| *h == accel.intersect(r)));
    /// ```
    #[inline]
    fn intersect_bundle(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.intersect_bundle_with(rays, out, &mut NoStats);
    }

    /// [`occluded_bundle_with`](Accel::occluded_bundle_with), uncounted.
    #[inline]
    fn occluded_bundle(&self, rays: &[Ray], out: &mut [bool]) {
        self.occluded_bundle_with(rays, out, &mut NoStats);
    }

    /// The closest hit of each ray of `rays`, into the same slot of `out`, reporting events to
    /// `stats`, for rays that need not be coherent (a path tracer's bounces, scattered shadow
    /// rays, rays in any order): as many rays as both slices have slots, the rest left alone.
    ///
    /// Every answer is exactly [`intersect_with`](Accel::intersect_with)'s for that ray,
    /// whatever order the rays come in. The default traces one ray at a time
    /// ([`intersect_each`]); a structure that walks many rays together (rt-bvh's stream
    /// traversal) overrides it. Where [`intersect_bundle_with`](Accel::intersect_bundle_with)
    /// gains from rays that lie together in the slice, this gains from many rays, wherever
    /// they go. Node visits count per ray and node (or cell) tested, as single rays count them.
    #[inline]
    fn intersect_stream_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        intersect_each(self, rays, out, stats);
    }

    /// Whether anything is hit in each ray's interval, into the same slot of `out`, for rays
    /// in any order: [`intersect_stream_with`](Accel::intersect_stream_with) for occlusion,
    /// each answer exactly [`occluded_with`](Accel::occluded_with)'s.
    #[inline]
    fn occluded_stream_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        occluded_each(self, rays, out, stats);
    }

    /// [`intersect_stream_with`](Accel::intersect_stream_with), uncounted.
    ///
    /// ```
    /// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
    /// let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y)];
    /// let accel = BruteForce::build(&tris, &());
    /// // Rays from scattered points, every one towards the triangle's centre.
    /// let rays: Vec<Ray> = (0..100)
    ///     .map(|i| {
    ///         let from = Vec3::new((i % 7) as f32 - 3.0, (i % 5) as f32 - 2.0, -1.0 - (i % 3) as f32);
    ///         Ray::new(from, Vec3::new(0.0, -1.0 / 3.0, 0.0) - from)
    ///     })
    ///     .collect();
    /// let mut hits = vec![None; rays.len()];
    /// accel.intersect_stream(&rays, &mut hits);
    /// assert!(hits.iter().all(|h| h.is_some_and(|h| h.prim == 0)));
    /// assert!(hits.iter().zip(&rays).all(|(h, r)| *h == accel.intersect(r)));
    /// ```
    #[inline]
    fn intersect_stream(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.intersect_stream_with(rays, out, &mut NoStats);
    }

    /// [`occluded_stream_with`](Accel::occluded_stream_with), uncounted.
    #[inline]
    fn occluded_stream(&self, rays: &[Ray], out: &mut [bool]) {
        self.occluded_stream_with(rays, out, &mut NoStats);
    }

    /// The box around every valid primitive the structure holds ([`Aabb::EMPTY`] if none).
    fn bounds(&self) -> Aabb;

    /// Offers `query` every valid primitive that may lie within its ball: the one traversal
    /// behind closest-point queries, nearest boxes first so the ball shrinks early.
    ///
    /// Contract: every valid primitive with a point within `query.radius_sq().sqrt()` of
    /// `query.center()` is passed to [`BallQuery::test`] (and counted as a primitive test),
    /// where the radius is read as it stands when the primitive's box or cell is reached: a
    /// box (or cell) may be skipped only when its [`Aabb::distance_squared`] from the centre is
    /// greater than the radius squared. Primitives outside the ball may be offered too, and a
    /// primitive more than once.
    fn ball_query<Q: BallQuery<Self::Prim>, S: Stats>(&self, query: &mut Q, stats: &mut S);

    /// The primitive nearest to `point` no farther than `max_distance` (inclusive; `f32::INFINITY`
    /// for no limit), with its nearest point and distance, reporting events to `stats`.
    ///
    /// `None` when nothing lies that near, and for an invalid query (see
    /// [`ClosestPointQuery::new`]).
    #[inline]
    fn closest_point_with<S: Stats>(
        &self,
        point: Vec3,
        max_distance: f32,
        stats: &mut S,
    ) -> Option<PointHit> {
        let mut query = ClosestPointQuery::new(point, max_distance, &self.bounds());
        self.ball_query(&mut query, stats);
        query.best()
    }

    /// The primitive nearest to `point` no farther than `max_distance`: see
    /// [`closest_point_with`](Accel::closest_point_with).
    ///
    /// ```
    /// use rt_core::{Accel, BruteForce, Triangle, glam::Vec3};
    /// let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
    /// let accel = BruteForce::build(&tris, &Default::default());
    /// let near = accel.closest_point(Vec3::new(2.0, 0.0, 0.0), f32::INFINITY).unwrap();
    /// assert_eq!((near.prim, near.point, near.distance), (0, Vec3::X, 1.0));
    /// assert!(accel.closest_point(Vec3::new(2.0, 0.0, 0.0), 0.5).is_none());
    /// ```
    #[inline]
    fn closest_point(&self, point: Vec3, max_distance: f32) -> Option<PointHit> {
        self.closest_point_with(point, max_distance, &mut NoStats)
    }

    /// Offers `query` every valid primitive that may meet its box: the one traversal behind box
    /// overlap queries ([`overlapping`](Accel::overlapping), [`overlaps_any`](Accel::overlaps_any)).
    ///
    /// Contract: every valid primitive whose [`Primitive::overlaps_box`] is true for
    /// `query.bounds()` is passed to [`BoxQuery::test`] (or [`BoxQuery::test_triangle`]) and
    /// counted as a primitive test, until a test returns [`ControlFlow::Break`], after which
    /// nothing more is offered. A box (or cell) may be skipped only when it does not meet the
    /// query box ([`Aabb::overlaps`]: closed boxes, so touching counts). Primitives outside the
    /// box may be offered too, and a primitive more than once. An empty or NaN query box is
    /// offered nothing.
    ///
    /// The default runs [`ball_query`](Accel::ball_query) with the ball around the box, which
    /// is correct for any structure whose ball query offers primitives through
    /// [`BallQuery::test`], but offers everything in that ball: every structure of this
    /// workspace overrides it to prune by the box itself. A structure whose ball query offers
    /// pre-processed triangles by their edges must override it, since a vertex rebuilt from an
    /// edge can differ from the vertex in the last bit.
    ///
    /// [`ControlFlow::Break`]: std::ops::ControlFlow::Break
    fn box_query<Q: BoxQuery<Self::Prim>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        if let Some(mut ball) = crate::overlap::BallOfBox::new(query) {
            self.ball_query(&mut ball, stats);
        }
    }

    /// The primitives that meet the closed box `bounds` ([`Primitive::overlaps_box`]), in
    /// ascending order, reporting events to `stats`.
    #[inline]
    fn overlapping_with<S: Stats>(&self, bounds: &Aabb, stats: &mut S) -> Vec<u32> {
        let mut query = OverlapQuery::all(*bounds);
        self.box_query(&mut query, stats);
        query.into_ids()
    }

    /// The primitives that meet the closed box `bounds`, in ascending order: see
    /// [`overlapping_with`](Accel::overlapping_with).
    ///
    /// ```
    /// use rt_core::{Aabb, Accel, BruteForce, Triangle, glam::Vec3};
    /// // Two triangles whose bounding boxes both meet the query box; only one meets the box.
    /// let tris = [
    ///     Triangle::new(Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 4.0, 0.0)),
    ///     Triangle::new(Vec3::new(4.0, 0.0, 1.0), Vec3::new(4.0, 4.0, 1.0), Vec3::new(0.0, 4.0, 1.0)),
    /// ];
    /// let accel = BruteForce::build(&tris, &());
    /// let corner = Aabb::new(Vec3::new(0.0, 0.0, -1.0), Vec3::new(1.0, 1.0, 2.0));
    /// assert_eq!(accel.overlapping(&corner), vec![0]);
    /// assert!(accel.overlaps_any(&corner));
    /// ```
    #[inline]
    fn overlapping(&self, bounds: &Aabb) -> Vec<u32> {
        self.overlapping_with(bounds, &mut NoStats)
    }

    /// Whether any primitive meets the closed box `bounds`; the walk stops at the first found.
    #[inline]
    fn overlaps_any(&self, bounds: &Aabb) -> bool {
        let mut query = OverlapQuery::first(*bounds);
        self.box_query(&mut query, &mut NoStats);
        query.found()
    }

    /// Heap and inline bytes the structure holds, its copy of the primitives included.
    fn memory_bytes(&self) -> usize;

    /// The structure's shape.
    fn build_stats(&self) -> BuildStats;

    /// Calls `visit` for every node or cell, parents before their children. The default
    /// describes nothing: a structure that does not implement it cannot be drawn, but is
    /// otherwise complete.
    fn regions(&self, visit: &mut dyn FnMut(Region)) {
        let _ = visit;
    }
}

/// A broken structural invariant: what every structure's `validate` method returns when its
/// tree or cells do not match what the builder's rules say. Where (the node or cell, numbered as
/// the structure numbers them, when one is to blame) and what, in one sentence.
///
/// ```
/// use rt_core::ValidationError;
/// assert_eq!(ValidationError::at(7, "child box outside its parent").to_string(),
///            "node 7: child box outside its parent");
/// assert_eq!(ValidationError::new("3 primitives but 2 ids").to_string(), "3 primitives but 2 ids");
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ValidationError {
    /// The node or cell where the invariant fails (`None` for an invariant of the whole
    /// structure).
    pub node: Option<usize>,
    /// Which invariant, in one sentence.
    pub message: String,
}

impl ValidationError {
    /// An invariant of the whole structure.
    pub fn new(message: impl Into<String>) -> Self {
        Self {
            node: None,
            message: message.into(),
        }
    }

    /// An invariant that fails at node (or cell) `node`.
    pub fn at(node: usize, message: impl Into<String>) -> Self {
        Self {
            node: Some(node),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for ValidationError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.node {
            Some(n) => write!(f, "node {n}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

impl std::error::Error for ValidationError {}

/// The default bundle queries' loop: [`Accel::intersect_with`] for each ray into the same slot
/// of `out` (as many as both have), each counted as a ray traced singly
/// ([`Stats::single_ray`]).
pub fn intersect_each<A: Accel, S: Stats>(
    accel: &A,
    rays: &[Ray],
    out: &mut [Option<Hit>],
    stats: &mut S,
) {
    for (o, r) in out.iter_mut().zip(rays) {
        stats.single_ray();
        *o = accel.intersect_with(r, stats);
    }
}

/// The default ordered bundle queries: the rays `order` lists (those within both slices),
/// gathered a few hundred at a time in its order, answered by `trace`, each answer written to
/// its ray's slot.
fn in_order<T: Copy + Default, S: Stats>(
    rays: &[Ray],
    order: &[u32],
    out: &mut [T],
    stats: &mut S,
    mut trace: impl FnMut(&[Ray], &mut [T], &mut S),
) {
    const GATHER: usize = 256;
    let n = rays.len().min(out.len());
    let mut ids = Vec::with_capacity(GATHER);
    let mut gathered = Vec::with_capacity(GATHER);
    let mut answers = [T::default(); GATHER];
    let mut listed = order
        .iter()
        .map(|&i| i as usize)
        .filter(|&i| i < n)
        .peekable();
    while listed.peek().is_some() {
        ids.clear();
        ids.extend(listed.by_ref().take(GATHER));
        gathered.clear();
        gathered.extend(ids.iter().map(|&i| rays[i]));
        let answers = &mut answers[..ids.len()];
        trace(&gathered, answers, stats);
        for (&i, &a) in ids.iter().zip(answers.iter()) {
            out[i] = a;
        }
    }
}

/// The default bundle queries' loop: [`Accel::occluded_with`] for each ray into the same slot of
/// `out` (as many as both have), each counted as a ray traced singly.
pub fn occluded_each<A: Accel, S: Stats>(accel: &A, rays: &[Ray], out: &mut [bool], stats: &mut S) {
    for (o, r) in out.iter_mut().zip(rays) {
        stats.single_ray();
        *o = accel.occluded_with(r, stats);
    }
}

/// The methods of an [`Accel`] impl whose walks a structure keeps in its phase files, as
/// inherent methods: each `walk: method` pair forwards one walk to `self.method(..)`, so the
/// impl names where each walk lives and writes nothing twice. The walks:
///
/// | walk | the methods it writes | `method`'s signature |
/// | --- | --- | --- |
/// | `build` | [`build`](Accel::build), building from the slice as from any geometry | the structure's [`build_from`](Accel::build_from) (give `build_from`) |
/// | `ray` | [`ray_query`](Accel::ray_query) | `fn(&self, &Ray, &mut Q, &mut S)` |
/// | `bundle` | [`intersect_bundle_with`](Accel::intersect_bundle_with), [`occluded_bundle_with`](Accel::occluded_bundle_with) | `fn::<S, const ANY: bool>(&self, rays: &[Ray], slots: usize, &mut S, answer: impl FnMut(usize, Option<Hit>))`, answering `Some` for a blocked ray when `ANY` |
/// | `ordered_bundle` | the same and their `_ordered_with` forms ([`intersect_bundle_ordered_with`](Accel::intersect_bundle_ordered_with)) | the same with `order: Option<&[u32]>` after `slots`: the rays it lists, in its order, when given |
/// | `ball` | [`ball_query`](Accel::ball_query) | `fn(&self, &mut Q, &mut S)` |
/// | `boxes` | [`box_query`](Accel::box_query) | `fn(&self, &mut Q, &mut S) -> ControlFlow<()>` |
/// | `regions` | [`regions`](Accel::regions) | `fn(&self, &mut dyn FnMut(Region))` |
///
/// ```
/// use rt_core::{Aabb, Accel, BallQuery, BruteForce, BuildStats, Geometry, Triangle};
/// /// Brute force under another name, its walks kept as inherent methods.
/// struct Wrapped(BruteForce<Triangle>);
/// impl Wrapped {
///     fn ball<Q: BallQuery<Triangle>, S: rt_core::Stats>(&self, q: &mut Q, s: &mut S) {
///         self.0.ball_query(q, s);
///     }
/// }
/// impl Accel for Wrapped {
///     type Prim = Triangle;
///     type Params = ();
///     const NAME: &'static str = "wrapped";
///     fn presets() -> Vec<(&'static str, ())> {
///         vec![("default", ())]
///     }
///     fn build_from<G: Geometry<Prim = Triangle> + ?Sized>(g: &G, _: &()) -> Self {
///         Self(BruteForce::build_from(g, &()))
///     }
///     fn bounds(&self) -> Aabb {
///         self.0.bounds()
///     }
///     fn memory_bytes(&self) -> usize {
///         self.0.memory_bytes()
///     }
///     fn build_stats(&self) -> BuildStats {
///         self.0.build_stats()
///     }
///     rt_core::accel_walks!(build: build_from, ball: ball);
/// }
/// let tris = [Triangle::new(rt_core::glam::Vec3::ZERO, rt_core::glam::Vec3::X, rt_core::glam::Vec3::Y)];
/// assert_eq!(Wrapped::build(&tris, &()).overlapping(&Aabb::new(rt_core::glam::Vec3::ZERO, rt_core::glam::Vec3::ONE)), [0]);
/// ```
#[macro_export]
macro_rules! accel_walks {
    ($($walk:ident : $method:ident),* $(,)?) => {
        $($crate::accel_walks!(@$walk $method);)*
    };
    (@build $method:ident) => {
        fn build(prims: &[Self::Prim], params: &Self::Params) -> Self {
            Self::$method(prims, params)
        }
    };
    (@ray $method:ident) => {
        #[inline]
        fn ray_query<Q: $crate::RayQuery, S: $crate::Stats>(
            &self,
            ray: &$crate::Ray,
            query: &mut Q,
            stats: &mut S,
        ) {
            self.$method(ray, query, stats);
        }
    };
    (@bundle $method:ident) => {
        fn intersect_bundle_with<S: $crate::Stats>(
            &self,
            rays: &[$crate::Ray],
            out: &mut [Option<$crate::Hit>],
            stats: &mut S,
        ) {
            self.$method::<S, false>(rays, out.len(), stats, |slot, hit| out[slot] = hit);
        }
        fn occluded_bundle_with<S: $crate::Stats>(
            &self,
            rays: &[$crate::Ray],
            out: &mut [bool],
            stats: &mut S,
        ) {
            self.$method::<S, true>(rays, out.len(), stats, |slot, hit| {
                out[slot] = hit.is_some()
            });
        }
    };
    (@ordered_bundle $method:ident) => {
        fn intersect_bundle_with<S: $crate::Stats>(
            &self,
            rays: &[$crate::Ray],
            out: &mut [Option<$crate::Hit>],
            stats: &mut S,
        ) {
            self.$method::<S, false>(rays, out.len(), None, stats, |slot, hit| out[slot] = hit);
        }
        fn occluded_bundle_with<S: $crate::Stats>(
            &self,
            rays: &[$crate::Ray],
            out: &mut [bool],
            stats: &mut S,
        ) {
            self.$method::<S, true>(rays, out.len(), None, stats, |slot, hit| {
                out[slot] = hit.is_some()
            });
        }
        fn intersect_bundle_ordered_with<S: $crate::Stats>(
            &self,
            rays: &[$crate::Ray],
            order: &[u32],
            out: &mut [Option<$crate::Hit>],
            stats: &mut S,
        ) {
            self.$method::<S, false>(rays, out.len(), Some(order), stats, |slot, hit| {
                out[slot] = hit
            });
        }
        fn occluded_bundle_ordered_with<S: $crate::Stats>(
            &self,
            rays: &[$crate::Ray],
            order: &[u32],
            out: &mut [bool],
            stats: &mut S,
        ) {
            self.$method::<S, true>(rays, out.len(), Some(order), stats, |slot, hit| {
                out[slot] = hit.is_some()
            });
        }
    };
    (@ball $method:ident) => {
        fn ball_query<Q: $crate::BallQuery<Self::Prim>, S: $crate::Stats>(
            &self,
            query: &mut Q,
            stats: &mut S,
        ) {
            self.$method(query, stats);
        }
    };
    (@boxes $method:ident) => {
        fn box_query<Q: $crate::BoxQuery<Self::Prim>, S: $crate::Stats>(
            &self,
            query: &mut Q,
            stats: &mut S,
        ) {
            let _ = self.$method(query, stats);
        }
    };
    (@regions $method:ident) => {
        fn regions(&self, visit: &mut dyn FnMut($crate::Region)) {
            self.$method(visit);
        }
    };
}

#[cfg(test)]
mod tests {
    use super::Hit;

    #[test]
    fn equal_answers_agree_even_at_an_infinite_t() {
        // A valid ray whose direction is near the smallest normal f32 hits at t = inf (found by
        // the `trace` fuzz target, where two structures gave this same answer and "disagreed").
        let hit = |prim, t| {
            Some(Hit {
                prim,
                t,
                u: 0.5,
                v: 0.25,
            })
        };
        assert!(Hit::agree(hit(0, f32::INFINITY), hit(0, f32::INFINITY)));
        assert!(!Hit::agree(hit(0, f32::INFINITY), hit(1, f32::INFINITY)));
        assert!(!Hit::agree(hit(0, f32::INFINITY), hit(0, 1e30)));
        assert!(Hit::agree(hit(3, 100.0), hit(3, 100.0005)));
        assert!(!Hit::agree(hit(3, 100.0), hit(3, 100.01)));
        assert!(!Hit::agree(hit(3, 100.0), None));
    }
}

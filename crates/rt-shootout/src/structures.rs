//! The rows of a shootout: structure types and presets, each built as an
//! [`rt_core::DynAccel`] (the one object-safe view of any structure), and the parallel passes
//! every command makes over them.
//!
//! [`rt_core::Accel`] is generic (and so not object-safe); a shootout needs a list. Each
//! [`Entry`] builds one structure type and preset. Dispatch is dynamic only per chunk of rays:
//! the chunk's loop ([`DynAccel::intersect_all`] and its kin) is compiled for the structure, so
//! timings measure the structure, not the trait object.

use rayon::prelude::*;
use rt_bvh::Bvh;
use rt_core::glam::Vec3;
use rt_core::{
    Aabb, Accel, BallQuery, BuildStats, Counters, DynAccel, Hit, NoStats, OverlapQuery, PointHit,
    PrimHit, Ray, Refit, RefitError, Region, Shape, Stats, Trace, Triangle,
};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_instance::{Instance, TwoLevel};
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_sdf::{SignedPoint, WindingTree, winding_number_exact};
use rt_simd::BundledBruteForce;
use std::sync::Arc;

/// Which query a run makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Closest hit.
    Closest,
    /// Any hit (occlusion); answers are `Some` with `prim == u32::MAX` when occluded.
    Any,
}

/// A built structure that can also follow its triangles when they move ([`Refit`]): an
/// extension of [`DynAccel`] for `animate`.
pub trait Refittable: DynAccel<Triangle> {
    /// [`Refit::refit`] to `tris`.
    ///
    /// # Errors
    /// As [`Refit::refit`]: the structure is then unchanged.
    fn refit(&mut self, tris: &[Triangle]) -> Result<(), RefitError>;
}

impl<A: Refit<Prim = Triangle>> Refittable for A {
    fn refit(&mut self, tris: &[Triangle]) -> Result<(), RefitError> {
        Refit::refit(self, tris)
    }
}

/// Queries per task of the parallel passes; the trait object is crossed once per task.
const CHUNK: usize = 256;
/// Rays per task of a stream pass: a stream gains from many rays at once (rt-bvh's streams
/// take up to 4,096), and a task's answers should stay in the caches as a chunk's do.
const STREAM_TASK: usize = 4096;
const OCCLUDED: Hit = Hit {
    prim: u32::MAX,
    t: f32::NAN,
    u: 0.0,
    v: 0.0,
};

/// Every item's answer, filled in parallel chunks over the current rayon pool, each chunk
/// counting into its own [`Counters`], and the counters summed: the counted passes.
fn counted_chunks<T: Sync, A: Clone + Send>(
    items: &[T],
    fill: impl Fn(&[T], &mut [Option<A>], &mut Counters) + Sync,
) -> (Vec<Option<A>>, Counters) {
    counted_tasks(items, CHUNK, fill)
}

/// [`counted_chunks`] in tasks of `task` items.
fn counted_tasks<T: Sync, A: Clone + Send>(
    items: &[T],
    task: usize,
    fill: impl Fn(&[T], &mut [Option<A>], &mut Counters) + Sync,
) -> (Vec<Option<A>>, Counters) {
    let mut answers = vec![None; items.len()];
    let counters = answers
        .par_chunks_mut(task)
        .zip(items.par_chunks(task))
        .map(|(out, items)| {
            let mut c = Counters::default();
            fill(items, out, &mut c);
            c
        })
        .reduce(Counters::default, Counters::merged);
    (answers, counters)
}

/// How a pass hands its rays to a structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// One ray per query ([`DynAccel::intersect_all`], [`DynAccel::occluded_all`]).
    Single,
    /// As bundles ([`DynAccel::intersect_bundle_dyn`], [`DynAccel::occluded_bundle_dyn`]).
    Bundles,
    /// As streams ([`DynAccel::intersect_stream_dyn`], [`DynAccel::occluded_stream_dyn`]).
    Streams,
}

/// Rays per task of a pass.
fn task_len(pass: Pass) -> usize {
    match pass {
        Pass::Streams => STREAM_TASK,
        Pass::Single | Pass::Bundles => CHUNK,
    }
}

/// One task's answers to `rays` into `out`, counted into `counters` if given.
fn answer_chunk(
    s: &dyn DynAccel<Triangle>,
    rays: &[Ray],
    query: Query,
    pass: Pass,
    out: &mut [Option<Hit>],
    counters: Option<&mut Counters>,
) {
    match (query, pass) {
        (Query::Closest, Pass::Single) => s.intersect_all(rays, out, counters),
        (Query::Closest, Pass::Bundles) => s.intersect_bundle_dyn(rays, out, counters),
        (Query::Closest, Pass::Streams) => s.intersect_stream_dyn(rays, out, counters),
        (Query::Any, _) => {
            let (mut kept, mut long) = ([false; CHUNK], Vec::new());
            let blocked = if rays.len() <= CHUNK {
                &mut kept[..rays.len()]
            } else {
                long.resize(rays.len(), false);
                &mut long[..]
            };
            match pass {
                Pass::Single => s.occluded_all(rays, blocked, counters),
                Pass::Bundles => s.occluded_bundle_dyn(rays, blocked, counters),
                Pass::Streams => s.occluded_stream_dyn(rays, blocked, counters),
            }
            for (o, &b) in out.iter_mut().zip(blocked.iter()) {
                *o = b.then_some(OCCLUDED);
            }
        }
    }
}

/// Every ray's answer, with the counters of all of them: the counted pass of every row, in
/// parallel chunks over the current rayon pool, each chunk counting into its own [`Counters`].
pub fn trace_counted(
    s: &dyn DynAccel<Triangle>,
    rays: &[Ray],
    query: Query,
) -> (Vec<Option<Hit>>, Counters) {
    trace_counted_as(s, rays, query, Pass::Single)
}

/// [`trace_counted`], handing the rays over as `pass` says. Tasks take 256 rays, four full
/// bundles, so a bundle pass sees the rays' order in runs of 64 as they come.
pub fn trace_counted_as(
    s: &dyn DynAccel<Triangle>,
    rays: &[Ray],
    query: Query,
    pass: Pass,
) -> (Vec<Option<Hit>>, Counters) {
    counted_tasks(rays, task_len(pass), |rays, out, c| {
        answer_chunk(s, rays, query, pass, out, Some(c))
    })
}

/// Traces every ray without counters and returns the number of hits (so the work cannot be
/// optimized away): the timed pass, in parallel chunks over the current rayon pool.
pub fn trace_timed(s: &dyn DynAccel<Triangle>, rays: &[Ray], query: Query) -> usize {
    trace_timed_as(s, rays, query, Pass::Single)
}

/// [`trace_timed`], handing the rays over as `pass` says.
pub fn trace_timed_as(s: &dyn DynAccel<Triangle>, rays: &[Ray], query: Query, pass: Pass) -> usize {
    rays.par_chunks(task_len(pass))
        .map(|rays| {
            let (mut kept, mut long) = ([None; CHUNK], Vec::new());
            let out = if rays.len() <= CHUNK {
                &mut kept[..rays.len()]
            } else {
                long.resize(rays.len(), None);
                &mut long[..]
            };
            answer_chunk(s, rays, query, pass, out, None);
            out.iter().filter(|h| h.is_some()).count()
        })
        .sum()
}

/// One ray's answer, and the events it caused.
pub fn answer_counted(
    s: &dyn DynAccel<Triangle>,
    ray: &Ray,
    query: Query,
) -> (Option<Hit>, Counters) {
    let mut c = Counters::default();
    let answer = match query {
        Query::Closest => s.intersect_dyn(ray, Some(&mut c)),
        Query::Any => s.occluded_dyn(ray, Some(&mut c)).then_some(OCCLUDED),
    };
    (answer, c)
}

/// One ray's answer.
pub fn answer(s: &dyn DynAccel<Triangle>, ray: &Ray, query: Query) -> Option<Hit> {
    match query {
        Query::Closest => s.intersect_dyn(ray, None),
        Query::Any => s.occluded_dyn(ray, None).then_some(OCCLUDED),
    }
}

/// The closest point for every `(point, maximum distance)`, with the counters of all of them, in
/// parallel chunks over the current rayon pool.
pub fn closest_counted(
    s: &dyn DynAccel<Triangle>,
    points: &[(Vec3, f32)],
) -> (Vec<Option<PointHit>>, Counters) {
    counted_chunks(points, |points, out, c| {
        s.closest_points_all(points, out, Some(c))
    })
}

/// The signed distance for every `(point, maximum distance)`, signed by `sign`, with the
/// counters of the closest-point walks, in parallel chunks.
pub fn signed_counted(
    s: &dyn DynAccel<Triangle>,
    sign: &WindingTree,
    points: &[(Vec3, f32)],
) -> (Vec<Option<SignedPoint>>, Counters) {
    counted_chunks(points, |points, out, c| {
        rt_sdf::signed_distances(s, sign, points, out, Some(c))
    })
}

/// The signed distances without counters; returns how many points are inside. The timed pass.
pub fn signed_timed(
    s: &dyn DynAccel<Triangle>,
    sign: &WindingTree,
    points: &[(Vec3, f32)],
) -> usize {
    points
        .par_chunks(CHUNK)
        .map(|points| {
            let mut out = [None; CHUNK];
            let out = &mut out[..points.len()];
            rt_sdf::signed_distances(s, sign, points, out, None);
            out.iter().flatten().filter(|h| h.inside).count()
        })
        .sum()
}

/// Brute force's signed distances, the reference: brute force's closest points, signed by the
/// exact winding number of `tris` (every triangle's solid angle, [`winding_number_exact`]) and
/// not by the tree the rows use.
pub fn signed_exact(
    s: &dyn DynAccel<Triangle>,
    tris: &[Triangle],
    points: &[(Vec3, f32)],
) -> (Vec<Option<SignedPoint>>, Counters) {
    counted_chunks(points, |points, out, c| {
        let mut near = [None; CHUNK];
        let near = &mut near[..points.len()];
        s.closest_points_all(points, near, Some(c));
        for ((o, &(p, _)), near) in out.iter_mut().zip(points).zip(near.iter()) {
            let inside = winding_number_exact(tris, p).is_ok_and(|w| w > 0.5);
            *o = near.map(|near| SignedPoint::signed(near, inside));
        }
    })
}

/// The closest points without counters; returns how many were found. The timed pass.
pub fn closest_timed(s: &dyn DynAccel<Triangle>, points: &[(Vec3, f32)]) -> usize {
    points
        .par_chunks(CHUNK)
        .map(|points| {
            let mut out = [None; CHUNK];
            let out = &mut out[..points.len()];
            s.closest_points_all(points, out, None);
            out.iter().filter(|h| h.is_some()).count()
        })
        .sum()
}

/// Every box's overlap list ([`rt_core::Accel::overlapping`]: ascending, each primitive once),
/// counted.
pub fn overlap_counted(s: &dyn DynAccel<Triangle>, boxes: &[Aabb]) -> (Vec<Vec<u32>>, Counters) {
    let (found, counters) = counted_chunks(boxes, |boxes, out, c| {
        for (b, slot) in boxes.iter().zip(out) {
            let mut query = OverlapQuery::all(*b);
            s.box_query_dyn(&mut query, Some(c));
            *slot = Some(query.into_ids());
        }
    });
    (
        found.into_iter().map(Option::unwrap_or_default).collect(),
        counters,
    )
}

/// How many boxes meet a primitive, without counters: the timed pass. Each box's list is
/// collected, as a caller of `overlapping` gets it.
pub fn overlap_timed(s: &dyn DynAccel<Triangle>, boxes: &[Aabb]) -> usize {
    boxes
        .par_chunks(CHUNK)
        .map(|boxes| {
            boxes
                .iter()
                .filter(|b| {
                    let mut query = OverlapQuery::all(**b);
                    s.box_query_dyn(&mut query, None);
                    !query.into_ids().is_empty()
                })
                .count()
        })
        .sum()
}

/// Every ray's hits ([`rt_core::Accel::all_hits`]: sorted, each primitive once), counted.
pub fn all_hits_counted(s: &dyn DynAccel<Triangle>, rays: &[Ray]) -> (Vec<Vec<Hit>>, Counters) {
    let (found, counters) = counted_chunks(rays, |rays, out, c| {
        for (r, slot) in rays.iter().zip(out) {
            *slot = Some(s.all_hits_dyn(r, Some(c)));
        }
    });
    (
        found.into_iter().map(Option::unwrap_or_default).collect(),
        counters,
    )
}

/// How many rays hit something, every hit collected as a caller of `all_hits` gets them,
/// without counters: the timed pass.
pub fn all_hits_timed(s: &dyn DynAccel<Triangle>, rays: &[Ray]) -> usize {
    rays.par_chunks(CHUNK)
        .map(|rays| {
            rays.iter()
                .filter(|r| !s.all_hits_dyn(r, None).is_empty())
                .count()
        })
        .sum()
}

/// Every ray's closest hit and whether it is occluded, both through `filter`; the closest hits
/// counted.
pub fn filtered_counted(
    s: &dyn DynAccel<Triangle>,
    rays: &[Ray],
    filter: fn(u32, &PrimHit) -> bool,
) -> (Vec<(Option<Hit>, bool)>, Counters) {
    let (found, counters) = counted_chunks(rays, |rays, out, c| {
        for (r, slot) in rays.iter().zip(out) {
            // The counters follow the closest hit, the query the timed pass makes.
            let hit = s.intersect_filtered_dyn(r, &mut { filter }, Some(c));
            *slot = Some((hit, s.occluded_filtered_dyn(r, &mut { filter }, None)));
        }
    });
    (
        found
            .into_iter()
            .map(|a| a.unwrap_or((None, false)))
            .collect(),
        counters,
    )
}

/// How many rays hit something through `filter` (closest hit), without counters: the timed
/// pass.
pub fn filtered_timed(
    s: &dyn DynAccel<Triangle>,
    rays: &[Ray],
    filter: fn(u32, &PrimHit) -> bool,
) -> usize {
    rays.par_chunks(CHUNK)
        .map(|rays| {
            rays.iter()
                .filter(|r| s.intersect_filtered_dyn(r, &mut { filter }, None).is_some())
                .count()
        })
        .sum()
}

/// Builds one row's structure over a scene (shared, so that instances can hold it too).
pub type Builder = Arc<dyn Fn(&[Triangle]) -> Arc<dyn DynAccel<Triangle>> + Send + Sync>;

/// Builds one row's structure over a scene as one that can refit (`animate`).
pub type RefitBuilder = Arc<dyn Fn(&[Triangle]) -> Box<dyn Refittable> + Send + Sync>;

/// Builds one row's structure over triangles and spheres, for `render`.
pub type ShapeBuilder = Arc<dyn Fn(&[Shape]) -> Box<dyn DynAccel<Shape>> + Send + Sync>;

/// One row a shootout can run: a structure type with one preset.
#[derive(Clone)]
pub struct Entry {
    /// Row name: the structure's [`Accel::NAME`] for its first preset, `NAME-preset` otherwise.
    pub name: String,
    /// Builds it over triangles (also the bottom level of `compare --instances`).
    pub build: Builder,
    /// Builds the same type and preset over [`Shape`]s, when the structure is generic over its
    /// primitive (see [`entries_of`]); `None` for triangle-only structures, which `render`
    /// cannot use.
    pub build_shapes: Option<ShapeBuilder>,
    /// Builds the same as a structure that can refit, when its type implements [`Refit`] (see
    /// [`entries_of_refittable`]); `None` for the others, which `animate` rebuilds every frame.
    pub build_refittable: Option<RefitBuilder>,
}

impl std::fmt::Debug for Entry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Entry")
            .field("name", &self.name)
            .field("renders", &self.build_shapes.is_some())
            .field("refits", &self.build_refittable.is_some())
            .finish_non_exhaustive()
    }
}

fn row_name<A: Accel>(i: usize, preset: &str) -> String {
    if i == 0 {
        A::NAME.to_string()
    } else {
        format!("{}-{preset}", A::NAME)
    }
}

/// Every preset of a structure type, `A` over triangles and `S` the same type over [`Shape`]s
/// (the same presets apply to both), so the rows can also render.
pub fn entries_of<A, S>() -> Vec<Entry>
where
    A: Accel<Prim = Triangle> + 'static,
    S: Accel<Prim = Shape, Params = A::Params> + 'static,
{
    A::presets()
        .into_iter()
        .enumerate()
        .map(|(i, (preset, params))| {
            let for_shapes = params.clone();
            Entry {
                name: row_name::<A>(i, preset),
                build: Arc::new(move |tris: &[Triangle]| {
                    Arc::new(A::build(tris, &params)) as Arc<dyn DynAccel<Triangle>>
                }),
                build_shapes: Some(Arc::new(move |shapes: &[Shape]| {
                    Box::new(S::build(shapes, &for_shapes)) as Box<dyn DynAccel<Shape>>
                })),
                build_refittable: None,
            }
        })
        .collect()
}

/// Every preset of a structure type over triangles only (a student's first structure, say):
/// rows for `compare`, not for `render`.
pub fn entries_of_triangles<A>() -> Vec<Entry>
where
    A: Accel<Prim = Triangle> + 'static,
{
    A::presets()
        .into_iter()
        .enumerate()
        .map(|(i, (preset, params))| Entry {
            name: row_name::<A>(i, preset),
            build: Arc::new(move |tris: &[Triangle]| {
                Arc::new(A::build(tris, &params)) as Arc<dyn DynAccel<Triangle>>
            }),
            build_shapes: None,
            build_refittable: None,
        })
        .collect()
}

/// [`entries_of`] for a structure type that can refit: the same rows, each also buildable as
/// a [`Refittable`] with its preset, for `animate`.
pub fn entries_of_refittable<A, S>() -> Vec<Entry>
where
    A: Refit<Prim = Triangle> + 'static,
    S: Accel<Prim = Shape, Params = A::Params> + 'static,
{
    entries_of::<A, S>()
        .into_iter()
        .zip(A::presets())
        .map(|(mut entry, (_, params))| {
            entry.build_refittable = Some(Arc::new(move |tris: &[Triangle]| {
                Box::new(A::build(tris, &params)) as Box<dyn Refittable>
            }));
            entry
        })
        .collect()
}

/// Every built-in structure and preset, in report order.
pub fn all() -> Vec<Entry> {
    let mut all = entries_of_refittable::<Bvh<Triangle>, Bvh<Shape>>();
    all.extend(entries_of::<KdTree<Triangle>, KdTree<Shape>>());
    all.extend(entries_of::<Grid<Triangle>, Grid<Shape>>());
    all.extend(entries_of::<HGrid<Triangle>, HGrid<Shape>>());
    all.extend(entries_of::<Octree<Triangle>, Octree<Shape>>());
    all
}

/// The brute-force reference, whose bundle queries test every triangle against a bundle's
/// lanes at once (rt-simd's [`BundledBruteForce`]): the answers of the rays `compare` checks
/// come from them, each the single-ray answer bit for bit.
pub fn brute_force() -> Entry {
    entries_of::<BundledBruteForce<Triangle>, BundledBruteForce<Shape>>().remove(0)
}

/// The entry called `name` among `entries`, or `brute-force`; else an error listing the names.
///
/// # Errors
/// One line naming the unknown structure and the known ones.
pub fn find(entries: &[Entry], name: &str) -> Result<Entry, String> {
    if name == "brute-force" {
        return Ok(brute_force());
    }
    entries
        .iter()
        .find(|e| e.name == name)
        .cloned()
        .ok_or_else(|| {
            format!(
                "unknown structure `{name}` (known: {}, brute-force)",
                entries
                    .iter()
                    .map(|e| e.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
}

/// A two-level scene as a row: a field of instances of one mesh. Hits name the flattened
/// triangle `instance · mesh_len + prim`, so rows over the same field compare directly.
pub struct Field<T> {
    scene: T,
    mesh: Arc<[Triangle]>,
}

impl<T> std::fmt::Debug for Field<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Field")
            .field("mesh_triangles", &self.mesh.len())
            .finish_non_exhaustive()
    }
}

impl<T: TwoLevel<Triangle>> Field<T> {
    /// The field of `mesh` placed by each of `transforms` (instance `k` gets id `k`), every
    /// instance sharing the bottom level `bottom` builds once.
    ///
    /// # Errors
    /// One line for a transform that is not finite or is too badly conditioned, or a field with
    /// more than 2³² - 1 triangles.
    pub fn new(
        mesh: Arc<[Triangle]>,
        transforms: &[rt_core::glam::Affine3A],
        bottom: &Builder,
    ) -> Result<Self, String> {
        if (mesh.len() as u64) * (transforms.len() as u64) >= u64::from(u32::MAX) {
            return Err(format!(
                "a field of {} instances of {} triangles has more than 2^32 - 1 triangles",
                transforms.len(),
                mesh.len()
            ));
        }
        let shared = bottom(&mesh);
        let instances = transforms
            .iter()
            .enumerate()
            .map(|(k, &xf)| {
                Instance::new(shared.clone(), xf, k as u32)
                    .map_err(|e| format!("instance {k}: {e}"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            scene: T::build(instances),
            mesh,
        })
    }

    fn flat(&self, h: rt_instance::InstanceHit) -> Hit {
        Hit {
            prim: h.instance * self.mesh.len() as u32 + h.prim,
            ..h.hit()
        }
    }

    fn ask<S: Stats>(&self, ray: &Ray, query: Query, stats: &mut S) -> Option<Hit> {
        match query {
            Query::Closest => self.scene.intersect_with(ray, stats).map(|h| self.flat(h)),
            Query::Any => self.scene.occluded_with(ray, stats).then_some(OCCLUDED),
        }
    }

    /// `query(rays, hits)` in chunks of up to 256 rays, each chunk's two-level hits written
    /// into `out` flattened.
    fn answer(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        mut query: impl FnMut(&[Ray], &mut [Option<rt_instance::InstanceHit>]),
    ) {
        let mut hits = [None; 256];
        for (rays, out) in rays.chunks(256).zip(out.chunks_mut(256)) {
            let hits = &mut hits[..rays.len().min(out.len())];
            query(rays, hits);
            for (o, h) in out.iter_mut().zip(hits.iter()) {
                *o = h.map(|h| self.flat(h));
            }
        }
    }

    fn point(&self, p: Vec3, max: f32, c: &mut Counters) -> Option<PointHit> {
        self.scene.closest_point_with(p, max, c).map(|h| PointHit {
            prim: h.instance * self.mesh.len() as u32 + h.prim,
            point: h.point,
            distance: h.distance,
            feature: h.feature,
        })
    }
}

/// A field as a structure: the flattened scene's numbering, the two-level walk's counts.
impl<T: TwoLevel<Triangle>> DynAccel<Triangle> for Field<T> {
    fn name(&self) -> &'static str {
        "instances"
    }

    fn bounds_dyn(&self) -> Aabb {
        self.scene.bounds()
    }

    fn memory_bytes_dyn(&self) -> usize {
        self.scene.memory_bytes()
    }

    /// The bottom level's shape, with the number of instances among the named figures.
    fn build_stats_dyn(&self) -> BuildStats {
        let instances = self.scene.instances();
        let mut stats = instances
            .first()
            .map(|i| i.bottom().build_stats_dyn())
            .unwrap_or_default();
        stats.extra.push(("instances", instances.len() as f64));
        stats
    }

    /// None: a field is drawn as its instances, which `draw` does not do.
    fn regions_dyn(&self) -> Vec<Region> {
        Vec::new()
    }

    fn intersect_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> Option<Hit> {
        match counters {
            Some(c) => self.ask(ray, Query::Closest, c),
            None => self.ask(ray, Query::Closest, &mut NoStats),
        }
    }

    fn occluded_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> bool {
        match counters {
            Some(c) => self.ask(ray, Query::Any, c),
            None => self.ask(ray, Query::Any, &mut NoStats),
        }
        .is_some()
    }

    /// Offers every world-space triangle of every instance whose box the ball reaches (the
    /// flattened scene, as brute force would), numbered as hits are.
    fn ball_query_dyn(&self, query: &mut dyn BallQuery<Triangle>, counters: Option<&mut Counters>) {
        let mut none = Counters::default();
        let counters = counters.unwrap_or(&mut none);
        let n = self.mesh.len() as u32;
        for (k, inst) in self.scene.instances().iter().enumerate() {
            counters.node_visit();
            if inst.world_bounds().distance_squared(query.center()) > query.radius_sq() {
                continue;
            }
            let xf = inst.transform().to_world();
            for (i, t) in self.mesh.iter().enumerate() {
                let w = |v: Vec3| xf.transform_point3(v);
                counters.prim_test();
                query.test(
                    &Triangle::new(w(t.v0), w(t.v1), w(t.v2)),
                    k as u32 * n + i as u32,
                );
            }
        }
    }

    /// Counts only: the two-level walk reports no steps.
    fn trace_dyn(&self, ray: &Ray, any: bool) -> (Option<Hit>, Trace) {
        let mut t = Trace::default();
        let query = if any { Query::Any } else { Query::Closest };
        (self.ask(ray, query, &mut t), t)
    }

    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        mut counters: Option<&mut Counters>,
    ) {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = self.intersect_dyn(r, counters.as_deref_mut());
        }
    }

    fn occluded_all(&self, rays: &[Ray], out: &mut [bool], mut counters: Option<&mut Counters>) {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = self.occluded_dyn(r, counters.as_deref_mut());
        }
    }

    /// The scene's bundle queries ([`TwoLevel::intersect_bundle_with`]).
    fn intersect_bundle_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        let mut counters = counters;
        self.answer(rays, out, |rays, hits| match counters.as_deref_mut() {
            Some(c) => self.scene.intersect_bundle_with(rays, hits, c),
            None => self.scene.intersect_bundle(rays, hits),
        });
    }

    fn occluded_bundle_dyn(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        match counters {
            Some(c) => self.scene.occluded_bundle_with(rays, out, c),
            None => self.scene.occluded_bundle(rays, out),
        }
    }

    /// The scene's stream queries ([`TwoLevel::intersect_stream_with`]).
    fn intersect_stream_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        let mut counters = counters;
        self.answer(rays, out, |rays, hits| match counters.as_deref_mut() {
            Some(c) => self.scene.intersect_stream_with(rays, hits, c),
            None => self.scene.intersect_stream(rays, hits),
        });
    }

    fn occluded_stream_dyn(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        match counters {
            Some(c) => self.scene.occluded_stream_with(rays, out, c),
            None => self.scene.occluded_stream(rays, out),
        }
    }

    fn closest_points_all(
        &self,
        points: &[(Vec3, f32)],
        out: &mut [Option<PointHit>],
        counters: Option<&mut Counters>,
    ) {
        let mut none = Counters::default();
        let counters = counters.unwrap_or(&mut none);
        for (o, &(p, max)) in out.iter_mut().zip(points) {
            *o = self.point(p, max, counters);
        }
    }
}

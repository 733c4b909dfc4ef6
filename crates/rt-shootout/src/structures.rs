//! The rows of a shootout: structure types and presets behind one object-safe interface.
//!
//! [`rt_core::Accel`] is generic (and so not object-safe); a shootout needs a list. Each
//! [`Entry`] wraps one structure type and preset. Dispatch is dynamic only per batch of rays: the
//! batch loop itself is monomorphized, so timings measure the structure, not the wrapper.

use rayon::prelude::*;
use rt_bvh::Bvh;
use rt_core::glam::Vec3;
use rt_core::{
    Aabb, Accel, BallQuery, Bottom, BruteForce, BuildStats, Counters, Hit, Instance, PointHit, Ray,
    Refit, RefitError, Region, Shape, Stats, Trace, Triangle, TwoLevel,
};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_render::Tracer;
use std::sync::Arc;

/// Which query a run makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Closest hit.
    Closest,
    /// Any hit (occlusion); answers are `Some` with `prim == u32::MAX` when occluded.
    Any,
}

/// A built structure, ready to trace.
pub trait Traceable: Send + Sync {
    /// [`Accel::memory_bytes`].
    fn memory_bytes(&self) -> usize;
    /// [`Accel::build_stats`].
    fn build_stats(&self) -> BuildStats;
    /// Answers for every ray, with counters, in parallel over the current rayon pool.
    fn trace_counted(&self, rays: &[Ray], query: Query) -> (Vec<Option<Hit>>, Counters);
    /// Traces every ray without counters and returns the number of hits (so the work cannot be
    /// optimized away). This is the timed path.
    fn trace_timed(&self, rays: &[Ray], query: Query) -> usize;
    /// One ray, for re-checking a disagreement.
    fn answer(&self, ray: &Ray, query: Query) -> Option<Hit>;
    /// One ray, with the events it caused (for the conformance kit, through [`crate::grade`]).
    fn answer_counted(&self, ray: &Ray, query: Query) -> (Option<Hit>, Counters);
    /// One ray with every step of its walk recorded (for `explain`).
    fn trace(&self, ray: &Ray, query: Query) -> (Option<Hit>, Trace);
    /// Every node or cell ([`Accel::regions`]), for `draw`.
    fn regions(&self) -> Vec<Region>;
    /// [`Accel::bounds`].
    fn bounds(&self) -> Aabb;
    /// [`Accel::ball_query`] for a query known only as a trait object, counting into `counters`.
    fn ball_query_dyn(&self, query: &mut dyn BallQuery<Triangle>, counters: &mut Counters);
    /// The closest point for every `(point, maximum distance)`, with counters, in parallel over
    /// the current rayon pool.
    fn closest_counted(&self, points: &[(Vec3, f32)]) -> (Vec<Option<PointHit>>, Counters);
    /// The closest points without counters; returns how many were found. The timed path.
    fn closest_timed(&self, points: &[(Vec3, f32)]) -> usize;
}

/// A built structure that can also follow its triangles when they move ([`Refit`]).
pub trait Refittable: Traceable {
    /// [`Refit::refit`] to `tris`.
    ///
    /// # Errors
    /// As [`Refit::refit`]: the structure is then unchanged.
    fn refit(&mut self, tris: &[Triangle]) -> Result<(), RefitError>;
}

struct Built<A>(A);

impl<A: Refit<Prim = Triangle>> Refittable for Built<A> {
    fn refit(&mut self, tris: &[Triangle]) -> Result<(), RefitError> {
        self.0.refit(tris)
    }
}

const CHUNK: usize = 256;
const OCCLUDED: Hit = Hit {
    prim: u32::MAX,
    t: f32::NAN,
    u: 0.0,
    v: 0.0,
};

/// Answers `items` in parallel chunks over the current rayon pool, each chunk counting into its
/// own [`Counters`], and the counters summed: the counted pass of every row.
fn answer_all<T: Sync, A: Send + Clone + Default>(
    items: &[T],
    answer: impl Fn(&T, &mut Counters) -> A + Sync,
) -> (Vec<A>, Counters) {
    let mut answers = vec![A::default(); items.len()];
    let counters = answers
        .par_chunks_mut(CHUNK)
        .zip(items.par_chunks(CHUNK))
        .map(|(out, items)| {
            let mut c = Counters::default();
            for (o, item) in out.iter_mut().zip(items) {
                *o = answer(item, &mut c);
            }
            c
        })
        .reduce(Counters::default, Counters::merged);
    (answers, counters)
}

impl<A: Accel<Prim = Triangle>> Built<A> {
    /// One query with a fresh sink of type `S`, and the sink.
    fn ask<S: Stats + Default>(&self, ray: &Ray, query: Query) -> (Option<Hit>, S) {
        let mut stats = S::default();
        let answer = match query {
            Query::Closest => self.0.intersect_with(ray, &mut stats),
            Query::Any => self.0.occluded_with(ray, &mut stats).then_some(OCCLUDED),
        };
        (answer, stats)
    }
}

impl<A: Accel<Prim = Triangle>> Traceable for Built<A> {
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }

    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }

    fn trace_counted(&self, rays: &[Ray], query: Query) -> (Vec<Option<Hit>>, Counters) {
        answer_all(rays, |r, c| match query {
            Query::Closest => self.0.intersect_with(r, c),
            Query::Any => self.0.occluded_with(r, c).then_some(OCCLUDED),
        })
    }

    fn trace_timed(&self, rays: &[Ray], query: Query) -> usize {
        rays.par_chunks(CHUNK)
            .map(|rays| match query {
                Query::Closest => rays
                    .iter()
                    .filter(|r| self.0.intersect(r).is_some())
                    .count(),
                Query::Any => rays.iter().filter(|r| self.0.occluded(r)).count(),
            })
            .sum()
    }

    fn regions(&self) -> Vec<Region> {
        let mut out = Vec::new();
        self.0.regions(&mut |r| out.push(r));
        out
    }

    fn answer(&self, ray: &Ray, query: Query) -> Option<Hit> {
        match query {
            Query::Closest => self.0.intersect(ray),
            Query::Any => self.0.occluded(ray).then_some(OCCLUDED),
        }
    }

    fn answer_counted(&self, ray: &Ray, query: Query) -> (Option<Hit>, Counters) {
        self.ask(ray, query)
    }

    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }

    fn ball_query_dyn(&self, mut query: &mut dyn BallQuery<Triangle>, counters: &mut Counters) {
        self.0.ball_query(&mut query, counters);
    }

    fn closest_counted(&self, points: &[(Vec3, f32)]) -> (Vec<Option<PointHit>>, Counters) {
        answer_all(points, |&(p, max), c| self.0.closest_point_with(p, max, c))
    }

    fn closest_timed(&self, points: &[(Vec3, f32)]) -> usize {
        points
            .par_chunks(CHUNK)
            .map(|points| {
                points
                    .iter()
                    .filter(|&&(p, max)| self.0.closest_point(p, max).is_some())
                    .count()
            })
            .sum()
    }

    fn trace(&self, ray: &Ray, query: Query) -> (Option<Hit>, Trace) {
        self.ask(ray, query)
    }
}

/// Builds one row's structure over a scene.
pub type Builder = Arc<dyn Fn(&[Triangle]) -> Box<dyn Traceable> + Send + Sync>;

/// Builds one row's structure over a scene as one that can refit (`animate`).
pub type RefitBuilder = Arc<dyn Fn(&[Triangle]) -> Box<dyn Refittable> + Send + Sync>;

/// Builds one row's structure over a mesh as the bottom level of instances (`compare
/// --instances`).
pub type BottomBuilder = Arc<dyn Fn(&[Triangle]) -> Arc<dyn Bottom<Triangle>> + Send + Sync>;

/// Builds one row's structure over triangles and spheres, for `render`.
pub type ShapeBuilder = Arc<dyn Fn(&[Shape]) -> Box<dyn Tracer> + Send + Sync>;

/// One row a shootout can run: a structure type with one preset.
#[derive(Clone)]
pub struct Entry {
    /// Row name: the structure's [`Accel::NAME`] for its first preset, `NAME-preset` otherwise.
    pub name: String,
    /// Builds it over triangles.
    pub build: Builder,
    /// Builds the same over one mesh, to be shared by instances.
    pub build_bottom: BottomBuilder,
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
            let for_bottom = params.clone();
            Entry {
                name: row_name::<A>(i, preset),
                build: Arc::new(move |tris: &[Triangle]| {
                    Box::new(Built(A::build(tris, &params))) as Box<dyn Traceable>
                }),
                build_bottom: Arc::new(move |tris: &[Triangle]| {
                    Arc::new(A::build(tris, &for_bottom)) as Arc<dyn Bottom<Triangle>>
                }),
                build_shapes: Some(Arc::new(move |shapes: &[Shape]| {
                    Box::new(S::build(shapes, &for_shapes)) as Box<dyn Tracer>
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
        .map(|(i, (preset, params))| {
            let for_bottom = params.clone();
            Entry {
                name: row_name::<A>(i, preset),
                build: Arc::new(move |tris: &[Triangle]| {
                    Box::new(Built(A::build(tris, &params))) as Box<dyn Traceable>
                }),
                build_bottom: Arc::new(move |tris: &[Triangle]| {
                    Arc::new(A::build(tris, &for_bottom)) as Arc<dyn Bottom<Triangle>>
                }),
                build_shapes: None,
                build_refittable: None,
            }
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
                Box::new(Built(A::build(tris, &params))) as Box<dyn Refittable>
            }));
            entry
        })
        .collect()
}

/// The default preset of one structure type.
#[cfg(test)]
pub fn entry_of<A, S>() -> Entry
where
    A: Accel<Prim = Triangle> + 'static,
    S: Accel<Prim = Shape, Params = A::Params> + 'static,
{
    entries_of::<A, S>().remove(0)
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

/// The brute-force reference.
pub fn brute_force() -> Entry {
    entries_of::<BruteForce<Triangle>, BruteForce<Shape>>().remove(0)
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
        bottom: &BottomBuilder,
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

    fn flat(&self, h: rt_core::InstanceHit) -> Hit {
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

    fn point(&self, p: Vec3, max: f32, c: &mut Counters) -> Option<PointHit> {
        self.scene.closest_point_with(p, max, c).map(|h| PointHit {
            prim: h.instance * self.mesh.len() as u32 + h.prim,
            point: h.point,
            distance: h.distance,
        })
    }
}

impl<T: TwoLevel<Triangle>> Traceable for Field<T> {
    fn memory_bytes(&self) -> usize {
        self.scene.memory_bytes()
    }

    /// The bottom level's shape, with the number of instances among the named figures.
    fn build_stats(&self) -> BuildStats {
        let instances = self.scene.instances();
        let mut stats = instances
            .first()
            .map(|i| i.bottom().build_stats())
            .unwrap_or_default();
        stats.extra.push(("instances", instances.len() as f64));
        stats
    }

    fn trace_counted(&self, rays: &[Ray], query: Query) -> (Vec<Option<Hit>>, Counters) {
        answer_all(rays, |r, c| self.ask(r, query, c))
    }

    fn trace_timed(&self, rays: &[Ray], query: Query) -> usize {
        rays.par_chunks(CHUNK)
            .map(|rays| match query {
                Query::Closest => rays
                    .iter()
                    .filter(|r| self.scene.intersect(r).is_some())
                    .count(),
                Query::Any => rays.iter().filter(|r| self.scene.occluded(r)).count(),
            })
            .sum()
    }

    fn answer(&self, ray: &Ray, query: Query) -> Option<Hit> {
        self.ask(ray, query, &mut rt_core::NoStats)
    }

    fn answer_counted(&self, ray: &Ray, query: Query) -> (Option<Hit>, Counters) {
        let mut c = Counters::default();
        (self.ask(ray, query, &mut c), c)
    }

    /// Counts only: the two-level walk reports no steps.
    fn trace(&self, ray: &Ray, query: Query) -> (Option<Hit>, Trace) {
        let mut t = Trace::default();
        (self.ask(ray, query, &mut t), t)
    }

    /// None: a field is drawn as its instances, which `draw` does not do.
    fn regions(&self) -> Vec<Region> {
        Vec::new()
    }

    fn bounds(&self) -> Aabb {
        self.scene.bounds()
    }

    /// Offers every world-space triangle of every instance whose box the ball reaches (the
    /// flattened scene, as brute force would), numbered as hits are.
    fn ball_query_dyn(&self, query: &mut dyn BallQuery<Triangle>, counters: &mut Counters) {
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

    fn closest_counted(&self, points: &[(Vec3, f32)]) -> (Vec<Option<PointHit>>, Counters) {
        answer_all(points, |&(p, max), c| self.point(p, max, c))
    }

    fn closest_timed(&self, points: &[(Vec3, f32)]) -> usize {
        points
            .par_chunks(CHUNK)
            .map(|points| {
                points
                    .iter()
                    .filter(|&&(p, max)| self.scene.closest_point(p, max).is_some())
                    .count()
            })
            .sum()
    }
}

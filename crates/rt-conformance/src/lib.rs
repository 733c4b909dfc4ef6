//! The conformance kit: checks that an [`Accel`] implementation answers exactly like
//! [`BruteForce`], on fixed adversarial scenes and on proptest-generated random scenes and rays.
//!
//! A structure crate takes this crate as a dev-dependency (a student's lab, as a dependency) and
//! writes one line per preset in a test file:
//!
//! ```
//! // In a structure crate this reads, e.g.:
//! // rt_conformance::conformance_tests!(sah, rt_bvh::Bvh<rt_core::Triangle>, rt_bvh::BvhParams::sah());
//! rt_conformance::conformance_tests!(reference, rt_core::BruteForce<rt_core::Triangle>, ());
//! ```
//!
//! That expands to a module `sah` with one `#[test]` per adversarial scene plus a proptest run,
//! so a failure names the scene. Each failure message prints the offending ray as Rust source
//! (and the scene, when it is small) so it can be pasted into a regression test.
//!
//! "Answers exactly like brute force" means: for every ray, the same primitive index (ties broken
//! by smallest `t`, then smallest index), `t` within a relative 1e-5, and the same occlusion
//! answer; for every closest-point query ([`scene_points`]: points on, near and far from the
//! primitives, with and without a maximum distance), the same primitive and a distance within a
//! relative 1e-5 ([`PointHit::agree`]); for every box overlap query ([`scene_boxes`]: boxes
//! that touch primitives, flat and point boxes on their vertices' planes, boxes at random, and
//! boxes that meet nothing), the same list of primitives ([`compare_boxes`]); for all hits,
//! hit counts and filtered queries, the hits of the primitives tested one by one
//! ([`compare_hits`]); for signed distance and crossing parity at up to 64 of those points, brute
//! force's closest point with the exact winding number's sign, and brute force's parity
//! ([`compare_inside`]); the answer must not change when statistics are counted;
//! and the structure must report the number of valid primitives it kept. The bundle queries
//! ([`Accel::intersect_bundle`], [`Accel::occluded_bundle`]) must give, ray for ray, the same
//! bits as the single queries, whatever bundles the rays come in ([`compare_bundles`]), and so
//! must the stream queries ([`Accel::intersect_stream`], [`Accel::occluded_stream`]) in any
//! order and at any length ([`compare_streams`]), and every batch query ([`rt_core::batch`], [`rt_sdf::batch`]), slot for slot, on threads
//! other than the one that built the structure ([`compare_batches`]; on the fixed scenes, whose
//! hundreds of rays fill several chunks of a batch).
//!
//! The number of proptest cases is proptest's default (256) unless `PROPTEST_CASES` is set.
//!
//! The kit never hangs: every case runs on a thread of its own under a watchdog, and a build or
//! a query that does not return within [`STALL_LIMIT`], or that panics, fails the case with the
//! ray it was on (see [`check_case`]).
//!
//! The checks come in parts ([`Part`]: closest hit, any hit, bundles, closest points, box
//! overlap, all hits, inside); [`check_part`] and [`check_random_part`] run one part alone, so
//! that a grade (`--grade` in the shootout) can show a structure's closest hit passing while its
//! any hit is not written yet.

use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use rt_core::trace::{Event, Outcome, Trace};
use rt_core::{
    Accel, BruteForce, ClosestPointQuery, Counters, DynAccel, Hit, PointHit, Primitive, Ray, Rng,
    Sphere, Triangle,
};
use std::fmt;

/// Re-exported for [`conformance_tests!`], so the macro's expansion names rt-core's items
/// without the calling crate depending on rt-core under that name.
#[doc(hidden)]
pub use rt_core;

mod batches;
mod boxes;
mod bundles;
mod hits;
mod inside;
mod instances;
mod refit;
mod saved;
mod streams;
pub use batches::compare_batches;
pub use boxes::{BoxMismatch, compare_boxes, scene_boxes};
pub use bundles::{
    BUNDLE_SIZES, bundle_orders, check_coherent_bundles, check_coherent_bundles_on,
    compare_bundles, same_bits,
};
pub use hits::{FILTERS, Filter, HitsMismatch, compare_hits, hits_one_by_one};
pub use inside::{InsideMismatch, SIGN_MARGIN, compare_inside};
pub use instances::{
    BottomBuilder, InstancedCase, Placement, TWO_LEVEL_SCENES, check_two_level_case,
    check_two_level_random, check_two_level_scene, two_level_scene,
};
pub use refit::{check_refit_case, check_refit_random, check_refit_scenes};
pub use saved::{
    DAMAGES, TRUNCATIONS, check_damaged, check_saved_case, check_saved_scenes, compare_saved,
};
pub use streams::{LONG_STREAM, STREAM_SIZES, compare_streams};

/// A disagreement between a structure and brute force on one ray.
#[derive(Clone, Debug)]
pub struct Mismatch {
    /// Which query disagreed: `"intersect"`, `"occluded"` or `"intersect_with(Counters)"`.
    pub query: &'static str,
    /// The ray.
    pub ray: Ray,
    /// What brute force answered (for `occluded`, `Some` means occluded).
    pub expected: Option<Hit>,
    /// What the structure answered.
    pub got: Option<Hit>,
    /// More about the failure, when there is more to say (else empty).
    pub detail: Box<str>,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} disagrees with brute force\n  ray: {}\n  rays-file line: {}\n  expected: {:?}\n  got:      {:?}",
            self.query,
            self.ray.to_rust(),
            self.ray.to_line(),
            self.expected,
            self.got
        )?;
        if !self.detail.is_empty() {
            write!(f, "\n  {}", self.detail)?;
        }
        Ok(())
    }
}

/// Compares `accel` with `reference` on every valid ray (see [`Ray::is_valid`]), returning the
/// first disagreement. Invalid rays are traced too, and must return at once: no hit, no
/// primitive test, at most one node visit per query.
///
/// # Errors
/// The first [`Mismatch`].
pub fn compare_rays<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    rays: &[Ray],
) -> Result<(), Mismatch> {
    compare_rays_probed(accel, reference, rays, &Probe::default(), true, true)
}

/// [`compare_rays`], telling `probe` which ray each query is about before making it; `closest`
/// and `any` say which of the two queries to check.
fn compare_rays_probed<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    rays: &[Ray],
    probe: &Probe,
    closest: bool,
    any: bool,
) -> Result<(), Mismatch> {
    for ray in rays {
        probe.tracing(ray);
        if !ray.is_valid() {
            // Outside the trait's precondition: the structure must answer at once, with no hit,
            // no primitive test and at most the root visited by each query (a NaN direction or
            // an origin at 10³⁰ must not walk the whole tree).
            let mut c = Counters::default();
            let hit = if closest {
                accel.intersect_with(ray, &mut c)
            } else {
                None
            };
            let occluded = any && accel.occluded_with(ray, &mut c);
            if hit.is_some() || occluded || c.prim_tests > 0 || c.node_visits > 2 {
                return Err(Mismatch {
                    query: "invalid ray",
                    ray: *ray,
                    expected: None,
                    got: hit,
                    detail: format!(
                        "must return at once; got a hit: {}, occluded: {occluded}, {} node visits \
                         and {} primitive tests over both queries",
                        hit.is_some(),
                        c.node_visits,
                        c.prim_tests
                    )
                    .into(),
                });
            }
            continue;
        }
        let expected = reference.intersect(ray);
        if closest {
            check_closest(accel, ray, expected)?;
        }
        if !any {
            continue;
        }
        let occluded = accel.occluded(ray);
        if occluded != expected.is_some() {
            let as_hit = |b: bool| {
                b.then_some(Hit {
                    prim: u32::MAX,
                    t: f32::NAN,
                    u: 0.0,
                    v: 0.0,
                })
            };
            return Err(Mismatch {
                query: "occluded",
                ray: *ray,
                expected: as_hit(expected.is_some()),
                got: as_hit(occluded),
                detail: Box::default(),
            });
        }
    }
    Ok(())
}

/// Checks the closest hit of one valid ray against brute force's `expected`: plain, counted
/// and traced.
fn check_closest<A: Accel>(accel: &A, ray: &Ray, expected: Option<Hit>) -> Result<(), Mismatch> {
    let got = accel.intersect(ray);
    if !Hit::agree(expected, got) {
        return Err(Mismatch {
            query: "intersect",
            ray: *ray,
            expected,
            got,
            detail: Box::default(),
        });
    }
    let mut counters = Counters::default();
    let counted = accel.intersect_with(ray, &mut counters);
    if !Hit::agree(got, counted) {
        return Err(Mismatch {
            query: "intersect_with(Counters)",
            ray: *ray,
            expected: got,
            got: counted,
            detail: Box::default(),
        });
    }
    let mut trace = Trace::default();
    let traced = accel.intersect_with(ray, &mut trace);
    if let Err(why) = trace_agrees(&trace, counters, traced) {
        return Err(Mismatch {
            query: "intersect_with(Trace)",
            ray: *ray,
            expected: got,
            got: traced,
            detail: why.into(),
        });
    }
    Ok(())
}

/// A disagreement between a structure and brute force on one closest-point query.
#[derive(Clone, Debug)]
pub struct PointMismatch {
    /// The query point.
    pub point: Vec3,
    /// The query's maximum distance.
    pub max_distance: f32,
    /// What brute force answered.
    pub expected: Option<PointHit>,
    /// What the structure answered.
    pub got: Option<PointHit>,
    /// More about the failure, when there is more to say (else empty).
    pub detail: Box<str>,
}

impl fmt::Display for PointMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.point;
        write!(
            f,
            "closest_point disagrees with brute force\n  query: closest_point(Vec3::new({:?}, {:?}, {:?}), {:?})\n  expected: {:?}\n  got:      {:?}",
            p.x, p.y, p.z, self.max_distance, self.expected, self.got
        )?;
        if !self.detail.is_empty() {
            write!(f, "\n  {}", self.detail)?;
        }
        Ok(())
    }
}

/// Compares `accel`'s closest-point answers with `reference`'s for every `(point, maximum
/// distance)`, counted and uncounted. An invalid query (see
/// [`ClosestPointQuery::new`](rt_core::ClosestPointQuery::new)) must return at once: nothing
/// found, no primitive test, at most one node visit.
///
/// # Errors
/// The first [`PointMismatch`].
pub fn compare_points<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    points: &[(Vec3, f32)],
) -> Result<(), PointMismatch> {
    compare_points_probed(accel, reference, points, &Probe::default()).map(drop)
}

fn compare_points_probed<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    points: &[(Vec3, f32)],
    probe: &Probe,
) -> Result<Vec<Option<PointHit>>, PointMismatch> {
    let mut answers = Vec::with_capacity(points.len());
    for &(point, max_distance) in points {
        probe.set(Doing::Point(point, max_distance));
        let mismatch = |expected, got, detail: String| PointMismatch {
            point,
            max_distance,
            expected,
            got,
            detail: detail.into(),
        };
        let valid = point.is_finite()
            && point.abs().max_element() <= Ray::MAX_ORIGIN
            && max_distance >= 0.0;
        let mut c = Counters::default();
        let counted = accel.closest_point_with(point, max_distance, &mut c);
        if !valid {
            if counted.is_some() || c.prim_tests > 0 || c.node_visits > 1 {
                return Err(mismatch(
                    None,
                    counted,
                    format!(
                        "an invalid query must return at once; got {} node visits and {} \
                         primitive tests",
                        c.node_visits, c.prim_tests
                    ),
                ));
            }
            answers.push(counted);
            continue;
        }
        let expected = reference.closest_point(point, max_distance);
        let got = accel.closest_point(point, max_distance);
        if !PointHit::agree(expected, got) {
            return Err(mismatch(expected, got, String::new()));
        }
        if counted != got {
            return Err(mismatch(
                got,
                counted,
                "closest_point_with(Counters) answers differently from closest_point".into(),
            ));
        }
        answers.push(got);
    }
    Ok(answers)
}

/// Closest-point queries probing `prims` as the kit runs them, drawn from the scene itself so a
/// fixed scene needs no points of its own. For each ray origin: no limit, a limit just below
/// brute force's answer (nothing may be found) and exactly at it (the answer must be found).
/// For up to 64 primitives: their centroid, their own nearest points to the first rays' origins
/// (on the surface: vertices, edge points and face points), those points pushed off the
/// surface, and the points of them farthest out along the axes (vertices, for triangles).
/// Then points far outside the scene, and invalid ones (NaN, beyond
/// [`Ray::MAX_ORIGIN`], a negative limit).
pub fn scene_points<P: Primitive>(prims: &[P], rays: &[Ray]) -> Vec<(Vec3, f32)> {
    let reference = BruteForce::build(prims, &());
    let bounds = reference.bounds();
    let mut points = Vec::new();
    let add_limited = |points: &mut Vec<(Vec3, f32)>, p: Vec3| {
        points.push((p, f32::INFINITY));
        if let Some(h) = reference.closest_point(p, f32::INFINITY) {
            points.push((p, h.distance));
            if h.distance > 0.0 {
                points.push((p, h.distance * 0.999));
            }
        }
    };
    for ray in rays.iter().filter(|r| r.origin.is_finite()).take(64) {
        add_limited(&mut points, ray.origin);
    }
    let size = bounds.extent().max_element().max(1.0);
    let far = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    for prim in prims.iter().filter(|p| p.is_valid()).take(64) {
        points.push((prim.centroid(), f32::INFINITY));
        for ray in rays.iter().filter(|r| r.origin.is_finite()).take(3) {
            let on = prim.closest_point(ray.origin);
            points.push((on, f32::INFINITY));
            points.push((on, 0.0));
            add_limited(&mut points, on + (on - ray.origin) * 1e-3);
        }
        for d in far {
            points.push((prim.closest_point(prim.centroid() + d * size * 100.0), 0.0));
        }
    }
    if !bounds.is_empty() {
        let c = bounds.center();
        for d in far {
            add_limited(&mut points, c + d * size * 1000.0);
            points.push((c + d * 1e6, f32::INFINITY));
        }
        points.push((bounds.min, f32::INFINITY));
        points.push((bounds.max, f32::INFINITY));
    }
    points.retain(|(p, _)| p.abs().max_element() <= Ray::MAX_ORIGIN);
    points.extend([
        (Vec3::new(f32::NAN, 0.0, 0.0), f32::INFINITY),
        (Vec3::splat(4.0 * Ray::MAX_ORIGIN), f32::INFINITY),
        (Vec3::ZERO, -1.0),
        (Vec3::ZERO, f32::NAN),
    ]);
    points
}

/// Whether a traced walk matches the counted one: the same answer and counts and, if the
/// structure reports events at all, one `Enter` per node visit, one `Test` per primitive test,
/// one `Skip` per mailbox skip, and a `Test` that found the answer's primitive at its `t`.
fn trace_agrees(trace: &Trace, counters: Counters, traced: Option<Hit>) -> Result<(), String> {
    if trace.counters != counters {
        return Err(format!(
            "a traced walk counted {:?}, an untraced one {counters:?}",
            trace.counters
        ));
    }
    if trace.events.is_empty() {
        return Ok(());
    }
    let count = |f: fn(&Event) -> bool| trace.events.iter().filter(|e| f(e)).count() as u64;
    let enters = count(|e| matches!(e, Event::Enter { .. }));
    let tests = count(|e| matches!(e, Event::Test { .. }));
    let skips = count(|e| matches!(e, Event::Skip { .. }));
    if (enters, tests, skips)
        != (
            counters.node_visits,
            counters.prim_tests,
            counters.mailbox_skips,
        )
    {
        return Err(format!(
            "the trace reports {enters} enters, {tests} tests and {skips} mailbox skips; the \
             counters {counters:?}"
        ));
    }
    if let Some(hit) = traced {
        let found = trace.events.iter().any(|e| {
            matches!(*e, Event::Test { prim, outcome: Outcome::Hit(t) }
                if prim == hit.prim && t == hit.t)
        });
        if !found {
            return Err(format!(
                "no traced test of primitive {} found its hit at t = {}",
                hit.prim, hit.t
            ));
        }
    }
    Ok(())
}

/// Builds `A` and brute force over `prims` and compares them on `rays`; also checks that the
/// structure reports the number of valid primitives it kept. Returns a message describing the
/// first failure.
///
/// The work runs on a thread of its own under a watchdog ([`check_case_within`] with
/// [`STALL_LIMIT`]): a build or a query that does not return within the limit, or that panics,
/// becomes a failure naming what it was doing: the build, or the ray (as Rust and as a
/// rays-file line) and the query. A structure that loops forever on one ray therefore fails
/// instead of hanging the test run (its thread is left spinning until the process exits).
///
/// # Errors
/// A description of the first failure, with the scene when it has at most 12 primitives.
pub fn check_case<A: Accel + 'static>(
    params: &A::Params,
    prims: &[A::Prim],
    rays: &[Ray],
) -> Result<(), String> {
    check_case_within::<A>(params, prims, rays, STALL_LIMIT)
}

/// How long the kit waits for one build or one query before it calls the structure stuck: 20
/// seconds, a hundred times what the slowest build of the kit's scenes takes in a debug build.
pub const STALL_LIMIT: std::time::Duration = std::time::Duration::from_secs(20);

/// [`check_case`] with another limit for one build or one query.
///
/// # Errors
/// As [`check_case`].
pub fn check_case_within<A: Accel + 'static>(
    params: &A::Params,
    prims: &[A::Prim],
    rays: &[Ray],
    stall: std::time::Duration,
) -> Result<(), String> {
    check_parts::<A>(params, prims, rays, stall, &Part::ALL, true, true)
}

/// One part of what [`check_case`] checks. Grading reports the parts apart, so that a structure
/// whose any-hit query is not written yet still shows which closest-hit checks pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Part {
    /// The closest hit ([`Accel::intersect`], also counted and traced), invalid rays answered
    /// at once, and the build's reports ([`Accel::build_stats`] `valid_prims`, [`check_regions`]).
    Closest,
    /// The any hit ([`Accel::occluded`]), invalid rays answered at once.
    Any,
    /// The bundle queries give the single queries' bits ([`compare_bundles`]), and so do the
    /// stream queries ([`compare_streams`]) and the ray batches. (Each other part checks its
    /// query's batch too: [`compare_batches`].)
    Bundles,
    /// Closest points ([`compare_points`]).
    ClosestPoints,
    /// Box overlap ([`compare_boxes`]).
    BoxOverlap,
    /// All hits, hit counts and filtered queries ([`compare_hits`]).
    AllHits,
    /// Signed distance and crossing parity ([`compare_inside`]).
    Inside,
}

impl Part {
    /// Every part, in the order [`check_case`] checks them.
    pub const ALL: [Part; 7] = [
        Part::Closest,
        Part::Any,
        Part::Bundles,
        Part::ClosestPoints,
        Part::BoxOverlap,
        Part::AllHits,
        Part::Inside,
    ];

    /// The part's name, as grading reports it: `closest-hit`, `any-hit`, `bundles`,
    /// `closest-points`, `box-overlap`, `all-hits` or `inside`.
    pub fn name(self) -> &'static str {
        match self {
            Part::Closest => "closest-hit",
            Part::Any => "any-hit",
            Part::Bundles => "bundles",
            Part::ClosestPoints => "closest-points",
            Part::BoxOverlap => "box-overlap",
            Part::AllHits => "all-hits",
            Part::Inside => "inside",
        }
    }

    /// The part called `name` (see [`Part::name`]).
    pub fn from_name(name: &str) -> Option<Part> {
        Part::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// [`check_case_within`] for one part only: the structure is built and checked on `rays` (or,
/// for the point and box parts, on the points and boxes [`scene_points`] and [`scene_boxes`]
/// make from them) under the same watchdog.
///
/// # Errors
/// As [`check_case`].
pub fn check_part<A: Accel + 'static>(
    params: &A::Params,
    prims: &[A::Prim],
    rays: &[Ray],
    part: Part,
    stall: std::time::Duration,
) -> Result<(), String> {
    check_parts::<A>(params, prims, rays, stall, &[part], true, true)
}

/// Checks `parts` of [`check_case_within`]; with `bundles_any` false, the bundle part checks the
/// closest-hit bundles only; with `batches` false, no part checks its batches (random cases:
/// a few rays and points each, which the fixed scenes' batches cover).
fn check_parts<A: Accel + 'static>(
    params: &A::Params,
    prims: &[A::Prim],
    rays: &[Ray],
    stall: std::time::Duration,
    parts: &[Part],
    bundles_any: bool,
    batches: bool,
) -> Result<(), String> {
    let (params, prims, rays) = (params.clone(), prims.to_vec(), rays.to_vec());
    let parts = parts.to_vec();
    let scene = scene_summary(&prims);
    watched(A::NAME, stall, &scene, move |probe| {
        let has = |p: Part| parts.contains(&p);
        probe.building(prims.len());
        let reference = BruteForce::build(&prims, &());
        let accel = A::build(&prims, &params);
        let scene = || scene_summary(&prims);
        let failed =
            |m: &dyn fmt::Display| format!("{} with {:?}: {m}{}", A::NAME, params, scene());
        if has(Part::Closest) {
            probe.checking();
            let valid = prims.iter().filter(|p| p.is_valid()).count();
            let kept = accel.build_stats().valid_prims;
            if kept != valid {
                return Err(format!(
                    "{}: build_stats().valid_prims is {kept}, but {valid} primitives are valid{}",
                    A::NAME,
                    scene()
                ));
            }
            check_regions(&accel).map_err(|m| failed(&m))?;
        }
        if has(Part::Closest) || has(Part::Any) {
            compare_rays_probed(
                &accel,
                &reference,
                &rays,
                probe,
                has(Part::Closest),
                has(Part::Any),
            )
            .map_err(|m| failed(&m))?;
        }
        // The points of the closest-point part, which the inside part samples too.
        let points = if has(Part::ClosestPoints) || has(Part::Inside) {
            scene_points(&prims, &rays)
        } else {
            Vec::new()
        };
        // The batches of each part, checked against the part's single answers at the end, on
        // the kit's pool, all in one visit.
        let mut later: Vec<batches::Check<'_>> = Vec::new();
        let accel = &accel;
        if has(Part::Bundles) {
            // The bundle queries must give the single queries' answers.
            let single = bundles::compare_bundles_probed(accel, &rays, bundles_any, probe)
                .map_err(|m| failed(&m))?;
            // And the stream queries, in any order and at any length.
            streams::compare_streams_probed(accel, &rays, bundles_any, probe)
                .map_err(|m| failed(&m))?;
            // And so must the batches, on other threads.
            let rays = &rays;
            later.push(Box::new(move || batches::rays(accel, rays, &single, probe)));
        }
        if has(Part::ClosestPoints) {
            let single =
                compare_points_probed(accel, &reference, &points, probe).map_err(|m| failed(&m))?;
            let points = &points;
            later.push(Box::new(move || {
                batches::points(accel, points, &single, probe)
            }));
        }
        if has(Part::BoxOverlap) {
            let boxes = scene_boxes(&prims, prims.len() as u64);
            let single = boxes::compare_boxes_probed(accel, &reference, &boxes, probe)
                .map_err(|m| failed(&m))?;
            later.push(Box::new(move || {
                batches::boxes(accel, &boxes, &single, probe)
            }));
        }
        if has(Part::AllHits) {
            // Every ray of small cases, an even spread of at most `HITS_RAYS` of large ones: each
            // ray runs seven more walks here, most of them to the ray's end.
            let stride = rays.len().div_ceil(hits::HITS_RAYS).max(1);
            let some: Vec<Ray> = rays.iter().step_by(stride).copied().collect();
            hits::compare_hits_probed(accel, &prims, &some, probe).map_err(|m| failed(&m))?;
            let single = batches::single_hits(accel, &some);
            later.push(Box::new(move || {
                batches::hits(accel, &some, &single, probe)
            }));
        }
        if has(Part::Inside) {
            // Parity counts crossings with `count_hits`, which the all-hits part checks.
            let near = inside::some_points(&points);
            let tree = rt_sdf::WindingTree::build(&prims).ok();
            let single = inside::compare_inside_probed(
                accel,
                &reference,
                &prims,
                tree.as_ref(),
                &near,
                probe,
            )
            .map_err(|m| failed(&m))?;
            if let Some(tree) = tree {
                later.push(Box::new(move || {
                    batches::signed(accel, &tree, &near, &single, probe)
                }));
            }
        }
        if !batches {
            later.clear();
        }
        batches::on_pool(later).map_err(|m| failed(&m))
    })
}

/// The scene as failure messages show it: every primitive when there are at most 12.
fn scene_summary<P: Primitive>(prims: &[P]) -> String {
    if prims.len() <= 12 {
        format!("\n  scene: {prims:?}")
    } else {
        format!("\n  scene: {} primitives", prims.len())
    }
}

/// What the kit's worker thread is doing, for the watchdog: a counter that moves at every
/// step, and the current step. A query stores only its ray (a copy, no allocation); the text is
/// written only when the watchdog reports.
#[derive(Default)]
struct Probe {
    steps: std::sync::atomic::AtomicU64,
    doing: std::sync::Mutex<Doing>,
}

#[derive(Default)]
enum Doing {
    #[default]
    Starting,
    Phase(&'static str, usize),
    Tracing(Ray),
    Bundle(Ray, usize),
    Point(Vec3, f32),
    Inside(Vec3, f32),
    Box(rt_core::Aabb),
}

impl Probe {
    fn set(&self, doing: Doing) {
        if let Ok(mut d) = self.doing.lock() {
            *d = doing;
        }
        self.steps
            .fetch_add(1, std::sync::atomic::Ordering::Release);
    }
    fn building(&self, prims: usize) {
        self.set(Doing::Phase("building over", prims));
    }
    fn checking(&self) {
        self.set(Doing::Phase("checking build_stats() and regions()", 0));
    }
    fn tracing(&self, ray: &Ray) {
        self.set(Doing::Tracing(*ray));
    }
    fn bundle(&self, first: &Ray, len: usize) {
        self.set(Doing::Bundle(*first, len));
    }
    fn doing(&self) -> String {
        match self.doing.lock().as_deref() {
            Ok(Doing::Starting) | Err(_) => "starting".into(),
            Ok(Doing::Phase(what, 0)) => (*what).into(),
            Ok(Doing::Phase(what, n)) => format!("{what} {n} primitives"),
            Ok(Doing::Tracing(ray)) => {
                format!("ray {}\n  rays-file line: {}", ray.to_rust(), ray.to_line())
            }
            Ok(Doing::Bundle(ray, len)) => format!(
                "a bundle query of {len} rays, the first {}\n  rays-file line: {}",
                ray.to_rust(),
                ray.to_line()
            ),
            Ok(Doing::Box(b)) => format!(
                "overlapping(&Aabb::new(Vec3::new({:?}, {:?}, {:?}), Vec3::new({:?}, {:?}, {:?})))",
                b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
            ),
            Ok(Doing::Point(p, max)) => format!(
                "closest_point(Vec3::new({:?}, {:?}, {:?}), {max:?})",
                p.x, p.y, p.z
            ),
            Ok(Doing::Inside(p, max)) => format!(
                "signed_distance and inside_by_parity at Vec3::new({:?}, {:?}, {:?}) within {max:?}",
                p.x, p.y, p.z
            ),
        }
    }
}

/// Runs `work` on its own thread and waits for it; a step (see [`Probe`]) that takes longer
/// than `stall`, or a panic, becomes an error naming what the worker was doing.
fn watched(
    name: &'static str,
    stall: std::time::Duration,
    scene: &str,
    work: impl FnOnce(&Probe) -> Result<(), String> + Send + 'static,
) -> Result<(), String> {
    use std::sync::atomic::Ordering;
    let probe = std::sync::Arc::new(Probe::default());
    let (tx, rx) = std::sync::mpsc::channel();
    let worker_probe = probe.clone();
    let spawned = std::thread::Builder::new()
        .name(format!("conformance {}", name))
        .spawn(move || {
            let result =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(&worker_probe)));
            let _ = tx.send(result);
        });
    if let Err(e) = spawned {
        return Err(format!("cannot start the kit's worker thread: {e}"));
    }
    let mut last = (
        probe.steps.load(Ordering::Acquire),
        std::time::Instant::now(),
    );
    loop {
        match rx.recv_timeout(std::time::Duration::from_millis(50)) {
            Ok(Ok(result)) => return result,
            Ok(Err(payload)) => {
                let message = payload
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic without a message".into());
                return Err(format!(
                    "{} panicked: {message}\n  while: {}{scene}",
                    name,
                    probe.doing()
                ));
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(format!("{}: the kit's worker thread vanished", name));
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                let steps = probe.steps.load(Ordering::Acquire);
                if steps != last.0 {
                    last = (steps, std::time::Instant::now());
                } else if last.1.elapsed() >= stall {
                    return Err(format!(
                        "{} {STALL_MARK} {:.0?} (a loop that never ends?)\n  while: {}{scene}",
                        name,
                        stall,
                        probe.doing()
                    ));
                }
            }
        }
    }
}

/// Checks what [`Accel::regions`] reports against [`Accel::build_stats`], for structures that
/// report regions at all: one region per node, one per leaf, the leaves' references summing to
/// `prim_refs`, and finite boxes.
///
/// # Errors
/// A sentence naming the first figure that does not match.
pub fn check_regions<A: Accel>(accel: &A) -> Result<(), String> {
    let (mut regions, mut leaves, mut refs, mut bad_box) = (0usize, 0usize, 0u64, None);
    accel.regions(&mut |r| {
        regions += 1;
        if let Some(n) = r.prims {
            leaves += 1;
            refs += n as u64;
        }
        if bad_box.is_none() && !(r.bounds.min.is_finite() && r.bounds.max.is_finite()) {
            bad_box = Some(r.bounds);
        }
    });
    if regions == 0 {
        return Ok(());
    }
    let stats = accel.build_stats();
    if let Some(b) = bad_box {
        return Err(format!("regions() reports a box that is not finite: {b:?}"));
    }
    if regions != stats.nodes || leaves != stats.leaves || refs != stats.prim_refs as u64 {
        return Err(format!(
            "regions() reports {regions} regions, {leaves} leaves and {refs} references, \
             build_stats() {} nodes, {} leaves and {} references",
            stats.nodes, stats.leaves, stats.prim_refs
        ));
    }
    Ok(())
}

/// A fixed adversarial scene: triangles and the rays that probe them.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Triangles, in primitive-index order.
    pub triangles: Vec<Triangle>,
    /// Rays to compare on.
    pub rays: Vec<Ray>,
}

/// Names of the fixed adversarial scenes, in the order [`scene`] knows them.
pub const SCENES: &[&str] = &[
    "empty_scene",
    "one_triangle",
    "shared_edge",
    "identical_triangles",
    "equal_centroids",
    "zero_area_triangles",
    "axis_parallel_rays",
    "rays_in_box_faces",
    "origins_inside",
    "large_coordinates",
    "nan_vertex",
    "exponential_chain",
    "far_origins",
    "planar_triangles",
    "spanning_triangles",
    "invalid_rays",
    "lattice",
    "closed_meshes",
];

/// The adversarial scene called `name` (one of [`SCENES`]).
///
/// # Panics
/// If `name` is not in [`SCENES`].
pub fn scene(name: &str) -> Scene {
    match name {
        "empty_scene" => Scene {
            triangles: vec![],
            rays: random_rays(&mut Rng::new(1), Vec3::splat(-1.0), Vec3::ONE, 64),
        },
        "one_triangle" => one_triangle(),
        "shared_edge" => shared_edge(),
        "identical_triangles" => identical_triangles(),
        "equal_centroids" => equal_centroids(),
        "zero_area_triangles" => zero_area_triangles(),
        "axis_parallel_rays" => axis_parallel_rays(),
        "rays_in_box_faces" => rays_in_box_faces(),
        "origins_inside" => origins_inside(),
        "large_coordinates" => large_coordinates(),
        "nan_vertex" => nan_vertex(),
        "planar_triangles" => planar_triangles(),
        "spanning_triangles" => spanning_triangles(),
        "invalid_rays" => invalid_rays(),
        "exponential_chain" => exponential_chain(),
        "far_origins" => far_origins(),
        "closed_meshes" => closed_meshes(),
        "lattice" => Scene {
            triangles: lattice_triangles(1, 60),
            rays: lattice_rays(1, 800),
        },
        _ => panic!("unknown conformance scene `{name}`; see rt_conformance::SCENES"),
    }
}

/// Checks structure `A` with `params` on the named adversarial scene.
///
/// # Panics
/// With a description of the first disagreement with brute force.
pub fn check_scene<A: Accel<Prim = Triangle> + 'static>(params: &A::Params, name: &str) {
    let s = scene(name);
    if let Err(e) = check_case::<A>(params, &s.triangles, &s.rays) {
        panic!("conformance scene `{name}` failed: {e}");
    }
    // The single queries agree with brute force; the slice queries must agree with them.
    let accel = A::build(&s.triangles, params);
    let points = scene_points(&s.triangles, &s.rays);
    if let Err(e) = compare_slices(&accel, &s.rays, &points) {
        panic!("conformance scene `{name}` failed: {e}");
    }
}

/// Checks that a structure's slice queries ([`DynAccel::intersect_all`],
/// [`occluded_all`](DynAccel::occluded_all) and
/// [`closest_points_all`](DynAccel::closest_points_all)) give, slot for slot, exactly its
/// single queries' answers, and count exactly the events the single queries count. The shootout
/// and batch callers use the slice queries, so a structure (or a wrapper) that implements them
/// itself must not answer differently there.
///
/// # Errors
/// The first slot or count that differs, with its ray or point.
pub fn compare_slices<P: Primitive>(
    accel: &dyn DynAccel<P>,
    rays: &[Ray],
    points: &[(Vec3, f32)],
) -> Result<(), String> {
    let name = accel.name();
    let (mut single, mut slices) = (Counters::default(), Counters::default());
    let mut hits = vec![None; rays.len()];
    accel.intersect_all(rays, &mut hits, Some(&mut slices));
    for (i, (r, got)) in rays.iter().zip(&hits).enumerate() {
        let expected = accel.intersect_dyn(r, Some(&mut single));
        if *got != expected {
            return Err(format!(
                "{name}: intersect_all slot {i} is {got:?}, intersect gives {expected:?}, for ray {}",
                r.to_rust()
            ));
        }
    }
    let mut blocked = vec![false; rays.len()];
    accel.occluded_all(rays, &mut blocked, Some(&mut slices));
    for (i, (r, &got)) in rays.iter().zip(&blocked).enumerate() {
        let expected = accel.occluded_dyn(r, Some(&mut single));
        if got != expected {
            return Err(format!(
                "{name}: occluded_all slot {i} is {got}, occluded gives {expected}, for ray {}",
                r.to_rust()
            ));
        }
    }
    let mut near = vec![None; points.len()];
    accel.closest_points_all(points, &mut near, Some(&mut slices));
    for (i, (&(p, max), got)) in points.iter().zip(&near).enumerate() {
        let mut q = ClosestPointQuery::new(p, max, &accel.bounds_dyn());
        accel.ball_query_dyn(&mut q, Some(&mut single));
        let expected = q.best();
        if *got != expected {
            return Err(format!(
                "{name}: closest_points_all slot {i} is {got:?}, closest_point gives {expected:?}, for the point {p:?} within {max}"
            ));
        }
    }
    if single != slices {
        return Err(format!(
            "{name}: the slice queries counted {slices:?}, the single queries {single:?}"
        ));
    }
    Ok(())
}

/// Checks only the closest-hit queries of structure `A` with `params` on the named scene, under
/// the same watchdog: for a structure whose any-hit query is not written yet, such as a lab's
/// template before its any-hit step. Invalid rays must still return at once.
///
/// # Panics
/// With a description of the first disagreement with brute force.
pub fn check_scene_closest<A: Accel<Prim = Triangle> + 'static>(params: &A::Params, name: &str) {
    let s = scene(name);
    let parts = [Part::Closest, Part::Bundles];
    if let Err(e) = check_parts::<A>(
        params,
        &s.triangles,
        &s.rays,
        STALL_LIMIT,
        &parts,
        false,
        true,
    ) {
        panic!("conformance scene `{name}` (closest hit) failed: {e}");
    }
}

/// The triangles as an indexed mesh whose bit-identical vertices are shared: what
/// [`check_geometry_sources`] builds from.
pub fn shared_vertex_mesh(tris: &[Triangle]) -> rt_core::Mesh {
    let mut index = std::collections::HashMap::new();
    let mut positions = Vec::new();
    let indices = tris
        .iter()
        .map(|t| {
            [t.v0, t.v1, t.v2].map(|v| {
                *index
                    .entry(v.to_array().map(f32::to_bits))
                    .or_insert_with(|| {
                        positions.push(v);
                        positions.len() as u32 - 1
                    })
            })
        })
        .collect();
    rt_core::Mesh::new(positions, indices).expect("every index names a vertex just pushed")
}

/// Checks that structure `A` built with [`Accel::build_from`] from a [`Mesh`](rt_core::Mesh) and
/// from an [`IndexedTriangles`](rt_core::IndexedTriangles) view answers every ray and point of
/// every adversarial scene exactly as when built from the triangle slice (same build stats, same
/// hits bit for bit), and so like brute force. The first 200 rays and points of each scene are
/// enough: the sources must give the same structure, which the full scene checks test already.
///
/// # Panics
/// At the first difference, naming the scene, the source and the query.
pub fn check_geometry_sources<A: Accel<Prim = Triangle> + 'static>(params: &A::Params) {
    let same_hit = |a: Option<Hit>, b: Option<Hit>| match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.prim == b.prim
                && [a.t, a.u, a.v].map(f32::to_bits) == [b.t, b.u, b.v].map(f32::to_bits)
        }
        _ => false,
    };
    for name in SCENES {
        let s = scene(name);
        let mesh = shared_vertex_mesh(&s.triangles);
        let bits = |t: &Triangle| [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits));
        assert!(
            mesh.triangles()
                .iter()
                .map(bits)
                .eq(s.triangles.iter().map(bits)),
            "scene `{name}`: the shared-vertex mesh does not rebuild the triangles"
        );
        let from_slice = A::build(&s.triangles, params);
        let rays = &s.rays[..s.rays.len().min(200)];
        let points = scene_points(&s.triangles, rays);
        let points = &points[..points.len().min(200)];
        for (source, accel) in [
            ("Mesh", A::build_from(&mesh, params)),
            ("IndexedTriangles", A::build_from(&mesh.view(), params)),
        ] {
            let fail = |what: String| -> ! {
                panic!(
                    "{} with {params:?} built from a {source} on scene `{name}`: {what}",
                    A::NAME
                )
            };
            if accel.build_stats() != from_slice.build_stats() {
                fail(format!(
                    "build stats {:?}, from the slice {:?}",
                    accel.build_stats(),
                    from_slice.build_stats()
                ));
            }
            for ray in rays {
                let (a, b) = (accel.intersect(ray), from_slice.intersect(ray));
                if !same_hit(a, b) {
                    fail(format!(
                        "{a:?}, from the slice {b:?}, for {}",
                        ray.to_rust()
                    ));
                }
                if accel.occluded(ray) != from_slice.occluded(ray) {
                    fail(format!("another any-hit answer for {}", ray.to_rust()));
                }
            }
            for &(p, max) in points {
                let (a, b) = (
                    accel.closest_point(p, max),
                    from_slice.closest_point(p, max),
                );
                let key = |h: Option<PointHit>| {
                    h.map(|h| {
                        (
                            h.prim,
                            h.distance.to_bits(),
                            h.point.to_array().map(f32::to_bits),
                        )
                    })
                };
                if key(a) != key(b) {
                    fail(format!(
                        "{a:?}, from the slice {b:?}, for the point {p:?} within {max}"
                    ));
                }
            }
        }
    }
}

/// `n` random triangles in the cube from -1 to 1, each with two edges of length up to about
/// `size × √3` from a random first vertex, drawn from `seed`: a scene for tests that need many
/// triangles of one size (the lab templates' step tests).
pub fn small_triangles(seed: u64, n: usize, size: f32) -> Vec<Triangle> {
    let mut rng = Rng::new(seed);
    let lo = Vec3::splat(-1.0);
    let hi = Vec3::ONE;
    (0..n)
        .map(|_| {
            let c = rng.in_box(lo, hi);
            let a = rng.in_box(lo, hi);
            let b = rng.in_box(lo, hi);
            Triangle::new(c, c + a * size, c + b * size)
        })
        .collect()
}

/// `n` rays from random origins in the cube from -2 to 2 towards random points in the cube from
/// -1 to 1, drawn from `seed`: about half start inside the smaller cube, most cross it.
pub fn rays_into_cube(seed: u64, n: usize) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let o = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
            let target = rng.in_box(Vec3::splat(-1.0), Vec3::ONE);
            Ray::new(o, (target - o).normalize())
        })
        .collect()
}

/// Runs proptest on random triangle scenes and rays for structure `A` with `params`.
///
/// Coordinates are drawn partly from a coarse lattice so that shared vertices, coplanar
/// triangles, rays through edges and vertices, and axis-parallel directions with `±0`
/// components come up often.
///
/// # Panics
/// With the shrunk failing case.
pub fn check_random<A: Accel<Prim = Triangle> + 'static>(params: &A::Params) {
    let check = |tris: &[Triangle], rays: &[Ray]| {
        check_parts::<A>(params, tris, rays, STALL_LIMIT, &Part::ALL, true, false)
    };
    if let Err(e) = random_scenes(A::NAME, check) {
        panic!("{e}");
    }
}

/// [`check_random`] for one part of the kit only ([`check_part`]), returning the shrunk
/// failing case instead of panicking.
///
/// # Errors
/// The shrunk failing case's message.
pub fn check_random_part<A: Accel<Prim = Triangle> + 'static>(
    params: &A::Params,
    part: Part,
    stall: std::time::Duration,
) -> Result<(), String> {
    random_scenes(A::NAME, |tris, rays| {
        check_parts::<A>(params, tris, rays, stall, &[part], true, false)
    })
}

/// Floats in `lo..hi` for proptest, on a grid of 2^24 steps, shrinking towards 0 (or towards
/// the bound nearer 0).
///
/// Why not proptest's own `lo..hi`: its float sampler (proptest 1.12) checks with a
/// `debug_assert!` that a sample overshoots a bound by less than one step, and on some seeds
/// that check fails (the sample itself is clamped into range). Students' crates and this
/// workspace test with debug assertions on, so the kit drew a panic instead of a case (a CI run,
/// `rt-hgrid`'s `deep::random_scenes`). An integer range mapped to floats has no such check.
pub(crate) fn float_in(lo: f32, hi: f32) -> impl Strategy<Value = f32> + Clone {
    debug_assert!(lo < hi && lo.is_finite() && hi.is_finite());
    let step = (hi - lo) / (1 << 24) as f32;
    let (first, end) = ((lo / step).ceil() as i64, (hi / step).ceil() as i64);
    (first..end).prop_map(move |k| (k as f32 * step).clamp(lo, hi.next_down()))
}

/// Runs proptest on random triangle scenes and rays (see [`check_random`]) with `check`.
fn random_scenes(
    name: &str,
    check: impl Fn(&[Triangle], &[Ray]) -> Result<(), String>,
) -> Result<(), String> {
    let coord = || {
        prop_oneof![
            (-6i32..=6).prop_map(|i| i as f32 * 0.5),
            float_in(-4.0, 4.0)
        ]
    };
    let vec3 = move || (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let tri = (vec3(), vec3(), vec3()).prop_map(|(a, b, c)| Triangle::new(a, b, c));
    let dir_c = || {
        prop_oneof![
            Just(0.0f32),
            Just(-0.0f32),
            Just(1.0f32),
            Just(-1.0f32),
            float_in(-1.0, 1.0)
        ]
    };
    // A ray either aims at a lattice point on a triangle (vertex, edge midpoint, centroid) or
    // goes in a random direction; `t_max` is sometimes finite and `t_min` sometimes positive.
    let ray = (
        vec3(),
        (dir_c(), dir_c(), dir_c()),
        prop::option::of((any::<prop::sample::Index>(), 0usize..7)),
        prop_oneof![Just(f32::INFINITY), float_in(0.1, 20.0)],
        prop_oneof![3 => Just(0.0f32), 1 => float_in(0.0, 2.0)],
    );
    let strategy = (
        prop::collection::vec(tri, 0..60),
        prop::collection::vec(ray, 1..40),
    );
    let mut runner = TestRunner::new(Config {
        failure_persistence: None,
        ..Config::default()
    });
    let stalled = std::sync::atomic::AtomicBool::new(false);
    let result = runner.run(&strategy, |(tris, specs)| {
        if stalled.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(());
        }
        let rays: Vec<Ray> = specs
            .iter()
            .filter_map(|&(o, (dx, dy, dz), aim, t_max, t_min)| {
                let dir = match aim {
                    Some((index, which)) if !tris.is_empty() => {
                        let t = tris[index.index(tris.len())];
                        let target = match which {
                            0 => t.v0,
                            1 => t.v1,
                            2 => t.v2,
                            3 => 0.5 * (t.v0 + t.v1),
                            4 => 0.5 * (t.v1 + t.v2),
                            5 => 0.5 * (t.v2 + t.v0),
                            _ => (t.v0 + t.v1 + t.v2) / 3.0,
                        };
                        target - o
                    }
                    _ => Vec3::new(dx, dy, dz),
                };
                let r = Ray::with_interval(o, dir, t_min.min(t_max), t_max);
                r.is_valid().then_some(r)
            })
            .collect();
        check(&tris, &rays).map_err(|e| stall_stops_shrinking(&stalled, e))
    });
    result.map_err(|e| proptest_failure(name, "", e))
}

/// A failed case for proptest. After a stall every later case passes at once: shrinking a case
/// that hangs would wait out the limit at every step, and the first stall already names its ray.
fn stall_stops_shrinking(stalled: &std::sync::atomic::AtomicBool, e: String) -> TestCaseError {
    if e.contains(STALL_MARK) {
        stalled.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    TestCaseError::fail(e)
}

/// The words that mark a stall in a failure message.
pub const STALL_MARK: &str = "did not return within";

/// The message of a failed proptest run: the failure (which names the ray and, when small, the
/// scene) without the shrunk input's full dump, which for a large scene runs to hundreds of
/// lines; `RT_CONFORMANCE_VERBOSE=1` adds it back.
fn proptest_failure<T: fmt::Debug>(
    name: &str,
    what: &str,
    e: proptest::test_runner::TestError<T>,
) -> String {
    use proptest::test_runner::TestError;
    let verbose = std::env::var("RT_CONFORMANCE_VERBOSE").is_ok_and(|v| v == "1");
    match e {
        TestError::Fail(reason, input) => {
            let mut m =
                format!("conformance {what}proptest failed for {name} (shrunk case): {reason}");
            if verbose {
                m.push_str(&format!("\n  full input: {input:?}"));
            } else {
                m.push_str("\n  (RT_CONFORMANCE_VERBOSE=1 prints the whole shrunk input)");
            }
            m
        }
        TestError::Abort(reason) => {
            format!("conformance {what}proptest aborted for {name}: {reason}")
        }
    }
}

/// Runs proptest on random sphere scenes (for structures generic over the primitive type).
///
/// # Panics
/// With the shrunk failing case.
pub fn check_random_spheres<A: Accel<Prim = Sphere> + 'static>(params: &A::Params) {
    let sphere = (
        prop::array::uniform3(float_in(-5.0, 5.0)),
        prop_oneof![float_in(0.01, 2.0), Just(0.0), Just(f32::NAN)],
    )
        .prop_map(|(c, r)| Sphere::new(Vec3::from(c), r));
    let ray = (
        prop::array::uniform3(float_in(-8.0, 8.0)),
        prop::array::uniform3(float_in(-1.0, 1.0)),
    );
    let strategy = (
        prop::collection::vec(sphere, 0..50),
        prop::collection::vec(ray, 1..40),
    );
    let mut runner = TestRunner::new(Config {
        failure_persistence: None,
        ..Config::default()
    });
    let stalled = std::sync::atomic::AtomicBool::new(false);
    let result = runner.run(&strategy, |(spheres, rays)| {
        if stalled.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(());
        }
        let rays: Vec<Ray> = rays
            .into_iter()
            .map(|(o, d)| Ray::new(Vec3::from(o), Vec3::from(d)))
            .filter(Ray::is_valid)
            .collect();
        check_case::<A>(params, &spheres, &rays).map_err(|e| stall_stops_shrinking(&stalled, e))
    });
    if let Err(e) = result {
        panic!("{}", proptest_failure(A::NAME, "sphere ", e));
    }
}

/// Runs every adversarial scene and the random-scene proptest; the one call a quick check needs.
/// Prefer [`conformance_tests!`](crate::conformance_tests), which makes one test per scene.
///
/// # Panics
/// At the first failure.
pub fn check_all<A: Accel<Prim = Triangle> + 'static>(params: &A::Params) {
    for name in SCENES {
        check_scene::<A>(params, name);
    }
    check_random::<A>(params);
}

/// Generates a test module with one `#[test]` per adversarial scene and one proptest run, for a
/// triangle structure type and a parameter expression. With `closest_hit:` before the module
/// name, one test per scene of its closest-hit queries only ([`check_scene_closest`]).
///
/// ```
/// // For example, in rt-bvh's tests:
/// // rt_conformance::conformance_tests!(median, rt_bvh::Bvh<rt_core::Triangle>, rt_bvh::BvhParams::median());
/// rt_conformance::conformance_tests!(reference, rt_core::BruteForce<rt_core::Triangle>, ());
/// ```
#[macro_export]
macro_rules! conformance_tests {
    ($module:ident, $accel:ty, $params:expr) => {
        mod $module {
            #[allow(unused_imports)]
            use super::*;
            fn params() -> <$accel as $crate::rt_core::Accel>::Params {
                $params
            }
            $crate::conformance_tests!(@scenes check_scene, $accel);
            #[test]
            fn random_scenes() {
                $crate::check_random::<$accel>(&params());
            }
            #[test]
            fn geometry_sources() {
                $crate::check_geometry_sources::<$accel>(&params());
            }
        }
    };
    // One test per scene of closest-hit queries only (`check_scene_closest`), no random scenes:
    // for a structure without its any-hit query yet.
    (closest_hit: $module:ident, $accel:ty, $params:expr) => {
        mod $module {
            #[allow(unused_imports)]
            use super::*;
            fn params() -> <$accel as $crate::rt_core::Accel>::Params {
                $params
            }
            $crate::conformance_tests!(@scenes check_scene_closest, $accel);
        }
    };
    (@scenes $check:ident, $accel:ty) => {
        $crate::conformance_tests!(@each $check, $accel;
            empty_scene one_triangle shared_edge identical_triangles equal_centroids
            zero_area_triangles axis_parallel_rays rays_in_box_faces origins_inside
            large_coordinates nan_vertex exponential_chain far_origins planar_triangles
            spanning_triangles invalid_rays lattice closed_meshes);
    };
    (@each $check:ident, $accel:ty; $($scene:ident)*) => {
        $(
            #[test]
            fn $scene() {
                $crate::$check::<$accel>(&params(), stringify!($scene));
            }
        )*
    };
}

fn random_rays(rng: &mut Rng, lo: Vec3, hi: Vec3, n: usize) -> Vec<Ray> {
    (0..n)
        .map(|_| Ray::new(rng.in_box(lo, hi), rng.unit_vector()))
        .collect()
}

/// Rays from random origins in `[lo, hi]` towards random points on random triangles, so that a
/// good share of them hit.
fn aimed_rays(rng: &mut Rng, tris: &[Triangle], lo: Vec3, hi: Vec3, n: usize) -> Vec<Ray> {
    let valid: Vec<&Triangle> = tris.iter().filter(|t| t.is_valid()).collect();
    (0..n)
        .filter_map(|_| {
            let t = valid.get(rng.below(valid.len().max(1) as u32) as usize)?;
            let (a, b) = (rng.f32(), rng.f32());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let target = t.v0 + a * (t.v1 - t.v0) + b * (t.v2 - t.v0);
            let o = rng.in_box(lo, hi);
            (target != o).then(|| Ray::new(o, target - o))
        })
        .collect()
}

fn soup(rng: &mut Rng, n: usize, lo: Vec3, hi: Vec3, size: f32) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let c = rng.in_box(lo, hi);
            Triangle::new(
                c + rng.unit_vector() * size,
                c + rng.unit_vector() * size,
                c + rng.unit_vector() * size,
            )
        })
        .collect()
}

/// The twelve triangles of the box `[lo, hi]` ([`Mesh::cuboid`]), facing outwards (inwards
/// with `inwards`).
fn box_triangles(lo: Vec3, hi: Vec3, inwards: bool) -> Vec<Triangle> {
    let tris = rt_core::Mesh::cuboid(lo, hi).triangles();
    if inwards {
        tris.iter()
            .map(|t| Triangle::new(t.v0, t.v2, t.v1))
            .collect()
    } else {
        tris
    }
}

/// Closed meshes, where inside and outside mean something: a box with a box-shaped cavity
/// (its faces turned inwards) and a UV sphere whose pole fans hold zero-area triangles. Rays
/// start inside and outside and run through the shared edges and vertices, along the faces
/// and at random.
fn closed_meshes() -> Scene {
    let mut rng = Rng::new(18);
    let mut triangles = box_triangles(Vec3::splat(-1.0), Vec3::ONE, false);
    triangles.extend(box_triangles(Vec3::splat(-0.4), Vec3::splat(0.4), true));
    let (centre, radius, rings, segments) = (Vec3::new(3.0, 0.0, 0.0), 0.75, 6, 12);
    let at = |i: usize, j: usize| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::TAU * (j % segments) as f32 / segments as f32;
        centre
            + radius
                * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                )
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            triangles.extend([Triangle::new(a, b, c), Triangle::new(a, c, d)]);
        }
    }
    let (lo, hi) = (Vec3::new(-1.5, -1.5, -1.5), Vec3::new(4.0, 1.5, 1.5));
    let mut rays = random_rays(&mut rng, lo, hi, 200);
    rays.extend(aimed_rays(&mut rng, &triangles, lo, hi, 200));
    // From inside the box and the cavity, through every vertex of the outer box and the middle
    // of its edges, and along the axes through its edges.
    for o in [
        Vec3::new(0.7, 0.1, -0.2),
        Vec3::new(0.1, -0.2, 0.05),
        Vec3::new(3.1, 0.2, 0.1),
    ] {
        for t in triangles.iter().take(12) {
            rays.push(Ray::new(o, t.v0 - o));
            rays.push(Ray::new(o, (t.v1 + t.v2) * 0.5 - o));
        }
    }
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        rays.push(Ray::new(Vec3::new(1.0, 1.0, 1.0) - axis * 3.0, axis));
        rays.push(Ray::new(Vec3::new(-1.0, 1.0, -1.0) - axis * 3.0, axis));
    }
    Scene { triangles, rays }
}

fn one_triangle() -> Scene {
    let t = Triangle::new(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    );
    let mut rays = Vec::new();
    // A lattice of targets in and around the triangle (vertices and edges included), seen from
    // both sides.
    for i in -6..=6 {
        for j in -6..=6 {
            let target = Vec3::new(i as f32 / 4.0, j as f32 / 4.0, 0.0);
            for o in [Vec3::new(0.3, 0.2, 3.0), Vec3::new(-0.5, 0.1, -2.0)] {
                rays.push(Ray::new(o, target - o));
            }
            rays.push(Ray::new(target + Vec3::Z, -Vec3::Z));
        }
    }
    Scene {
        triangles: vec![t],
        rays,
    }
}

fn shared_edge() -> Scene {
    // A unit quad split along its diagonal, plus a fan of four triangles sharing a vertex.
    let q = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let c = Vec3::new(3.0, 0.5, 0.0);
    let fan = [
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(4.0, 1.0, 0.0),
        Vec3::new(2.0, 1.0, 0.0),
    ];
    let mut triangles = vec![
        Triangle::new(q[0], q[1], q[2]),
        Triangle::new(q[0], q[2], q[3]),
    ];
    for k in 0..4 {
        triangles.push(Triangle::new(c, fan[k], fan[(k + 1) % 4]));
    }
    let mut rays = Vec::new();
    let origins = [
        Vec3::new(0.3, -0.7, 2.0),
        Vec3::new(-1.0, 2.0, 0.5),
        Vec3::new(0.5, 0.5, -1.0),
        Vec3::new(2.5, 3.0, 1.5),
    ];
    for i in 0..=32 {
        let s = i as f32 / 32.0;
        for target in [
            Vec3::new(s, s, 0.0),
            0.5 * (fan[0] + c) + s * (c - fan[0]) * 0.5,
            c,
        ] {
            for o in origins {
                rays.push(Ray::new(o, target - o));
            }
            rays.push(Ray::new(target + Vec3::Z, Vec3::new(0.0, -0.0, -1.0)));
        }
    }
    Scene { triangles, rays }
}

fn identical_triangles() -> Scene {
    let t = Triangle::new(
        Vec3::new(-1.0, -1.0, 0.5),
        Vec3::new(1.0, -1.0, 0.5),
        Vec3::new(0.0, 1.0, 0.5),
    );
    let mut rng = Rng::new(4);
    // Far more copies than any leaf, node or cell holds before a builder gives up splitting.
    // PERF: 1000 copies made the fine grid's scene and geometry-source tests take 56 s of a CI
    // run at opt-level 1 (every cell on the plane lists every copy, and a closest-point ball
    // meets many cells); 256 keep the case and take a quarter of that.
    let triangles = vec![t; 256];
    let rays = aimed_rays(
        &mut rng,
        &triangles,
        Vec3::splat(-3.0),
        Vec3::splat(3.0),
        200,
    );
    Scene { triangles, rays }
}

fn equal_centroids() -> Scene {
    // 300 triangles of different sizes and orientations, all with their centroid at one point.
    let mut rng = Rng::new(5);
    let c = Vec3::new(0.25, -0.5, 1.0);
    let triangles: Vec<Triangle> = (0..300)
        .map(|i| {
            let s = 0.01 + (i % 17) as f32 * 0.1;
            let a = rng.unit_vector() * s;
            let b = rng.unit_vector() * s;
            Triangle::new(c + a, c + b, c - a - b)
        })
        .collect();
    let mut rays = aimed_rays(
        &mut rng,
        &triangles,
        Vec3::splat(-3.0),
        Vec3::splat(3.0),
        300,
    );
    rays.extend(random_rays(
        &mut rng,
        Vec3::splat(-2.0),
        Vec3::splat(2.0),
        100,
    ));
    Scene { triangles, rays }
}

fn zero_area_triangles() -> Scene {
    let mut rng = Rng::new(6);
    let mut triangles = soup(&mut rng, 100, Vec3::splat(-1.0), Vec3::ONE, 0.4);
    for i in 0..100 {
        let p = rng.in_box(Vec3::splat(-1.0), Vec3::ONE);
        let d = rng.unit_vector() * 0.5;
        let degenerate = match i % 3 {
            0 => Triangle::new(p, p, p),
            1 => Triangle::new(p, p + d, p + 2.0 * d),
            _ => Triangle::new(p, p + d, p),
        };
        triangles.insert(2 * i, degenerate);
    }
    let mut rays = aimed_rays(
        &mut rng,
        &triangles,
        Vec3::splat(-2.0),
        Vec3::splat(2.0),
        300,
    );
    // Rays straight at the degenerate ones.
    for t in triangles.iter().filter(|t| !t.is_valid()).take(50) {
        let o = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
        if o != t.v1 {
            rays.push(Ray::new(o, t.v1 - o));
        }
    }
    Scene { triangles, rays }
}

/// Triangles on a half-unit lattice, hit by rays along the axes whose other direction
/// components are `+0.0` or `-0.0` and whose origins lie on lattice planes, where the slab
/// test sees `0 · inf`.
fn axis_parallel_rays() -> Scene {
    let mut triangles = Vec::new();
    let mut rng = Rng::new(7);
    let lattice = |r: &mut Rng| (r.below(9) as f32 - 4.0) * 0.5;
    for _ in 0..150 {
        let p = |r: &mut Rng| Vec3::new(lattice(r), lattice(r), lattice(r));
        let t = Triangle::new(p(&mut rng), p(&mut rng), p(&mut rng));
        if t.is_valid() {
            triangles.push(t);
        }
    }
    let mut rays = Vec::new();
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            for zero in [0.0f32, -0.0] {
                for _ in 0..60 {
                    let mut o = Vec3::new(lattice(&mut rng), lattice(&mut rng), lattice(&mut rng));
                    if rng.below(2) == 0 {
                        o[(axis + 1) % 3] += 0.25;
                    }
                    o[axis] = -3.0 * sign;
                    let mut d = Vec3::splat(zero);
                    d[axis] = sign;
                    rays.push(Ray::new(o, d));
                }
            }
        }
    }
    Scene { triangles, rays }
}

/// Tilted triangles whose boxes share face planes (x, y, z in {-1, 0, 1}), and rays lying
/// exactly in those planes.
fn rays_in_box_faces() -> Scene {
    let mut rng = Rng::new(8);
    let planes = [-1.0f32, 0.0, 1.0];
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for &p in &planes {
            for _ in 0..12 {
                // One vertex on the plane, the others on one side of it: the plane is a box face.
                let mut a = rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5));
                a[axis] = p;
                let side = if rng.below(2) == 0 { 1.0 } else { -1.0 };
                let mut b = rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5));
                b[axis] = p + side * rng.range(0.1, 0.5);
                let mut c = rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5));
                c[axis] = p + side * rng.range(0.1, 0.5);
                triangles.push(Triangle::new(a, b, c));
                // And an edge lying in the plane.
                let mut d = rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5));
                d[axis] = p;
                triangles.push(Triangle::new(a, d, b));
            }
        }
    }
    let mut rays = Vec::new();
    for t in &triangles {
        for axis in 0..3 {
            for zero in [0.0f32, -0.0] {
                // A ray in the plane `axis = v0[axis]` aimed through v0 from outside.
                let mut o = rng.in_box(Vec3::splat(-3.0), Vec3::splat(3.0));
                o[axis] = t.v0[axis];
                let mut d = t.v0 - o;
                d[axis] = zero;
                if d != Vec3::ZERO {
                    rays.push(Ray::new(o, d));
                }
            }
        }
    }
    Scene { triangles, rays }
}

fn origins_inside() -> Scene {
    let mut rng = Rng::new(9);
    let triangles = soup(&mut rng, 500, Vec3::splat(-1.0), Vec3::ONE, 0.3);
    let mut rays = random_rays(&mut rng, Vec3::splat(-1.0), Vec3::ONE, 300);
    rays.extend(aimed_rays(
        &mut rng,
        &triangles,
        Vec3::splat(-0.5),
        Vec3::splat(0.5),
        300,
    ));
    // Origins exactly on triangle vertices and in the middle of triangles.
    for t in triangles.iter().take(100) {
        rays.push(Ray::new(t.v0, rng.unit_vector()));
        rays.push(Ray::new((t.v0 + t.v1 + t.v2) / 3.0, rng.unit_vector()));
    }
    Scene { triangles, rays }
}

fn large_coordinates() -> Scene {
    // Small triangles far from the origin (where a float's spacing is ~1) and a scene spanning
    // ±1e8: the box tests must stay conservative when rounding is coarse.
    let mut rng = Rng::new(10);
    let far = Vec3::new(3.0e7, -2.0e7, 1.0e7);
    let mut triangles = soup(
        &mut rng,
        200,
        far - Vec3::splat(500.0),
        far + Vec3::splat(500.0),
        60.0,
    );
    triangles.extend(soup(
        &mut rng,
        200,
        Vec3::splat(-1.0e8),
        Vec3::splat(1.0e8),
        2.0e7,
    ));
    let mut rays = aimed_rays(
        &mut rng,
        &triangles[..200],
        far - Vec3::splat(2000.0),
        far + Vec3::splat(2000.0),
        300,
    );
    rays.extend(aimed_rays(
        &mut rng,
        &triangles[200..],
        Vec3::splat(-2.0e8),
        Vec3::splat(2.0e8),
        300,
    ));
    Scene { triangles, rays }
}

fn nan_vertex() -> Scene {
    let mut rng = Rng::new(11);
    let mut triangles = soup(&mut rng, 300, Vec3::splat(-1.0), Vec3::ONE, 0.3);
    let bad = [
        Triangle::new(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y),
        Triangle::new(
            Vec3::splat(f32::NAN),
            Vec3::splat(f32::NAN),
            Vec3::splat(f32::NAN),
        ),
        Triangle::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::Y),
        Triangle::new(Vec3::new(0.0, f32::NEG_INFINITY, 1.0), Vec3::X, Vec3::Y),
    ];
    for (k, t) in bad.into_iter().enumerate() {
        triangles.insert(37 * k + 1, t);
    }
    let mut rays = aimed_rays(
        &mut rng,
        &triangles,
        Vec3::splat(-2.0),
        Vec3::splat(2.0),
        400,
    );
    rays.extend(random_rays(&mut rng, Vec3::splat(-1.0), Vec3::ONE, 100));
    // Rays through where the bad triangles would be if NaN were treated as a number.
    rays.push(Ray::new(Vec3::new(0.1, 0.1, 3.0), -Vec3::Z));
    rays.push(Ray::new(Vec3::new(0.1, 0.1, -3.0), Vec3::Z));
    Scene { triangles, rays }
}

/// 120 parallel triangles at `x = 1.5^k`: every builder that splits space or centroids in the
/// middle peels off one triangle per level, so the tree is as deep as its builder allows, and a
/// traversal stack must not overflow.
/// Axis-aligned triangles lying in a few shared planes (x, y or z in {-1, 0, 1}), overlapping
/// each other, plus tilted ones with a vertex in those planes: the planes are split candidates
/// with primitives lying in them. Rays run inside the planes (axis-parallel and diagonal), cross
/// them at vertices, and hit them head-on.
fn planar_triangles() -> Scene {
    let mut rng = Rng::new(13);
    let planes = [-1.0f32, 0.0, 1.0];
    let lattice = |r: &mut Rng| (r.below(9) as f32 - 4.0) * 0.25;
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for &c in &planes {
            for k in 0..10 {
                let mut v = [Vec3::ZERO; 3];
                for p in &mut v {
                    *p = Vec3::new(lattice(&mut rng), lattice(&mut rng), lattice(&mut rng));
                    p[axis] = c;
                }
                // Every other one tilted out of the plane by one vertex.
                if k % 2 == 1 {
                    v[2][axis] = c + 0.5;
                }
                let t = Triangle::new(v[0], v[1], v[2]);
                if t.is_valid() {
                    triangles.push(t);
                }
            }
        }
    }
    let mut rays = Vec::new();
    for axis in 0..3 {
        for &c in &planes {
            for _ in 0..40 {
                // In the plane: origin on it, direction with a zero component along `axis`.
                let mut o =
                    Vec3::new(lattice(&mut rng), lattice(&mut rng), lattice(&mut rng)) * 3.0;
                o[axis] = c;
                let mut d = rng.unit_vector();
                d[axis] = if rng.below(2) == 0 { 0.0 } else { -0.0 };
                if d.length_squared() > 0.0 {
                    rays.push(Ray::new(o, d));
                }
                // Through the plane at a lattice point, and head-on.
                let mut target = Vec3::new(lattice(&mut rng), lattice(&mut rng), lattice(&mut rng));
                target[axis] = c;
                let from = rng.in_box(Vec3::splat(-3.0), Vec3::splat(3.0));
                if from != target {
                    rays.push(Ray::new(from, target - from));
                }
                let mut head_on = target;
                head_on[axis] = c + 2.0;
                let mut d = Vec3::ZERO;
                d[axis] = -1.0;
                rays.push(Ray::new(head_on, d));
            }
        }
    }
    Scene { triangles, rays }
}

/// A few large triangles spanning the whole scene among many small ones, so a ray often hits a
/// large triangle in a cell beyond the current one while a closer small triangle waits in the
/// next cell: structures that stop at the first hit found, instead of the first hit inside the
/// current cell, fail here.
fn spanning_triangles() -> Scene {
    let mut rng = Rng::new(14);
    let mut triangles = soup(&mut rng, 400, Vec3::splat(-1.0), Vec3::ONE, 0.08);
    for _ in 0..12 {
        let p = |r: &mut Rng| r.in_box(Vec3::splat(-1.5), Vec3::splat(1.5));
        let t = Triangle::new(p(&mut rng), p(&mut rng), p(&mut rng));
        if t.is_valid() {
            triangles.push(t);
        }
    }
    let mut rays = random_rays(&mut rng, Vec3::splat(-2.0), Vec3::splat(2.0), 400);
    rays.extend(aimed_rays(
        &mut rng,
        &triangles,
        Vec3::splat(-2.0),
        Vec3::splat(2.0),
        400,
    ));
    Scene { triangles, rays }
}

/// Rays a caller should not send (`Ray::is_valid` is false): NaN, infinite or huge origins
/// (10³⁰, beyond `Ray::MAX_ORIGIN`), zero, infinite or NaN directions, empty or NaN intervals.
/// A structure must answer them at once: no hit, no primitive tested, at most one node visited.
fn invalid_rays() -> Scene {
    let mut rng = Rng::new(15);
    let triangles = soup(&mut rng, 300, Vec3::splat(-1.0), Vec3::ONE, 0.3);
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let rays = vec![
        Ray::new(Vec3::new(nan, 0.0, 0.0), Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::new(nan, 1.0, 0.0)),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::new(Vec3::splat(inf), -Vec3::ONE),
        Ray::new(Vec3::splat(-inf), Vec3::ONE),
        Ray::new(Vec3::ZERO, Vec3::new(inf, 1.0, 0.0)),
        Ray::with_interval(Vec3::splat(-2.0), Vec3::ONE, 3.0, 1.0),
        Ray::with_interval(Vec3::splat(-2.0), Vec3::ONE, nan, nan),
        Ray::with_interval(Vec3::splat(-2.0), Vec3::ONE, -inf, inf),
        Ray::new(Vec3::splat(1e30), -Vec3::ONE),
        Ray::new(Vec3::new(0.0, 0.0, 1e30), -Vec3::Z),
        Ray::new(Vec3::new(0.0, -Ray::MAX_ORIGIN * 2.0, 0.0), Vec3::Y),
        Ray::new(Vec3::ZERO, Vec3::splat(nan)),
    ];
    Scene { triangles, rays }
}

/// `count` triangles with vertices on the half-integer lattice of the cube `[0, 4]³`; the first
/// two pin the scene's box to the whole cube. A third lie in an axis plane through a lattice
/// point. On a grid (or kd-tree) whose planes are the integers or half-integers, they lie in cell
/// planes, touch cells at a vertex or an edge, and span many cells.
pub fn lattice_triangles(seed: u64, count: usize) -> Vec<Triangle> {
    let mut rng = Rng::new(seed);
    let mut tris = vec![
        Triangle::new(
            Vec3::ZERO,
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.0, 0.5, 0.0),
        ),
        Triangle::new(
            Vec3::splat(4.0),
            Vec3::new(3.5, 4.0, 4.0),
            Vec3::new(4.0, 3.5, 4.0),
        ),
    ];
    let point = |rng: &mut Rng| {
        Vec3::new(
            (rng.f32() * 9.0).floor() * 0.5,
            (rng.f32() * 9.0).floor() * 0.5,
            (rng.f32() * 9.0).floor() * 0.5,
        )
    };
    while tris.len() < count {
        let a = point(&mut rng);
        let mut b = point(&mut rng);
        let mut c = point(&mut rng);
        if rng.f32() < 0.33 {
            let axis = (rng.f32() * 3.0) as usize % 3;
            b[axis] = a[axis];
            c[axis] = a[axis];
        }
        let t = Triangle::new(a, b, c);
        if t.normal() != Vec3::ZERO {
            tris.push(t);
        }
    }
    tris.truncate(count.max(2));
    tris
}

/// `count` rays from integer lattice points of `[-1, 5]³` (inside the cube of
/// [`lattice_triangles`], on its faces, edges and corners, and outside) along directions with
/// components in {-2, -1, -0, +0, 1, 2}: they run along lattice planes and pass exactly through
/// lattice edges and corners.
pub fn lattice_rays(seed: u64, count: usize) -> Vec<Ray> {
    let mut rng = Rng::new(seed ^ 0xdda);
    let component =
        |rng: &mut Rng| [-2.0, -1.0, -0.0, 0.0, 1.0, 2.0][(rng.f32() * 6.0) as usize % 6];
    let mut rays = Vec::with_capacity(count);
    while rays.len() < count {
        let o = Vec3::new(
            (rng.f32() * 7.0).floor() - 1.0,
            (rng.f32() * 7.0).floor() - 1.0,
            (rng.f32() * 7.0).floor() - 1.0,
        );
        let d = Vec3::new(
            component(&mut rng),
            component(&mut rng),
            component(&mut rng),
        );
        if d.abs() != Vec3::ZERO {
            rays.push(Ray::new(o, d));
        }
    }
    rays
}

/// One case of tiny triangles hugging a lattice edge: the two pinning triangles of
/// [`lattice_triangles`], then four triangles of size up to 10⁻³, one in each quadrant around the
/// edge x = i, y = j (integers 1..=3) at distances down to 10⁻⁷, and 200 rays at them from up to
/// 10⁴ away. Rounding moves such a ray's computed path across the edge by more than the
/// triangles' distance to it: a structure with cells there must look on both sides.
pub fn edge_grazing_case(rng: &mut Rng) -> (Vec<Triangle>, Vec<Ray>) {
    let mut tris = lattice_triangles(0, 2);
    let (i, j) = (
        (1 + (rng.f32() * 3.0) as u32) as f32,
        (1 + (rng.f32() * 3.0) as u32) as f32,
    );
    let eps = 10f32.powf(-3.0 - rng.f32() * 4.0);
    for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
        let c = Vec3::new(i + sx * eps, j + sy * eps, 2.0 + rng.f32());
        let s = eps * 0.5;
        tris.push(Triangle::new(
            c + Vec3::new(-s, -s, 0.0),
            c + Vec3::new(s, -s, 0.0),
            c + Vec3::new(0.0, s, 0.01),
        ));
    }
    let rays = (0..200)
        .map(|_| {
            let target = Vec3::new(
                i + (rng.f32() - 0.5) * eps * 4.0,
                j + (rng.f32() - 0.5) * eps * 4.0,
                2.0 + rng.f32(),
            );
            let dist = 10f32.powf(rng.f32() * 4.0);
            let dir = rng.unit_vector();
            Ray::new(target - dir * dist, dir)
        })
        .collect();
    (tris, rays)
}

fn exponential_chain() -> Scene {
    let mut triangles = Vec::new();
    for k in 0..120 {
        let x = 1.5f32.powi(k);
        let s = 1.0 + k as f32 * 0.01;
        triangles.push(Triangle::new(
            Vec3::new(x, -s, -s),
            Vec3::new(x, s, -s),
            Vec3::new(x, 0.0, s),
        ));
    }
    let mut rng = Rng::new(12);
    let mut rays = Vec::new();
    for _ in 0..100 {
        let o = Vec3::new(0.0, rng.range(-0.5, 0.5), rng.range(-0.5, 0.5));
        rays.push(Ray::new(o, Vec3::X));
        // From far out along the chain (as far as a valid origin goes, `Ray::MAX_ORIGIN`),
        // back towards the start: the triangles beyond are hit by the rays along +x.
        let far = Vec3::new(Ray::MAX_ORIGIN, o.y, o.z);
        rays.push(Ray::new(far, -Vec3::X));
        rays.push(Ray::new(o, Vec3::new(1.0, rng.range(-1e-9, 1e-9), 0.0)));
    }
    let hi = Vec3::new(1.5f32.powi(120), 2.0, 2.0);
    rays.extend(aimed_rays(&mut rng, &triangles, Vec3::splat(-2.0), hi, 200));
    Scene { triangles, rays }
}

/// A scene a few thousand units wide (the start of [`exponential_chain`]: 24 triangles, one
/// behind the other along x) seen from as far as a valid origin goes ([`Ray::MAX_ORIGIN`]): the
/// ray parameter's rounding step (131,072 at 10¹²) is larger than the scene, so every cell or
/// node boundary the ray crosses has the same parameter, and hits on different triangles round
/// to parameters one step apart. A walk must still visit every cell in order and find the hit
/// brute force finds. (Found by the `trace` fuzz target: the grids started their walk in the
/// last cell along the ray, where all the boundaries' parameters collapsed, and missed the rest.)
fn far_origins() -> Scene {
    let triangles: Vec<Triangle> = exponential_chain().triangles.into_iter().take(24).collect();
    let mut rng = Rng::new(13);
    let far = Ray::MAX_ORIGIN;
    let mut rays = Vec::new();
    for _ in 0..100 {
        let (y, z) = (rng.range(-0.5, 0.5), rng.range(-0.5, 0.5));
        rays.push(Ray::new(Vec3::new(far, y, z), -Vec3::X));
        rays.push(Ray::new(Vec3::new(-far, y, z), Vec3::X));
        // Slanted just enough to drift across the triangles' width on the way: aiming from
        // 10¹² at a point of a unit triangle is meaningless in f32 (the triangle's corners are
        // one float apart there), but a slope is exact.
        let slope = Vec3::new(0.0, rng.range(-1e-12, 1e-12), rng.range(-1e-12, 1e-12));
        rays.push(Ray::new(Vec3::new(far, y, z), slope - Vec3::X));
    }
    Scene { triangles, rays }
}

/// The directory of real meshes beside the repository (`../shared/meshes`), or the one named by
/// the `RT_SHARED_MESHES` environment variable.
///
/// Returns `None`, after printing why on stderr, when the directory is missing, so a local run
/// can go on without it.
///
/// # Panics
/// When the directory is missing and `CI=true`: in CI a test that needs the meshes must fail,
/// never skip.
pub fn shared_meshes_dir() -> Option<std::path::PathBuf> {
    let dir = match std::env::var_os("RT_SHARED_MESHES") {
        Some(d) => std::path::PathBuf::from(d),
        None => std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes"),
    };
    if dir.join("stanford-bunny.obj").is_file() {
        return Some(dir);
    }
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    assert!(
        !ci,
        "shared meshes not found at {} (CI=true, so this fails instead of skipping)",
        dir.display()
    );
    eprintln!(
        "note: shared meshes not found at {}; skipping what needs them (set RT_SHARED_MESHES)",
        dir.display()
    );
    None
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::strategy::ValueTree;

    /// Every draw lies in `lo..hi`, draws spread over the range, and a draw shrinks to the
    /// bound nearer 0 (to 0 itself when the range holds it).
    #[test]
    fn float_in_stays_in_range_and_shrinks_towards_zero() {
        let mut runner = TestRunner::deterministic();
        for (lo, hi) in [
            (-4.0, 4.0),
            (0.1, 20.0),
            (0.01, 2.0),
            (0.25, 4.0),
            (0.0, 6.3),
        ] {
            let strategy = float_in(lo, hi);
            let (mut low_half, mut high_half) = (0, 0);
            for _ in 0..2000 {
                let mut tree = strategy.new_tree(&mut runner).unwrap();
                let x = tree.current();
                assert!((lo..hi).contains(&x), "{x} outside {lo}..{hi}");
                if x < (lo + hi) / 2.0 {
                    low_half += 1;
                } else {
                    high_half += 1;
                }
                while tree.simplify() {}
                let least = if lo <= 0.0 && hi > 0.0 { 0.0 } else { lo };
                assert!(
                    (tree.current() - least).abs() <= (hi - lo) * 1e-6,
                    "{lo}..{hi}"
                );
            }
            assert!(
                low_half > 800 && high_half > 800,
                "{lo}..{hi}: {low_half}/{high_half}"
            );
        }
    }
}

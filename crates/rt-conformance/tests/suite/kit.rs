//! The conformance kit never hangs and always names the ray: structures that loop forever or
//! panic on one ray fail with a short message naming that ray.

use rt_conformance::{Part, STALL_LIMIT, check_case_within, check_part, check_random, scene};
use rt_core::glam::Vec3;
use rt_core::{
    Aabb, Accel, BallQuery, BoxQuery, BruteForce, BuildStats, Hit, PrimHit, Primitive, Ray,
    RayQuery, Stats, Triangle,
};
use rt_persist::{LoadError, Persist, Reader, Writer};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The items every test structure below forwards to the brute force it wraps: each then
/// writes only its name and the query it breaks.
macro_rules! forward_to_brute_force {
    () => {
        type Prim = Triangle;
        type Params = ();
        fn presets() -> Vec<(&'static str, ())> {
            vec![("default", ())]
        }
        fn build(prims: &[Triangle], _: &()) -> Self {
            Self(BruteForce::build(prims, &()))
        }
        fn bounds(&self) -> Aabb {
            self.0.bounds()
        }
        fn memory_bytes(&self) -> usize {
            self.0.memory_bytes()
        }
        fn build_stats(&self) -> BuildStats {
            self.0.build_stats()
        }
    };
}

/// Lets the looping structure's stuck thread finish once its test has seen the failure.
static RELEASE: AtomicBool = AtomicBool::new(false);

/// The rays a broken structure below gets wrong: those heading mostly down.
fn cursed(ray: &Ray) -> bool {
    ray.is_valid() && ray.dir().y < -0.5 * ray.dir().length()
}

/// Brute force, except that its ray walk for a closest hit never returns on a cursed ray (like a
/// DDA stepping by zero), or panics there. Only the closest hit, so that the random scenes
/// shrink to a ray the kit's first check traces (a point's crossing parity casts cursed rays
/// too).
struct Broken<const PANICS: bool>(BruteForce<Triangle>);

impl<const PANICS: bool> Accel for Broken<PANICS> {
    forward_to_brute_force!();
    const NAME: &'static str = "broken";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        // `ClosestHit` is the one query that ignores copies and is no occlusion query.
        if Q::COPIES_CHANGE_NOTHING && !Q::OCCLUSION && cursed(ray) {
            assert!(
                !PANICS,
                "index out of bounds: the len is 3 but the index is 7"
            );
            while !RELEASE.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
}

/// Brute force for rays, but its ball query prunes like a structure that forgot the tie rule's
/// margin: it offers only the primitives after the first one it finds inside the ball.
struct StopsAtFirst(BruteForce<Triangle>);

/// Forwards to a query and remembers whether anything has been offered yet.
struct Once<'a, Q> {
    inner: &'a mut Q,
    offered: bool,
}

impl<Q: BallQuery<Triangle>> BallQuery<Triangle> for Once<'_, Q> {
    fn center(&self) -> rt_core::glam::Vec3 {
        self.inner.center()
    }
    fn radius_sq(&self) -> f32 {
        self.inner.radius_sq()
    }
    fn test(&mut self, prim: &Triangle, id: u32) {
        if !self.offered {
            self.offered = true;
            self.inner.test(prim, id);
        }
    }
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        if !self.offered {
            self.offered = true;
            self.inner.test_triangle(v0, e1, e2, id);
        }
    }
}

impl Accel for StopsAtFirst {
    forward_to_brute_force!();
    const NAME: &'static str = "stops-at-first";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        let mut once = Once {
            inner: query,
            offered: false,
        };
        self.0.ball_query(&mut once, stats);
    }
}

#[test]
fn a_wrong_closest_point_query_fails_with_its_point_named() {
    // Rays all agree; only the closest-point checks can catch it.
    let s = scene("shared_edge");
    let e = check_case_within::<StopsAtFirst>(&(), &s.triangles, &s.rays, Duration::from_secs(20))
        .expect_err("offering only the first primitive must fail");
    assert!(
        e.contains("closest_point disagrees with brute force"),
        "{e}"
    );
    assert!(e.contains("query: closest_point(Vec3::new("), "{e}");
}

#[test]
fn a_looping_structure_fails_with_its_ray_named() {
    let s = scene("one_triangle");
    let first = s
        .rays
        .iter()
        .find(|r| cursed(r))
        .expect("the scene has a downward ray");
    let start = Instant::now();
    let result =
        check_case_within::<Broken<false>>(&(), &s.triangles, &s.rays, Duration::from_secs(1));
    RELEASE.store(true, Ordering::Relaxed);
    let message = result.expect_err("a structure that never returns must fail");
    assert!(
        start.elapsed() < Duration::from_secs(10),
        "took {:?}",
        start.elapsed()
    );
    assert!(message.contains("did not return within"), "{message}");
    assert!(message.contains(&first.to_rust()), "{message}");
    assert!(message.contains(&first.to_line()), "{message}");
}

#[test]
fn a_panicking_structure_fails_with_the_ray_and_the_panic() {
    let s = scene("one_triangle");
    let first = s.rays.iter().find(|r| cursed(r)).unwrap();
    let message =
        check_case_within::<Broken<true>>(&(), &s.triangles, &s.rays, Duration::from_secs(20))
            .expect_err("a panic must fail the case");
    assert!(
        message.contains("broken panicked: index out of bounds"),
        "{message}"
    );
    assert!(message.contains(&first.to_rust()), "{message}");
    assert!(message.lines().count() <= 5, "{message}");
}

#[test]
fn the_random_scenes_report_is_short() {
    let panic = std::panic::catch_unwind(|| check_random::<Broken<true>>(&()))
        .expect_err("the proptest run must fail");
    let message = panic.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(message.contains("broken panicked"), "{message}");
    assert!(message.contains("Ray::with_interval("), "{message}");
    // The shrunk case's scene is at most 12 triangles on one line; no dump of the whole input.
    assert!(
        message.lines().count() <= 8,
        "{} lines:\n{message}",
        message.lines().count()
    );
}

#[test]
fn the_test_macro_lists_every_scene_of_the_kit() {
    // `conformance_tests!` spells the scene names out (a macro cannot loop over a const slice):
    // if the kit grows a scene, the macro's list must grow too.
    let source = include_str!("../../src/lib.rs");
    let start = source
        .find("conformance_tests!(@each $check, $accel;")
        .expect("the macro's scene list");
    let list = &source[start..];
    let list = &list[list.find(';').unwrap() + 1..list.find(')').unwrap()];
    let listed: Vec<&str> = list.split_whitespace().collect();
    assert_eq!(listed, rt_conformance::SCENES);
}

/// The `TwoLevel` methods a faulty two-level scene below takes unchanged from the linear
/// reference it wraps (`self.0`).
macro_rules! forward_to_linear {
    () => {
        fn instances(&self) -> &[rt_instance::Instance<Triangle>] {
            self.0.instances()
        }
        fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
            self.0.occluded_with(ray, stats)
        }
        fn closest_point_with<S: Stats>(
            &self,
            point: rt_core::glam::Vec3,
            max_distance: f32,
            stats: &mut S,
        ) -> Option<rt_instance::InstancePointHit> {
            self.0.closest_point_with(point, max_distance, stats)
        }
        fn bounds(&self) -> rt_core::Aabb {
            self.0.bounds()
        }
        fn memory_bytes(&self) -> usize {
            self.0.memory_bytes()
        }
    };
}

/// The linear reference with one fault: it never looks at the instance at index 1, or it
/// reports a hit's `t` a little late.
struct SkipsOne<const LATE: bool>(rt_instance::LinearInstances<Triangle>);

impl<const LATE: bool> rt_instance::TwoLevel<Triangle> for SkipsOne<LATE> {
    const NAME: &'static str = "skips-one";
    fn build(mut instances: Vec<rt_instance::Instance<Triangle>>) -> Self {
        if !LATE && instances.len() > 1 {
            // Instance 1 moved far away, where no ray of the kit goes.
            let far = rt_core::glam::Affine3A::from_translation(rt_core::glam::Vec3::splat(1e6));
            instances[1] =
                rt_instance::Instance::new(instances[1].bottom().clone(), far, instances[1].id())
                    .unwrap();
        }
        Self(rt_instance::LinearInstances::build(instances))
    }
    fn intersect_with<S: Stats>(
        &self,
        ray: &Ray,
        stats: &mut S,
    ) -> Option<rt_instance::InstanceHit> {
        self.0
            .intersect_with(ray, stats)
            .map(|h| rt_instance::InstanceHit {
                t: if LATE { h.t * 1.001 } else { h.t },
                ..h
            })
    }
    forward_to_linear!();
}

fn brute_bottom(t: &[Triangle]) -> std::sync::Arc<dyn rt_core::DynAccel<Triangle>> {
    std::sync::Arc::new(BruteForce::build(t, &()))
}

#[test]
fn a_two_level_scene_that_loses_an_instance_or_a_t_fails_with_its_ray_named() {
    let case = rt_conformance::two_level_scene("mirrored_and_scaled").remove(0);
    let lost = rt_conformance::check_two_level_case::<SkipsOne<false>>(&[brute_bottom], &case)
        .expect_err("an instance that moved away must be missed");
    assert!(
        lost.contains("disagrees with the linear reference") && lost.contains("ray: Ray::"),
        "{lost}"
    );
    let late = rt_conformance::check_two_level_case::<SkipsOne<true>>(&[brute_bottom], &case)
        .expect_err("a late t must be caught");
    assert!(late.contains("intersect disagrees"), "{late}");
    // The reference itself passes.
    rt_conformance::check_two_level_case::<rt_instance::LinearInstances<Triangle>>(
        &[brute_bottom],
        &case,
    )
    .expect("the linear reference agrees with itself and with the flattened scene");
}

/// The linear reference with a batch query that writes each answer one slot late, as an
/// override that lost track of its rays' order would.
struct ShiftedBatch(rt_instance::LinearInstances<Triangle>);

impl rt_instance::TwoLevel<Triangle> for ShiftedBatch {
    const NAME: &'static str = "shifted-batch";
    fn build(instances: Vec<rt_instance::Instance<Triangle>>) -> Self {
        Self(rt_instance::LinearInstances::build(instances))
    }
    fn intersect_with<S: Stats>(
        &self,
        ray: &Ray,
        stats: &mut S,
    ) -> Option<rt_instance::InstanceHit> {
        self.0.intersect_with(ray, stats)
    }
    fn intersect_batch<R: rt_core::batch::RaySource + ?Sized>(
        &self,
        rays: &R,
        out: &mut [Option<rt_instance::InstanceHit>],
    ) {
        self.0.intersect_batch(rays, out);
        out.rotate_right(1.min(out.len()));
    }
    forward_to_linear!();
}

#[test]
fn a_two_level_batch_that_misplaces_answers_fails_with_its_ray_named() {
    let case = rt_conformance::two_level_scene("mirrored_and_scaled").remove(0);
    let shifted = rt_conformance::check_two_level_case::<ShiftedBatch>(&[brute_bottom], &case)
        .expect_err("answers in the wrong slots must be caught");
    assert!(
        shifted.contains("a batch of") && shifted.contains("ray: Ray::"),
        "{shifted}"
    );
}

/// The linear reference with bundle queries that lose the last ray's hit in every call of two
/// rays or more (`STREAM`: its stream queries instead), as a walk that dropped a lane would.
struct LosesALane<const STREAM: bool>(rt_instance::LinearInstances<Triangle>);

impl<const STREAM: bool> LosesALane<STREAM> {
    fn lose<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<rt_instance::InstanceHit>],
        s: &mut S,
    ) {
        rt_instance::TwoLevel::intersect_bundle_with(&self.0, rays, out, s);
        if let [_, .., last] = out {
            *last = None;
        }
    }
}

impl<const STREAM: bool> rt_instance::TwoLevel<Triangle> for LosesALane<STREAM> {
    const NAME: &'static str = "loses-a-lane";
    fn build(instances: Vec<rt_instance::Instance<Triangle>>) -> Self {
        Self(rt_instance::LinearInstances::build(instances))
    }
    fn intersect_with<S: Stats>(
        &self,
        ray: &Ray,
        stats: &mut S,
    ) -> Option<rt_instance::InstanceHit> {
        self.0.intersect_with(ray, stats)
    }
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<rt_instance::InstanceHit>],
        stats: &mut S,
    ) {
        if STREAM {
            self.0.intersect_bundle_with(rays, out, stats);
        } else {
            self.lose(rays, out, stats);
        }
    }
    fn intersect_stream_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<rt_instance::InstanceHit>],
        stats: &mut S,
    ) {
        if STREAM {
            self.lose(rays, out, stats);
        } else {
            self.0.intersect_stream_with(rays, out, stats);
        }
    }
    forward_to_linear!();
}

#[test]
fn two_level_bundles_or_streams_that_lose_a_lane_fail_with_its_ray_named() {
    let case = rt_conformance::two_level_scene("mirrored_and_scaled").remove(0);
    let bundle = rt_conformance::check_two_level_case::<LosesALane<false>>(&[brute_bottom], &case)
        .expect_err("a bundle that loses a hit must be caught");
    assert!(
        bundle.contains("a bundle of") && bundle.contains("ray: Ray::"),
        "{bundle}"
    );
    let stream = rt_conformance::check_two_level_case::<LosesALane<true>>(&[brute_bottom], &case)
        .expect_err("a stream that loses a hit must be caught");
    assert!(
        stream.contains("a stream of") && stream.contains("ray: Ray::"),
        "{stream}"
    );
}

/// Brute force, except that building from a mesh or another source reads the triangles in
/// reverse order, as a builder that numbered them from the wrong end would.
struct Reversed(BruteForce<Triangle>);

impl Accel for Reversed {
    forward_to_brute_force!();
    const NAME: &'static str = "reversed";
    fn build_from<G: rt_core::Geometry<Prim = Triangle> + ?Sized>(g: &G, _: &()) -> Self {
        let reversed: Vec<Triangle> = (0..g.len()).rev().map(|i| g.prim(i)).collect();
        Self(BruteForce::build(&reversed, &()))
    }
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
}

#[test]
fn a_structure_that_numbers_a_mesh_wrongly_fails_the_geometry_check() {
    let failure =
        std::panic::catch_unwind(|| rt_conformance::check_geometry_sources::<Reversed>(&()))
            .expect_err("a reversed numbering must be caught");
    let message = failure
        .downcast_ref::<String>()
        .expect("the kit panics with a formatted message");
    assert!(
        message.contains("reversed with () built from a Mesh on scene `shared_edge`"),
        "{message}"
    );
}

/// A refit that accepts every geometry and changes nothing, as one that forgot to re-read the
/// primitives would.
impl rt_core::Refit for Reversed {
    fn refit<G: rt_core::Geometry<Prim = Triangle> + ?Sized>(
        &mut self,
        _: &G,
    ) -> Result<(), rt_core::RefitError> {
        Ok(())
    }
}

#[test]
fn a_refit_that_ignores_the_motion_fails_the_refit_kit() {
    let s = scene("shared_edge");
    let e = rt_conformance::check_refit_case::<Reversed>(&(), &s.triangles, &s.rays)
        .expect_err("answers for the old places must be caught");
    assert!(e.starts_with("after refitting to a wave:"), "{e}");
}

/// A structure seen through `DynAccel` whose slice queries are wrong on purpose: the last ray of
/// a slice gets no answer (`LOSES`), or the slices count nothing (`!LOSES`). Every single query
/// is brute force's.
struct SlicedWrong<const LOSES: bool>(BruteForce<Triangle>);

impl<const LOSES: bool> rt_core::DynAccel<Triangle> for SlicedWrong<LOSES> {
    fn name(&self) -> &'static str {
        "sliced-wrong"
    }
    fn bounds_dyn(&self) -> Aabb {
        self.0.bounds()
    }
    fn memory_bytes_dyn(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats_dyn(&self) -> BuildStats {
        self.0.build_stats()
    }
    fn regions_dyn(&self) -> Vec<rt_core::Region> {
        Vec::new()
    }
    fn intersect_dyn(&self, ray: &Ray, counters: Option<&mut rt_core::Counters>) -> Option<Hit> {
        rt_core::DynAccel::intersect_dyn(&self.0, ray, counters)
    }
    fn occluded_dyn(&self, ray: &Ray, counters: Option<&mut rt_core::Counters>) -> bool {
        rt_core::DynAccel::occluded_dyn(&self.0, ray, counters)
    }
    fn ball_query_dyn(
        &self,
        query: &mut dyn BallQuery<Triangle>,
        counters: Option<&mut rt_core::Counters>,
    ) {
        rt_core::DynAccel::ball_query_dyn(&self.0, query, counters);
    }
    fn trace_dyn(&self, ray: &Ray, any: bool) -> (Option<Hit>, rt_core::Trace) {
        rt_core::DynAccel::trace_dyn(&self.0, ray, any)
    }
    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut rt_core::Counters>,
    ) {
        let counters = if LOSES { counters } else { None };
        rt_core::DynAccel::intersect_all(&self.0, rays, out, counters);
        if let (true, Some(last)) = (LOSES, out.last_mut()) {
            *last = None;
        }
    }
    fn occluded_all(
        &self,
        rays: &[Ray],
        out: &mut [bool],
        counters: Option<&mut rt_core::Counters>,
    ) {
        let counters = if LOSES { counters } else { None };
        rt_core::DynAccel::occluded_all(&self.0, rays, out, counters);
    }
    fn closest_points_all(
        &self,
        points: &[(Vec3, f32)],
        out: &mut [Option<rt_core::PointHit>],
        counters: Option<&mut rt_core::Counters>,
    ) {
        let counters = if LOSES { counters } else { None };
        rt_core::DynAccel::closest_points_all(&self.0, points, out, counters);
    }
}

/// The slice check passes brute force and fails a structure whose slice answers or slice counts
/// differ from its single queries'.
#[test]
fn slice_queries_that_differ_from_single_ones_fail() {
    let s = scene("shared_edge");
    // The last ray must hit, so that losing its answer shows.
    let mut rays = s.rays.clone();
    let brute = BruteForce::build(&s.triangles, &());
    let hitting = *rays.iter().find(|r| brute.intersect(r).is_some()).unwrap();
    rays.push(hitting);
    let points = rt_conformance::scene_points(&s.triangles, &rays);
    rt_conformance::compare_slices(&brute, &rays, &points).unwrap();
    let lost = rt_conformance::compare_slices(&SlicedWrong::<true>(brute.clone()), &rays, &points)
        .expect_err("a lost answer must be caught");
    assert!(lost.contains("intersect_all slot"), "{lost}");
    let uncounted = rt_conformance::compare_slices(&SlicedWrong::<false>(brute), &rays, &points)
        .expect_err("slices that count nothing must be caught");
    assert!(
        uncounted.contains("the slice queries counted"),
        "{uncounted}"
    );
}

/// A structure whose ordered bundle queries answer in the order's positions instead of the
/// rays' own slots (`out[k]` for the ray `order[k]`). Everything else is brute force's.
struct MisplacesOrdered(BruteForce<Triangle>);

impl Accel for MisplacesOrdered {
    forward_to_brute_force!();
    const NAME: &'static str = "misplaces-ordered";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn intersect_bundle_ordered_with<S: Stats>(
        &self,
        rays: &[Ray],
        order: &[u32],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        for (k, &i) in order.iter().enumerate() {
            if let (Some(ray), Some(slot)) = (rays.get(i as usize), out.get_mut(k)) {
                *slot = self.0.intersect_with(ray, stats);
            }
        }
    }
}

/// The bundle check catches ordered bundle queries that write an answer to the wrong slot.
#[test]
fn ordered_bundle_queries_that_misplace_answers_fail() {
    let s = scene("shared_edge");
    let brute = BruteForce::build(&s.triangles, &());
    rt_conformance::compare_bundles(&brute, &s.rays, true).unwrap();
    let e = rt_conformance::compare_bundles(&MisplacesOrdered(brute), &s.rays, true)
        .expect_err("a misplaced answer must be caught");
    assert!(
        e.starts_with("misplaces-ordered: intersect_bundle_ordered_with (every ray, shuffled)"),
        "{e}"
    );
}

/// A structure whose bundle traversal drops a lane: the last lane of every bundle of two or more
/// rays gets no hit (and counts as not occluded). Single rays and rays that travel alone are
/// brute force's.
struct DropsLane(BruteForce<Triangle>);

impl Accel for DropsLane {
    forward_to_brute_force!();
    const NAME: &'static str = "drops-lane";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        self.lanes(rays, out.len(), |slot, ray, dropped| {
            out[slot] = (!dropped)
                .then(|| self.0.intersect_with(ray, stats))
                .flatten();
        });
    }
    fn occluded_bundle_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        self.lanes(rays, out.len(), |slot, ray, dropped| {
            out[slot] = !dropped && self.0.occluded_with(ray, stats);
        });
    }
}

impl DropsLane {
    /// Calls `answer(slot, ray, dropped)` for each of the first `slots` rays, `dropped` for the
    /// last lane of a bundle of two or more.
    fn lanes(&self, rays: &[Ray], slots: usize, mut answer: impl FnMut(usize, &Ray, bool)) {
        let rays = &rays[..rays.len().min(slots)];
        rt_simd::bundle::for_each_bundle(rays, |group| match group {
            rt_simd::bundle::Group::Bundle(b) => {
                for i in 0..b.len() {
                    let slot = b.slot[i] as usize;
                    answer(slot, &rays[slot], b.len() > 1 && i == b.len() - 1);
                }
            }
            rt_simd::bundle::Group::Single(slot, ray) => answer(slot, ray, false),
        });
    }
}

/// The bundle check passes brute force (whose bundle queries test each triangle against a
/// bundle's lanes) and fails a bundle traversal that drops a lane, naming the ray, the order and
/// the bundle size.
#[test]
fn a_bundle_traversal_that_drops_a_lane_fails() {
    let s = scene("shared_edge");
    let brute = rt_simd::BundledBruteForce::build(&s.triangles, &());
    rt_conformance::compare_bundles(&brute, &s.rays, true).unwrap();
    let e = rt_conformance::compare_bundles(&DropsLane(brute.0), &s.rays, true)
        .expect_err("a dropped lane must be caught");
    assert!(
        e.starts_with("drops-lane: intersect_bundle gives None where intersect gives Some"),
        "{e}"
    );
    assert!(
        e.contains("in a slice of 7 rays (rays as given, slice lengths cycling upwards), slot"),
        "{e}"
    );
    // Through the whole kit too: the scene's check fails on the bundles.
    let e = check_case_within::<DropsLane>(&(), &s.triangles, &s.rays, Duration::from_secs(20))
        .expect_err("the kit must run the bundle check");
    assert!(e.contains("intersect_bundle gives"), "{e}");
}

/// A structure whose stream queries lose the answers of rays past the 256th of a stream (no
/// hit, not occluded), as a stream traversal that mishandles its chunks might. Everything else
/// is brute force's.
struct LosesLongStreams(BruteForce<Triangle>);

impl Accel for LosesLongStreams {
    forward_to_brute_force!();
    const NAME: &'static str = "loses-long-streams";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn intersect_stream_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        for (i, (slot, ray)) in out.iter_mut().zip(rays).enumerate() {
            *slot = (i < 256)
                .then(|| self.0.intersect_with(ray, stats))
                .flatten();
        }
    }
    fn occluded_stream_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        for (i, (slot, ray)) in out.iter_mut().zip(rays).enumerate() {
            *slot = i < 256 && self.0.occluded_with(ray, stats);
        }
    }
}

/// The stream check passes brute force (whose stream queries are the default loop) and fails
/// stream queries that lose answers in long streams, naming the ray, the order and the stream's
/// length; the whole kit runs it.
#[test]
fn stream_queries_that_lose_answers_fail() {
    let s = scene("shared_edge");
    let brute = BruteForce::build(&s.triangles, &());
    rt_conformance::compare_streams(&brute, &s.rays, true).unwrap();
    let e = rt_conformance::compare_streams(&LosesLongStreams(brute), &s.rays, true)
        .expect_err("a lost answer must be caught");
    assert!(
        e.starts_with("loses-long-streams: intersect_stream gives None where intersect gives Some"),
        "{e}"
    );
    assert!(e.contains("(rays as given, "), "{e}");
    assert!(e.contains("stream of"), "{e}");
    let e =
        check_case_within::<LosesLongStreams>(&(), &s.triangles, &s.rays, Duration::from_secs(20))
            .expect_err("the kit must run the stream check");
    assert!(e.contains("intersect_stream gives"), "{e}");
}

/// Brute force with a bundle walk of its own: every lane of a bundle tested against every
/// triangle through the shared eight-lane tests, except that with `DROP` the last lane of every
/// bundle gets no answer; with `ALONE` the bundle queries are the default loop over single rays.
struct Walker<const DROP: bool, const ALONE: bool>(BruteForce<Triangle>, Vec<Triangle>);

impl<const DROP: bool, const ALONE: bool> Walker<DROP, ALONE> {
    fn query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        stats: &mut S,
        answer: impl FnMut(usize, Option<Hit>),
    ) {
        let ids: Vec<u32> = (0..self.1.len() as u32).collect();
        let bounds = self.0.bounds();
        rt_simd::bundle::walk_groups::<S, ANY>(
            rays,
            slots,
            stats,
            |ray, stats| {
                let hit = self.0.intersect_with(ray, stats);
                hit.map(|h| if ANY { Hit { t: f32::NAN, ..h } } else { h })
            },
            |b| b.route(&bounds, |_| true),
            |b, lanes, stats| {
                stats.node_visit();
                stats.bundle_lanes(b.len() as u32, b.len() as u32);
                let mut mailbox = rt_simd::bundle::LaneMailbox::new();
                let all = b.all_lanes();
                let t_hi = lanes.far_end();
                rt_simd::bundle::test_primitives::<Triangle, S, ANY>(
                    &self.1,
                    &ids,
                    (b, t_hi),
                    lanes,
                    if DROP { all >> 1 } else { all },
                    &mut mailbox,
                    stats,
                );
                0
            },
            answer,
        );
    }
}

impl<const DROP: bool, const ALONE: bool> Accel for Walker<DROP, ALONE> {
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "walker";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()), prims.to_vec())
    }
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        if ALONE {
            rt_core::bundle::intersect_each(self, rays, out, stats);
        } else {
            self.query::<S, false>(rays, out.len(), stats, |slot, hit| out[slot] = hit);
        }
    }
    fn occluded_bundle_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        if ALONE {
            rt_core::bundle::occluded_each(self, rays, out, stats);
        } else {
            self.query::<S, true>(rays, out.len(), stats, |slot, hit| {
                out[slot] = hit.is_some()
            });
        }
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
}

/// The coherent-bundle check passes a bundle walk that answers as its single rays, and fails
/// one that drops a lane and one whose rays all go alone.
#[test]
fn the_coherent_bundle_check_fails_a_dropped_lane_and_rays_that_go_alone() {
    let tris = rt_scene::scenes::builtin("teapot:1000")
        .expect("a built-in scene")
        .triangles();
    let size = (32, 24);
    rt_conformance::check_coherent_bundles_on(
        &Walker::<false, false>::build(&tris, &()),
        &tris,
        size,
        true,
    )
    .unwrap();
    let e = rt_conformance::check_coherent_bundles_on(
        &Walker::<true, false>::build(&tris, &()),
        &tris,
        size,
        true,
    )
    .unwrap_err();
    assert!(e.starts_with("primary ray "), "{e}");
    let e = rt_conformance::check_coherent_bundles_on(
        &Walker::<false, true>::build(&tris, &()),
        &tris,
        size,
        true,
    )
    .unwrap_err();
    assert!(e.starts_with("no bundle step at all"), "{e}");
}

/// Brute force whose box queries are wrong on purpose: it prunes with open boxes (`OPEN`), so a
/// triangle that only touches the query box is never offered, or it goes on offering after the
/// query stopped (`!OPEN`).
struct BoxesWrong<const OPEN: bool>(BruteForce<Triangle>);

impl<const OPEN: bool> Accel for BoxesWrong<OPEN> {
    forward_to_brute_force!();
    const NAME: &'static str = "boxes-wrong";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn box_query<Q: BoxQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.box_query(&mut WrongBoxes::<Q, OPEN>(query), stats);
    }
}

/// The query [`BoxesWrong`] hands brute force: it hides triangles that only touch the box
/// (`OPEN`), or never stops the walk (`!OPEN`).
struct WrongBoxes<'a, Q, const OPEN: bool>(&'a mut Q);

impl<Q: BoxQuery<Triangle>, const OPEN: bool> BoxQuery<Triangle> for WrongBoxes<'_, Q, OPEN> {
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn test(&mut self, t: &Triangle, id: u32) -> ControlFlow<()> {
        let (tb, b) = (t.bounds(), self.0.bounds());
        if OPEN {
            if tb.min.cmplt(b.max).all() && b.min.cmplt(tb.max).all() {
                return self.0.test(t, id);
            }
            return ControlFlow::Continue(());
        }
        let _ = self.0.test(t, id);
        ControlFlow::Continue(())
    }
    fn test_triangle(&mut self, v: [Vec3; 3], id: u32) -> ControlFlow<()> {
        self.test(&Triangle::new(v[0], v[1], v[2]), id)
    }
}

#[test]
fn box_queries_that_miss_touching_triangles_or_go_on_after_a_stop_fail_the_kit() {
    let s = scene("shared_edge");
    let open = check_case_within::<BoxesWrong<true>>(&(), &s.triangles, &s.rays, STALL_LIMIT)
        .expect_err("a triangle touching the box must be found");
    assert!(
        open.contains("overlapping disagrees with brute force") && open.contains("missing ["),
        "{open}"
    );
    let goes_on = check_case_within::<BoxesWrong<false>>(&(), &s.triangles, &s.rays, STALL_LIMIT)
        .expect_err("offering primitives after the query stopped must be caught");
    assert!(goes_on.contains("stops at its first find"), "{goes_on}");
}

/// Brute force that implements only the ball query, pruned by each triangle's box: its box and
/// ray queries run the trait's defaults, through the ball around the box.
struct BallOnly(BruteForce<Triangle>);

impl Accel for BallOnly {
    forward_to_brute_force!();
    const NAME: &'static str = "ball-only";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(&mut Pruned(query), stats);
    }
}

/// A ball query that sees only the triangles whose box lies within its radius, as a structure
/// that prunes by boxes offers them.
struct Pruned<'a, Q>(&'a mut Q);

impl<Q: BallQuery<Triangle>> BallQuery<Triangle> for Pruned<'_, Q> {
    fn center(&self) -> Vec3 {
        self.0.center()
    }
    fn radius_sq(&self) -> f32 {
        self.0.radius_sq()
    }
    fn test(&mut self, t: &Triangle, id: u32) {
        if t.bounds().distance_squared(self.center()) <= self.radius_sq() {
            self.0.test(t, id);
        }
    }
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        self.0.test_triangle(v0, e1, e2, id);
    }
}

#[test]
fn the_default_box_query_through_the_ball_passes_the_kit() {
    // Its ray queries run the defaults too: box and ball around the ray's segment, which an
    // origin far from the scene (`far_origins`) must not shrink below the rounding of `at`.
    for name in [
        "shared_edge",
        "large_coordinates",
        "planar_triangles",
        "far_origins",
    ] {
        let s = scene(name);
        check_case_within::<BallOnly>(&(), &s.triangles, &s.rays, STALL_LIMIT)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

/// Brute force whose closest-point queries see every triangle with its vertices rotated
/// (`v1, v2, v0`): the nearest points are the same places, but the edges and vertices they lie
/// on are numbered wrongly, as a structure that stored triangles in another vertex order would
/// report them.
struct Rotated(BruteForce<Triangle>);

impl Accel for Rotated {
    forward_to_brute_force!();
    const NAME: &'static str = "rotated";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(&mut RotatedBall(query), stats);
    }
    fn box_query<Q: BoxQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.box_query(query, stats);
    }
}

struct RotatedBall<'a, Q>(&'a mut Q);

impl<Q: BallQuery<Triangle>> BallQuery<Triangle> for RotatedBall<'_, Q> {
    fn center(&self) -> Vec3 {
        self.0.center()
    }
    fn radius_sq(&self) -> f32 {
        self.0.radius_sq()
    }
    fn test(&mut self, t: &Triangle, id: u32) {
        self.0.test(&Triangle::new(t.v1, t.v2, t.v0), id);
    }
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        self.test(&Triangle::new(v0, v0 + e1, v0 + e2), id);
    }
}

#[test]
fn a_closest_point_on_the_wrong_feature_fails_the_kit() {
    let s = scene("shared_edge");
    let e = check_case_within::<Rotated>(&(), &s.triangles, &s.rays, STALL_LIMIT)
        .expect_err("edges and vertices numbered from the wrong vertex must be caught");
    assert!(
        e.contains("closest_point disagrees with brute force") && e.contains("feature"),
        "{e}"
    );
}

/// Brute force whose ray queries beyond the closest and any hit are wrong on purpose: it offers
/// every hit twice (`MODE` 0), goes on offering after the query stopped (1), or takes every
/// repeatable query for a closest hit and stops looking behind the nearest hit it offered,
/// which loses the hit behind one a filter rejects (2).
struct RaysWrong<const MODE: u8>(BruteForce<Triangle>);

impl<const MODE: u8> Accel for RaysWrong<MODE> {
    forward_to_brute_force!();
    const NAME: &'static str = "rays-wrong";
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn box_query<Q: BoxQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.box_query(query, stats);
    }
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        let mut wrong = WrongRays::<Q, MODE>(query, f32::INFINITY);
        self.0.ray_query(ray, &mut wrong, stats);
    }
}

/// The query [`RaysWrong`] hands brute force, with the nearest `t` it offered.
struct WrongRays<'a, Q, const MODE: u8>(&'a mut Q, f32);

impl<Q: RayQuery, const MODE: u8> RayQuery for WrongRays<'_, Q, MODE> {
    const OCCLUSION: bool = Q::OCCLUSION;
    const REPEATABLE: bool = Q::REPEATABLE;
    fn t_far(&self) -> f32 {
        if MODE == 2 && Q::REPEATABLE {
            self.0.t_far().min(self.1)
        } else {
            self.0.t_far()
        }
    }
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        match MODE {
            0 => {
                self.0.offer(prim, hit)?;
                self.0.offer(prim, hit)
            }
            1 => {
                let _ = self.0.offer(prim, hit);
                ControlFlow::Continue(())
            }
            _ => {
                self.1 = self.1.min(hit.t);
                self.0.offer(prim, hit)
            }
        }
    }
}

#[test]
fn ray_queries_that_repeat_a_hit_go_on_after_a_stop_or_prune_a_filter_s_hits_fail_the_kit() {
    let s = scene("shared_edge");
    let check = |e: Result<(), String>, what: &str, want: &str| {
        let e = e.expect_err(what);
        assert!(e.contains(want) && e.contains("rays-file line:"), "{e}");
    };
    check(
        check_case_within::<RaysWrong<0>>(&(), &s.triangles, &s.rays, STALL_LIMIT),
        "a hit offered twice must be caught",
        "all_hits disagrees with brute force",
    );
    check(
        check_case_within::<RaysWrong<1>>(&(), &s.triangles, &s.rays, STALL_LIMIT),
        "offers after the query stopped must be caught",
        "ray_query (stopping) disagrees",
    );
    // A hit lost behind a rejected one needs a scene where a farther triangle has the larger
    // index: the kit has several; every one that fails must fail on a filtered query.
    let failures: Vec<String> = rt_conformance::SCENES
        .iter()
        .filter_map(|name| {
            let s = scene(name);
            check_case_within::<RaysWrong<2>>(&(), &s.triangles, &s.rays, STALL_LIMIT).err()
        })
        .collect();
    assert!(
        !failures.is_empty(),
        "a hit lost behind a rejected one must be caught"
    );
    for e in failures {
        assert!(
            e.contains("_filtered disagrees") && e.contains("rays-file line:"),
            "{e}"
        );
    }
}

#[test]
fn the_closed_meshes_scene_winds_once_in_the_walls_and_the_ball_and_never_in_the_cavity() {
    let s = scene("closed_meshes");
    let w = |p: Vec3| rt_sdf::winding_number_exact(&s.triangles, p).unwrap();
    for (p, expected) in [
        (Vec3::new(0.7, 0.1, -0.2), 1.0),
        (Vec3::new(3.1, 0.2, 0.1), 1.0),
        (Vec3::new(0.1, -0.2, 0.05), 0.0),
        (Vec3::new(2.0, 0.0, 0.0), 0.0),
    ] {
        assert!((w(p) - expected).abs() < 1e-9, "{p}: {}", w(p));
    }
}

/// Brute force that gets signed distances or crossing parity wrong through its walks, the only
/// way a structure can (rt-sdf's `SignedDistance` signs every structure's closest point the
/// same way): a ball query that offers only odd-numbered primitives, so the nearest is often
/// missed (`MODE` 0), or a ray walk that offers every hit twice, so every count is even (1).
struct SignWrong<const MODE: u8>(BruteForce<Triangle>);

/// A ball query that sees only odd-numbered primitives.
struct OddOnly<'a, Q>(&'a mut Q);

impl<Q: BallQuery<Triangle>> BallQuery<Triangle> for OddOnly<'_, Q> {
    fn center(&self) -> Vec3 {
        self.0.center()
    }
    fn radius_sq(&self) -> f32 {
        self.0.radius_sq()
    }
    fn test(&mut self, prim: &Triangle, id: u32) {
        if id % 2 == 1 {
            self.0.test(prim, id);
        }
    }
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        if id % 2 == 1 {
            self.0.test_triangle(v0, e1, e2, id);
        }
    }
}

/// A ray query offered every hit twice.
struct Twice<'a, Q>(&'a mut Q);

impl<Q: RayQuery> RayQuery for Twice<'_, Q> {
    fn t_far(&self) -> f32 {
        self.0.t_far()
    }
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        self.0.offer(prim, hit)?;
        self.0.offer(prim, hit)
    }
}

impl<const MODE: u8> Accel for SignWrong<MODE> {
    forward_to_brute_force!();
    const NAME: &'static str = "sign-wrong";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if MODE == 1 {
            self.0.ray_query(ray, &mut Twice(query), stats);
        } else {
            self.0.ray_query(ray, query, stats);
        }
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        if MODE == 0 {
            self.0.ball_query(&mut OddOnly(query), stats);
        } else {
            self.0.ball_query(query, stats);
        }
    }
    fn box_query<Q: BoxQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.box_query(query, stats);
    }
}

#[test]
fn a_wrong_signed_distance_or_a_wrong_parity_fails_the_kit() {
    let s = scene("closed_meshes");
    let e = check_part::<SignWrong<0>>(&(), &s.triangles, &s.rays, Part::Inside, STALL_LIMIT)
        .expect_err("a signed distance from the wrong primitive must be caught");
    assert!(
        e.contains("signed_distance disagrees with brute force") && e.contains("point:"),
        "{e}"
    );
    let e = check_part::<SignWrong<1>>(&(), &s.triangles, &s.rays, Part::Inside, STALL_LIMIT)
        .expect_err("a wrong crossing parity must be caught");
    assert!(e.contains("inside_by_parity disagrees"), "{e}");
}

/// Brute force whose saved file loads wrongly on purpose: the loaded structure answers without
/// its last primitive (`MODE` 0), or its loader trusts an index the file gives (1).
struct SavedWrong<const MODE: u8>(BruteForce<Triangle>);

impl<const MODE: u8> Accel for SavedWrong<MODE> {
    forward_to_brute_force!();
    const NAME: &'static str = "saved-wrong";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn box_query<Q: BoxQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.box_query(query, stats);
    }
}

impl<const MODE: u8> Persist for SavedWrong<MODE> {
    const KIND: &'static str = "kit::SavedWrong";
    const LAYOUT: u32 = 1;
    type Saved = Triangle;
    fn write_sections<'a>(&'a self, w: &mut Writer<'a>) {
        w.section("first", &[0u32]);
        self.0.write_sections(w);
    }
    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError> {
        let first = r.value::<u32>("first")? as usize;
        if MODE == 1 {
            // Trusts `first`: a hostile file makes this index out of bounds.
            let _ = r.section::<Triangle>("prims")?[first];
        }
        if MODE == 0 {
            // Answers without the last primitive.
            let mut prims: Vec<Triangle> = r.section("prims")?;
            prims.pop();
            return Ok(Self(BruteForce::build(&prims, &())));
        }
        Ok(Self(BruteForce::read_sections(r)?))
    }
    fn check_loaded(&self) -> Result<(), LoadError> {
        self.0.check_loaded()
    }
}

#[test]
fn a_saved_structure_that_answers_otherwise_or_trusts_its_file_fails_the_kit() {
    let s = scene("closed_meshes");
    let e = rt_conformance::check_saved_case::<SavedWrong<0>>(&(), &s.triangles, &s.rays, 1)
        .expect_err("a loaded structure without its last primitive must be caught");
    assert!(
        e.contains("after loading") || e.contains("another file"),
        "{e}"
    );
    let s = scene("one_triangle");
    let e = rt_conformance::check_saved_case::<SavedWrong<1>>(&(), &s.triangles, &s.rays, 1)
        .expect_err("a loader that indexes with a number from the file must be caught");
    assert!(e.contains("loading panics with bytes"), "{e}");
}

/// Brute force itself saves and loads: every scene, answers bit for bit, damage refused.
#[test]
fn brute_force_saves_and_loads() {
    rt_conformance::check_saved_scenes::<BruteForce<Triangle>>();
}

/// Brute force whose walk never offers an occlusion query anything: its closest hit is right,
/// its any hit wrong on every ray that hits.
struct NeverBlocked(BruteForce<Triangle>);

impl Accel for NeverBlocked {
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "never-blocked";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()))
    }
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if !Q::OCCLUSION {
            self.0.ray_query(ray, query, stats);
        }
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
}

/// The kit's parts are checked apart: a structure with a wrong any hit passes the closest-hit
/// part and fails the any-hit part (naming the ray), on a fixed scene and on random scenes.
#[test]
fn parts_are_checked_apart() {
    use rt_conformance::check_random_part;
    let s = scene("one_triangle");
    let part = |p| check_part::<NeverBlocked>(&(), &s.triangles, &s.rays, p, STALL_LIMIT);
    assert!(part(Part::Closest).is_ok(), "{:?}", part(Part::Closest));
    let any = part(Part::Any).expect_err("the any-hit part must fail");
    assert!(
        any.contains("occluded disagrees") && any.contains("rays-file line: "),
        "{any}"
    );
    assert!(
        check_random_part::<NeverBlocked>(&(), Part::Closest, STALL_LIMIT).is_ok(),
        "random scenes, closest hit"
    );
    let random = check_random_part::<NeverBlocked>(&(), Part::Any, STALL_LIMIT)
        .expect_err("the any-hit part fails on random scenes");
    assert!(random.contains("occluded"), "{random}");
    // All parts together fail too.
    assert!(check_case_within::<NeverBlocked>(&(), &s.triangles, &s.rays, STALL_LIMIT).is_err());
}

/// Brute force that finds nothing off the thread that built it, as a structure keeping its
/// primitives in a thread-local would: every single query the kit makes on its own thread is
/// right, every batch (run on the kit's pool) wrong.
struct ThreadBound(BruteForce<Triangle>, std::thread::ThreadId);

impl ThreadBound {
    fn here(&self) -> bool {
        std::thread::current().id() == self.1
    }
}

impl Accel for ThreadBound {
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "thread-bound";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()), std::thread::current().id())
    }
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if self.here() {
            self.0.ray_query(ray, query, stats);
        }
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        if self.here() {
            self.0.ball_query(query, stats);
        }
    }
    fn box_query<Q: BoxQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        if self.here() {
            self.0.box_query(query, stats);
        }
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
}

/// The batch checks can fail: a structure right on its own thread only fails each part that
/// has a batch, naming the batch query, and `compare_batches` alone fails it too; brute force
/// passes it.
#[test]
fn batches_answer_on_every_thread() {
    let s = scene("one_triangle");
    let part = |p| check_part::<ThreadBound>(&(), &s.triangles, &s.rays, p, STALL_LIMIT);
    assert!(part(Part::Closest).is_ok(), "{:?}", part(Part::Closest));
    assert!(part(Part::Any).is_ok(), "{:?}", part(Part::Any));
    for (p, query) in [
        (Part::Bundles, "batch::intersect of"),
        (Part::ClosestPoints, "batch::closest_points of"),
        (Part::BoxOverlap, "batch::overlapping of"),
        (Part::AllHits, "batch::count_hits of"),
        (Part::Inside, "rt_sdf::batch::signed_distances of"),
    ] {
        let e = part(p).expect_err(query);
        assert!(e.contains(query) && e.contains("on two threads"), "{e}");
    }
    let accel = ThreadBound::build(&s.triangles, &());
    let e = rt_conformance::compare_batches(&accel, &s.triangles, &s.rays).unwrap_err();
    assert!(e.contains("batch::intersect of"), "{e}");
    let brute = BruteForce::build(&s.triangles, &());
    rt_conformance::compare_batches(&brute, &s.triangles, &s.rays).unwrap();
}

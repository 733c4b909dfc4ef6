//! The conformance kit never hangs and always names the ray: structures that loop forever or
//! panic on one ray fail with a short message naming that ray.

use rt_core::conformance::{check_case_within, check_random, scene};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Accel, BallQuery, BruteForce, BuildStats, Hit, Ray, Stats, Triangle};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Lets the looping structure's stuck thread finish once its test has seen the failure.
static RELEASE: AtomicBool = AtomicBool::new(false);

/// The rays a broken structure below gets wrong: those heading mostly down.
fn cursed(ray: &Ray) -> bool {
    ray.is_valid() && ray.dir.y < -0.5 * ray.dir.length()
}

/// Brute force, except that `intersect` never returns on a cursed ray (like a DDA stepping by
/// zero), or panics there.
struct Broken<const PANICS: bool>(BruteForce<Triangle>);

impl<const PANICS: bool> Accel for Broken<PANICS> {
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "broken";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()))
    }
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        if cursed(ray) {
            assert!(
                !PANICS,
                "index out of bounds: the len is 3 but the index is 7"
            );
            while !RELEASE.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        self.0.intersect_with(ray, stats)
    }
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        self.0.occluded_with(ray, stats)
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
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "stops-at-first";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()))
    }
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        self.0.intersect_with(ray, stats)
    }
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        self.0.occluded_with(ray, stats)
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        let mut once = Once {
            inner: query,
            offered: false,
        };
        self.0.ball_query(&mut once, stats);
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
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
    let source = include_str!("../src/conformance.rs");
    let start = source
        .find("conformance_tests!(@each $check, $accel;")
        .expect("the macro's scene list");
    let list = &source[start..];
    let list = &list[list.find(';').unwrap() + 1..list.find(')').unwrap()];
    let listed: Vec<&str> = list.split_whitespace().collect();
    assert_eq!(listed, rt_core::conformance::SCENES);
}

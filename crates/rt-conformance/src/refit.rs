//! The kit for structures that follow moving primitives ([`Refit`]): refitted to moved
//! triangles, a structure must answer exactly like brute force built over them, and a refit it
//! refuses must leave it answering as before.

use super::{SCENES, aimed_rays, compare_points, compare_rays, proptest_failure, scene};
use super::{scene_points, small_triangles};
use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use rt_core::{Accel, BruteForce, Primitive, Ray, Refit, RefitError, Rng, Triangle};
use rt_scene::motion::{explode, wave};

/// `moved`, except that a triangle whose validity the motion changed keeps its old place: a
/// refit follows primitives that stay valid (or invalid), and the kit tests that, not the
/// motion's rounding.
fn keeping_validity(old: &[Triangle], moved: Vec<Triangle>) -> Vec<Triangle> {
    old.iter()
        .zip(moved)
        .map(|(o, m)| if o.is_valid() == m.is_valid() { m } else { *o })
        .collect()
}

/// `accel` against brute force over `tris`, on `rays` and points drawn from them.
fn agrees<A: Refit<Prim = Triangle>>(
    accel: &A,
    tris: &[Triangle],
    rays: &[Ray],
) -> Result<(), String> {
    let reference = BruteForce::build(tris, &());
    compare_rays(accel, &reference, rays).map_err(|m| m.to_string())?;
    let points = scene_points(tris, rays);
    compare_points(accel, &reference, &points).map_err(|m| m.to_string())
}

/// Builds `A` over `tris`, refits it through a wave, an explosion and back to `tris`, checking it
/// against brute force after each (on `rays` and on rays aimed at the moved triangles), and
/// checks that a refit to another count or to a triangle turned invalid is refused with the
/// structure left as it was.
///
/// # Errors
/// The first disagreement or wrong refusal, naming the step.
pub fn check_refit_case<A: Refit<Prim = Triangle>>(
    params: &A::Params,
    tris: &[Triangle],
    rays: &[Ray],
) -> Result<(), String> {
    let mut accel = A::build(tris, params);
    let motions = [
        ("a wave", keeping_validity(tris, wave(tris, 0.7))),
        (
            "an explosion",
            keeping_validity(tris, explode(tris, 0.2, 11)),
        ),
        ("the first places", tris.to_vec()),
    ];
    let mut rng = Rng::new(3);
    let mut last = tris.to_vec();
    for (step, moved) in motions {
        accel
            .refit(&moved)
            .map_err(|e| format!("refitting to {step}: {e}"))?;
        let lo = Vec3::splat(-3.0);
        let mut probe: Vec<Ray> = rays.to_vec();
        probe.extend(aimed_rays(&mut rng, &moved, lo, -lo, 100));
        agrees(&accel, &moved, &probe).map_err(|e| format!("after refitting to {step}: {e}"))?;
        last = moved;
    }
    if let Some(fewer) = last.len().checked_sub(1) {
        let want = RefitError::CountChanged {
            built: last.len(),
            now: fewer,
        };
        match accel.refit(&last[..fewer]) {
            Err(e) if e == want => {}
            other => return Err(format!("refitting to one triangle fewer gave {other:?}")),
        }
        agrees(&accel, &last, rays).map_err(|e| format!("after a refused refit: {e}"))?;
    }
    if let Some(i) = last.iter().position(|t| t.is_valid()) {
        let mut broken = last.clone();
        broken[i].v1 = Vec3::NAN;
        match accel.refit(&broken) {
            Err(RefitError::ValidityChanged { prim }) if prim == i as u32 => {}
            other => {
                return Err(format!(
                    "refitting with triangle {i} made invalid gave {other:?}"
                ));
            }
        }
        agrees(&accel, &last, rays)
            .map_err(|e| format!("after refusing an invalid triangle: {e}"))?;
    }
    Ok(())
}

/// [`check_refit_case`] on every adversarial scene, and on 300 small triangles with rays into
/// their cube.
///
/// # Panics
/// At the first failure, naming the scene.
pub fn check_refit_scenes<A: Refit<Prim = Triangle>>(params: &A::Params) {
    for name in SCENES {
        let s = scene(name);
        if let Err(e) = check_refit_case::<A>(params, &s.triangles, &s.rays) {
            panic!(
                "{} with {params:?}, refit kit, scene `{name}`: {e}",
                A::NAME
            );
        }
    }
    let tris = small_triangles(5, 300, 0.2);
    let rays = super::rays_into_cube(6, 300);
    if let Err(e) = check_refit_case::<A>(params, &tris, &rays) {
        panic!(
            "{} with {params:?}, refit kit, 300 small triangles: {e}",
            A::NAME
        );
    }
}

/// Proptest: random triangles (with repeats, so copies occur) refitted to random explosions of
/// waves, against brute force.
///
/// # Panics
/// With the shrunk failing case.
pub fn check_refit_random<A: Refit<Prim = Triangle>>(params: &A::Params) {
    let coord = || {
        prop_oneof![
            (-6i32..=6).prop_map(|i| i as f32 * 0.5),
            crate::float_in(-4.0, 4.0)
        ]
    };
    let vec3 = move || (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let tri = (vec3(), vec3(), vec3()).prop_map(|(a, b, c)| Triangle::new(a, b, c));
    let strategy = (
        prop::collection::vec(tri, 0..40),
        0usize..4,
        any::<u64>(),
        crate::float_in(0.0, 3.0),
    );
    let mut runner = TestRunner::new(Config {
        failure_persistence: None,
        ..Config::default()
    });
    let result = runner.run(&strategy, |(mut tris, repeats, seed, amount)| {
        // A few exact copies, which a BVH stores once.
        for i in 0..repeats.min(tris.len()) {
            tris.push(tris[i]);
        }
        let mut accel = A::build(&tris, params);
        let moved = keeping_validity(&tris, explode(&wave(&tris, amount), amount / 3.0, seed));
        accel
            .refit(&moved)
            .map_err(|e| TestCaseError::fail(format!("refit refused: {e}")))?;
        let mut rng = Rng::new(seed);
        let lo = Vec3::splat(-8.0);
        let rays = aimed_rays(&mut rng, &moved, lo, -lo, 40);
        agrees(&accel, &moved, &rays).map_err(TestCaseError::fail)?;
        Ok(())
    });
    if let Err(e) = result {
        panic!("{}", proptest_failure(A::NAME, "refit ", e));
    }
}

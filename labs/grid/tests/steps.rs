//! The lab's tests, step by step: `cargo test step_3` runs step 3's. Each step's tests use only
//! what that step and the ones before it build, and draw their scenes and rays from the
//! conformance kit (`rt_conformance`) and brute force.

use lab_grid::{GridParams, LabGrid, step1, step2, step3, step6};
use rt_conformance::{rays_into_cube, small_triangles};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Accel, BruteForce, Counters, Hit, Primitive, Ray, Triangle};

#[test]
fn step_1_scene_bounds_ignore_invalid_triangles() {
    let scene = rt_conformance::scene("nan_vertex");
    let expected = scene
        .triangles
        .iter()
        .filter(|t| t.is_valid())
        .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    assert_eq!(
        step1::scene_bounds(&scene.triangles),
        expected,
        "the box around the kit scene `nan_vertex`'s valid triangles (the one with a NaN vertex left out)"
    );
    assert!(
        step1::scene_bounds(&[]).is_empty(),
        "no triangles: an empty box (Aabb::EMPTY)"
    );
}

#[test]
fn step_1_slab_test_handles_the_corner_cases() {
    let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let along_x = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
    assert_eq!(
        step1::slab(&b, &along_x, f32::INFINITY).map(|t| t.0),
        Some(1.0),
        "ray {} runs along +x into the unit box: it enters at t = 1",
        along_x.to_line()
    );
    let far = step1::slab(&b, &along_x, f32::INFINITY).unwrap().1;
    assert!((2.0..2.0001).contains(&far), "exit at {far}");
    assert_eq!(step1::slab(&b, &along_x, 0.5), None, "t_max before the box");
    let behind = Ray::new(Vec3::new(2.0, 0.5, 0.5), Vec3::X);
    assert_eq!(
        step1::slab(&b, &behind, f32::INFINITY),
        None,
        "box behind the ray"
    );
    let inside = Ray::new(Vec3::splat(0.5), Vec3::Y);
    assert_eq!(
        step1::slab(&b, &inside, f32::INFINITY).map(|t| t.0),
        Some(0.0),
        "ray {} starts inside the box: it enters at t_min = 0",
        inside.to_line()
    );
    // In the face plane x = 0 with a direction of -0.0 along x: inside the closed box.
    let in_face = Ray::new(Vec3::new(0.0, -1.0, 0.5), Vec3::new(-0.0, 1.0, 0.0));
    assert_eq!(
        step1::slab(&b, &in_face, f32::INFINITY).map(|t| t.0),
        Some(1.0),
        "ray {} lies in the face plane x = 0 with a direction of -0.0 along x: inside the closed box, it enters at t = 1 (0 × ∞ is NaN: that axis must not narrow the interval)",
        in_face.to_line()
    );
    // Parallel to a slab and outside it: a miss, whatever the sign of the zero.
    for zero in [0.0, -0.0] {
        let outside = Ray::new(Vec3::new(2.0, -1.0, 0.5), Vec3::new(zero, 1.0, 0.0));
        assert_eq!(
            step1::slab(&b, &outside, f32::INFINITY),
            None,
            "ray {} runs parallel to the x slab, outside it: a miss",
            outside.to_line()
        );
    }
    // A flat box is still hit.
    let flat = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0));
    let down = Ray::new(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z);
    assert_eq!(
        step1::slab(&flat, &down, f32::INFINITY).map(|t| t.0),
        Some(1.0),
        "ray {} goes down onto a flat box (zero thickness in z): it enters at t = 1",
        down.to_line()
    );
}

#[test]
fn step_1_slab_test_agrees_with_the_reference() {
    let b = Aabb::new(Vec3::new(-0.5, -0.25, 0.0), Vec3::new(0.5, 0.75, 0.5));
    for ray in rays_into_cube(11, 4000) {
        let got = step1::slab(&b, &ray, ray.t_max);
        let want = b.intersect(&ray, ray.t_max);
        match (got, want) {
            (Some(g), Some(w)) => assert!(
                (g.0 - w.0).abs() <= 1e-5 * w.0.abs().max(1.0),
                "{}: entry {} against {}",
                ray.to_line(),
                g.0,
                w.0
            ),
            (None, None) => {}
            // A ray that only grazes an edge or corner may go either way by rounding.
            (_, Some(w)) if w.1 - w.0 < 1e-4 => {}
            (g, w) => panic!("{}: got {g:?}, expected {w:?}", ray.to_line()),
        }
    }
}

#[test]
fn step_2_resolution_gives_about_density_times_n_near_cubic_cells() {
    let cube = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let r = step2::resolution(&cube, 1000, 2.0);
    assert!(
        r[0] == r[1] && r[1] == r[2],
        "a cube gets equal resolutions: {r:?}"
    );
    let cells = r.iter().product::<u32>() as f32;
    assert!(
        (2000.0..=4000.0).contains(&cells),
        "{r:?}: {cells} cells for 2000"
    );
    let slab = Aabb::new(Vec3::ZERO, Vec3::new(4.0, 1.0, 1.0));
    let r = step2::resolution(&slab, 1000, 2.0);
    assert!(
        r[0] > 3 * r[1] && r[1] == r[2],
        "cells stay near cubes: {r:?}"
    );
    let flat = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0));
    let r = step2::resolution(&flat, 800, 2.0);
    assert_eq!(r[2], 1, "a flat axis gets one cell: {r:?}");
    assert!((1600..=3300).contains(&(r[0] * r[1])), "{r:?}");
    assert_eq!(
        step2::resolution(&cube, 0, 2.0),
        [1, 1, 1],
        "no triangles: one cell"
    );
    assert_eq!(
        step2::resolution(&Aabb::EMPTY, 10, 2.0),
        [1, 1, 1],
        "an empty box: one cell"
    );
    let huge = step2::resolution(&cube, 100_000_000, 2.0);
    assert!(
        huge.iter().all(|&n| (1..=step2::MAX_RES).contains(&n)),
        "{huge:?}"
    );
}

#[test]
fn step_2_every_triangle_is_listed_in_every_cell_it_touches_and_no_other() {
    let mut tris = small_triangles(5, 300, 0.3);
    tris.push(Triangle::new(Vec3::ZERO, Vec3::splat(f32::NAN), Vec3::X));
    let grid = LabGrid::build(&tris, &GridParams::default());
    let n = grid.res.iter().product::<u32>() as usize;
    assert_eq!(grid.cells.len(), n + 1, "one offset per cell, plus one");
    let margin = (grid.bounds.max - grid.bounds.min).max_element() * 1e-3;
    for z in 0..grid.res[2] {
        for y in 0..grid.res[1] {
            for x in 0..grid.res[0] {
                let c = [x, y, z];
                let cell = grid.cell_box(c);
                let listed = grid.cell(c);
                for (id, t) in tris.iter().enumerate() {
                    let b = t.bounds();
                    let inner = cell.intersection(&b);
                    let overlaps = t.is_valid() && (inner.max - inner.min).min_element() > margin;
                    let near =
                        t.is_valid() && cell.overlaps(&Aabb::new(b.min - margin, b.max + margin));
                    let has = listed.contains(&(id as u32));
                    assert!(!overlaps || has, "cell {c:?} misses triangle {id}");
                    assert!(near || !has, "cell {c:?} lists triangle {id}, far from it");
                }
            }
        }
    }
}

#[test]
fn step_3_walk_visits_the_cells_the_ray_crosses_in_order() {
    let grid = LabGrid::build(&small_triangles(7, 400, 0.2), &GridParams::default());
    let size = (grid.bounds.max - grid.bounds.min) / Vec3::from_array(grid.res.map(|r| r as f32));
    let tol = size.min_element() * 1e-3;
    for ray in rays_into_cube(8, 300) {
        let Some((t0, t1)) = step1::slab(&grid.bounds, &ray, ray.t_max) else {
            continue;
        };
        let mut walked = Vec::new();
        step3::walk(&grid, &ray, t0, t1, |c, a, b| {
            walked.push((c, a, b));
            false
        });
        // The cells the ray truly crosses for more than a sliver, by testing every cell.
        let mut crossed = Vec::new();
        for z in 0..grid.res[2] {
            for y in 0..grid.res[1] {
                for x in 0..grid.res[0] {
                    let c = [x, y, z];
                    if let Some((a, b)) = grid.cell_box(c).intersect(&ray, ray.t_max)
                        && b - a > tol
                    {
                        crossed.push(c);
                    }
                }
            }
        }
        for c in &crossed {
            assert!(
                walked.iter().any(|w| w.0 == *c),
                "{}: the walk skips cell {c:?}",
                ray.to_line()
            );
        }
        for w in walked.windows(2) {
            assert!(
                w[0].1 <= w[1].1,
                "{}: cells out of order: {w:?}",
                ray.to_line()
            );
        }
        assert!(
            walked.len() <= crossed.len() + 3,
            "{}: {} cells walked, {} crossed",
            ray.to_line(),
            walked.len(),
            crossed.len()
        );
        let mut count = 0;
        step3::walk(&grid, &ray, t0, t1, |_, _, _| {
            count += 1;
            true
        });
        assert_eq!(count, 1, "the walk goes on after visit returned true");
    }
}

rt_conformance::conformance_tests!(closest_hit: step_4_closest_hit, LabGrid, GridParams::default());

#[test]
fn step_4_a_hit_beyond_the_cell_does_not_end_the_walk() {
    // A long triangle hit far away, listed in every cell, and a small one hit nearer in a
    // later cell: stopping at the first hit found returns the long one.
    let tris = vec![
        Triangle::new(
            Vec3::new(-10.0, -10.0, 9.0),
            Vec3::new(10.0, -10.0, 0.0),
            Vec3::new(0.0, 10.0, 4.0),
        ),
        Triangle::new(
            Vec3::new(-0.1, -0.1, 3.0),
            Vec3::new(0.1, -0.1, 3.0),
            Vec3::new(0.0, 0.1, 3.0),
        ),
    ];
    let mut all = tris.clone();
    all.extend(
        small_triangles(3, 200, 0.05)
            .into_iter()
            .map(|t| Triangle::new(t.v0 * 10.0, t.v1 * 10.0, t.v2 * 10.0)),
    );
    let grid = LabGrid::build(&all, &GridParams::default());
    let reference = BruteForce::build(&all, &());
    for ray in rays_into_cube(4, 500)
        .iter()
        .map(|r| Ray::new(r.origin * 10.0, r.dir()))
    {
        assert!(
            Hit::agree(reference.intersect(&ray), grid.intersect(&ray)),
            "{}",
            ray.to_line()
        );
    }
}

// The conformance kit, as any structure meets it: every query against brute force, on every
// scene of the kit (one test each) and on random scenes.
rt_conformance::conformance_tests!(step_5_kit, LabGrid, GridParams::default());

#[test]
fn step_5_any_hit_stops_at_the_first_hit() {
    // A stack of 50 sheets across the rays' path: the closest hit must test all the sheets in
    // the first cell it reaches, the any-hit query only until one blocks.
    let tris: Vec<Triangle> = (0..50)
        .map(|i| {
            let z = i as f32 * 0.001;
            Triangle::new(
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(3.0, -1.0, z),
                Vec3::new(-1.0, 3.0, z),
            )
        })
        .collect();
    let grid = LabGrid::build(&tris, &GridParams::default());
    let (mut closest, mut any) = (Counters::default(), Counters::default());
    for i in 0..100 {
        let ray = Ray::new(Vec3::new(-0.5 + i as f32 * 0.01, 0.3, 5.0), -Vec3::Z);
        assert!(
            grid.intersect_with(&ray, &mut closest).is_some(),
            "ray {} must hit the stack of sheets (closest hit)",
            ray.to_line()
        );
        assert!(
            grid.occluded_with(&ray, &mut any),
            "ray {} must be blocked by the stack of sheets (any hit)",
            ray.to_line()
        );
    }
    assert!(
        any.prim_tests * 4 < closest.prim_tests,
        "any hit made {} tests, closest hit {}",
        any.prim_tests,
        closest.prim_tests
    );
}

#[test]
fn step_6_mailbox_remembers_the_last_slots_ids() {
    let mut m = step6::RayMailbox::new();
    assert!(!m.seen(3), "a new mailbox has seen nothing");
    assert!(m.seen(3), "the second time, 3 has been seen");
    for id in 100..100 + step6::SLOTS as u32 {
        assert!(
            !m.seen(id),
            "id {id} was never seen before, so seen({id}) is false"
        );
    }
    assert!(!m.seen(3), "{} later ids have pushed 3 out", step6::SLOTS);
}

#[test]
fn step_6_no_ray_tests_a_triangle_twice_in_a_row_of_cells() {
    // Ten large triangles, each listed in many cells, among small ones.
    let mut tris = small_triangles(9, 500, 0.05);
    tris.extend((0..10).map(|i| {
        let z = -0.9 + 0.18 * i as f32;
        Triangle::new(
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z + 0.1),
            Vec3::new(0.0, 1.0, z),
        )
    }));
    let plain = LabGrid::build(&tris, &GridParams::default());
    let boxed = LabGrid::build(&tris, &GridParams::mailboxed());
    let (mut without, mut with) = (Counters::default(), Counters::default());
    for ray in rays_into_cube(10, 500) {
        let a = plain.intersect_with(&ray, &mut without);
        let b = boxed.intersect_with(&ray, &mut with);
        assert_eq!(a, b, "{}", ray.to_line());
    }
    assert!(with.mailbox_skips > 0, "no test was skipped: {with:?}");
    assert_eq!(
        with.prim_tests + with.mailbox_skips,
        without.prim_tests,
        "each skip replaces exactly one test"
    );
}

rt_conformance::conformance_tests!(step_6_kit, LabGrid, GridParams::mailboxed());

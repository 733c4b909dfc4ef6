//! The lab's tests, step by step: `cargo test step_3` runs step 3's. Each step's tests use only
//! what that step and the ones before it build, and draw their scenes and rays from the
//! conformance kit (`rt_conformance`) and brute force.

use lab_kdtree::step2::Visit;
use lab_kdtree::{KdLabParams, LabKdTree, step1, step2, step3};
use rt_conformance::{rays_into_cube, small_triangles};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Accel, BruteForce, Counters, Hit, NoStats, Ray, Triangle};

/// Every node's index with its cell, the part of the tree's box it covers.
fn cells(lab: &LabKdTree) -> Vec<(usize, Aabb)> {
    let nodes = lab.tree.nodes();
    let mut out = Vec::new();
    let mut stack = vec![(0, lab.tree.bounds())];
    while let Some((i, cell)) = stack.pop() {
        out.push((i, cell));
        let node = &nodes[i];
        if !node.is_leaf() {
            let (mut below, mut above) = (cell, cell);
            below.max[node.axis()] = node.split();
            above.min[node.axis()] = node.split();
            stack.push((node.index(), below));
            stack.push((node.index() + 1, above));
        }
    }
    out
}

/// A tree over a soup, with its root split on some axis.
fn soup_tree(seed: u64, n: usize) -> LabKdTree {
    LabKdTree::build(&small_triangles(seed, n, 0.2), &KdLabParams::default())
}

#[test]
fn step_1_plane_t_and_the_near_child() {
    let lab = soup_tree(1, 200);
    let root = lab.tree.nodes()[0];
    assert!(!root.is_leaf(), "a tree over 200 triangles splits its root");
    let (a, s, first) = (root.axis(), root.split(), root.index());
    let point = |along: f32| {
        let mut p = Vec3::splat(0.1);
        p[a] = along;
        p
    };
    let mut up = Vec3::new(0.3, 0.2, 0.1);
    up[a] = 1.0;
    let up = up.normalize();
    let from_below = Ray::new(point(s - 2.0), up);
    let t = step1::plane_t(&root, &from_below);
    assert!(
        (t - 2.0 / up[a]).abs() < 1e-5,
        "t = {t}, expected {}",
        2.0 / up[a]
    );
    assert_eq!(
        step1::near_far(&root, &from_below),
        (first, first + 1),
        "ray {} starts below the root's plane: the child below is near",
        from_below.to_line()
    );
    let from_above = Ray::new(point(s + 2.0), up);
    assert!(
        step1::plane_t(&root, &from_above) < 0.0,
        "the plane is behind"
    );
    assert_eq!(
        step1::near_far(&root, &from_above),
        (first + 1, first),
        "ray {} starts above the root's plane: the child above is near",
        from_above.to_line()
    );
    // An origin in the plane: the direction decides.
    let in_plane_up = Ray::new(point(s), up);
    assert_eq!(
        step1::plane_t(&root, &in_plane_up),
        0.0,
        "ray {} starts in the plane: it crosses it at t = 0",
        in_plane_up.to_line()
    );
    assert_eq!(
        step1::near_far(&root, &in_plane_up),
        (first, first + 1),
        "going up"
    );
    let in_plane_down = Ray::new(point(s), -up);
    assert_eq!(
        step1::near_far(&root, &in_plane_down),
        (first + 1, first),
        "going down"
    );
    // Parallel to the plane: never crossed, or NaN when lying in it.
    let mut flat = Vec3::ONE;
    flat[a] = 0.0;
    assert!(
        step1::plane_t(&root, &Ray::new(point(s - 1.0), flat)).is_infinite(),
        "a ray parallel to the plane, below it, never crosses it: t is infinite"
    );
    assert!(
        step1::plane_t(&root, &Ray::new(point(s), flat)).is_nan(),
        "a ray lying in the plane: t is NaN (0 / 0)"
    );
    flat[a] = -0.0;
    assert!(
        step1::plane_t(&root, &Ray::new(point(s + 1.0), flat)).is_infinite(),
        "a ray parallel to the plane (direction -0.0 along its axis), above it: t is infinite"
    );
    assert_eq!(
        step1::near_far(&root, &Ray::new(point(s + 1.0), flat)).0,
        first + 1,
        "a ray parallel to the plane, above it: the child above is near"
    );
}

#[test]
fn step_1_the_near_child_holds_the_origin() {
    let lab = soup_tree(2, 300);
    for ray in rays_into_cube(3, 200) {
        for (i, _) in cells(&lab) {
            let node = &lab.tree.nodes()[i];
            if node.is_leaf() {
                continue;
            }
            let o = ray.origin[node.axis()];
            if o == node.split() {
                continue;
            }
            let want = if o < node.split() {
                node.index()
            } else {
                node.index() + 1
            };
            assert_eq!(step1::near_far(node, &ray).0, want, "{}", ray.to_line());
            let t = step1::plane_t(node, &ray);
            assert_eq!(
                ray.at(t)[node.axis()].is_finite(),
                t.is_finite(),
                "ray {}: plane_t {t} is finite exactly when the ray crosses the plane somewhere",
                ray.to_line()
            );
            if t.is_finite() && t.abs() < 100.0 {
                let at = ray.at(t)[node.axis()];
                assert!(
                    (at - node.split()).abs() < 1e-4,
                    "{}: at {at}",
                    ray.to_line()
                );
            }
        }
    }
}

#[test]
fn step_2_visit_covers_the_four_cases() {
    let lab = soup_tree(4, 200);
    let root = lab.tree.nodes()[0];
    let (a, s, first) = (root.axis(), root.split(), root.index());
    let mut o = Vec3::splat(0.1);
    o[a] = s - 2.0;
    let mut d = Vec3::ZERO;
    d[a] = 1.0;
    let ray = Ray::new(o, d); // Crosses the plane at t = 2.
    let (below, above) = (first, first + 1);
    assert_eq!(
        step2::visit(&root, &ray, 0.0, 1.0),
        Visit::Near(below),
        "plane beyond t1"
    );
    assert_eq!(
        step2::visit(&root, &ray, 3.0, 4.0),
        Visit::Far(above),
        "plane before t0"
    );
    assert_eq!(
        step2::visit(&root, &ray, 1.0, 3.0),
        Visit::Both {
            near: below,
            far: above,
            t: 2.0
        },
        "ray {} crosses the plane at t = 2 inside [1, 3]: both children, the one below first",
        ray.to_line()
    );
    // Within rounding of either end: both children, so a triangle on the plane is not missed.
    assert!(
        matches!(
            step2::visit(&root, &ray, 0.0, 1.9999999),
            Visit::Both { .. }
        ),
        "ray {} on [0, 1.9999999]: the plane at t = 2 is within rounding of the end, so both children",
        ray.to_line()
    );
    assert!(
        matches!(
            step2::visit(&root, &ray, 2.0000002, 3.0),
            Visit::Both { .. }
        ),
        "ray {} on [2.0000002, 3]: the plane at t = 2 is within rounding of the start, so both children",
        ray.to_line()
    );
    // A plane behind the origin is never crossed.
    let back = Ray::new(o, -d);
    assert_eq!(
        step2::visit(&root, &back, 0.0, 5.0),
        Visit::Near(below),
        "ray {} heads away from the plane: only the near child",
        back.to_line()
    );
    // An origin in the plane crosses it at t = 0: the side it comes from, then the other.
    let mut on = o;
    on[a] = s;
    assert_eq!(
        step2::visit(&root, &Ray::new(on, d), 0.0, 5.0),
        Visit::Both {
            near: below,
            far: above,
            t: 0.0
        },
        "a ray from a point in the plane crosses it at t = 0: the side it comes from, then the other"
    );
    // Lying in the plane: both, over the whole interval.
    let mut in_plane = Vec3::ONE;
    in_plane[a] = 0.0;
    assert!(
        matches!(
            step2::visit(&root, &Ray::new(on, in_plane), 0.0, 5.0),
            Visit::InPlane { .. }
        ),
        "a ray lying in the plane: both children over the whole interval (Visit::InPlane)"
    );
}

#[test]
fn step_2_visit_reaches_every_child_the_ray_crosses() {
    let lab = soup_tree(5, 400);
    let all = cells(&lab);
    let cell_of = |i: usize| all.iter().find(|c| c.0 == i).unwrap().1;
    let mut checked = 0;
    for ray in rays_into_cube(6, 200) {
        for &(i, cell) in &all {
            let node = &lab.tree.nodes()[i];
            let Some((t0, t1)) = cell.intersect(&ray, ray.t_max) else {
                continue;
            };
            if node.is_leaf() || t1 - t0 < 1e-4 {
                continue;
            }
            let reached: Vec<usize> = match step2::visit(node, &ray, t0, t1) {
                Visit::Near(c) | Visit::Far(c) => vec![c],
                Visit::Both { near, far, .. } | Visit::InPlane { near, far } => vec![near, far],
            };
            for child in [node.index(), node.index() + 1] {
                if let Some((a, b)) = cell_of(child).intersect(&ray, ray.t_max)
                    && b - a > 1e-4
                {
                    assert!(
                        reached.contains(&child),
                        "{}: node {i} over [{t0}, {t1}] misses child {child} (crossed over [{a}, {b}])",
                        ray.to_line()
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 1000, "only {checked} children crossed");
}

#[test]
fn step_3_walk_visits_the_leaves_the_ray_crosses_in_order() {
    let lab = soup_tree(7, 400);
    let all = cells(&lab);
    let nodes = lab.tree.nodes();
    for ray in rays_into_cube(8, 300) {
        let Some((t0, t1)) = lab.tree.bounds().intersect(&ray, ray.t_max) else {
            continue;
        };
        let mut walked = Vec::new();
        step3::walk(&lab, &ray, t0, t1, &mut NoStats, |leaf, a, b, _| {
            let i = nodes.iter().position(|n| std::ptr::eq(n, leaf)).unwrap();
            walked.push((i, a, b));
            f32::INFINITY
        });
        let crossed: Vec<usize> = all
            .iter()
            .filter(|(i, cell)| {
                nodes[*i].is_leaf()
                    && cell
                        .intersect(&ray, ray.t_max)
                        .is_some_and(|(a, b)| b - a > 1e-4)
            })
            .map(|c| c.0)
            .collect();
        for c in &crossed {
            assert!(
                walked.iter().any(|w| w.0 == *c),
                "{}: the walk skips leaf {c}",
                ray.to_line()
            );
        }
        for w in walked.windows(2) {
            assert!(
                w[0].1 <= w[1].1,
                "{}: leaves out of order: {w:?}",
                ray.to_line()
            );
        }
        for &(_, a, b) in &walked {
            assert!(a <= b, "{}: a backwards interval [{a}, {b}]", ray.to_line());
        }
        assert!(
            walked.len() <= crossed.len() + 3,
            "{}: {} leaves walked, {} crossed",
            ray.to_line(),
            walked.len(),
            crossed.len()
        );
        // A limit skips every leaf starting beyond it.
        if let Some(&(_, _, first_end)) = walked.first() {
            let mut after = Vec::new();
            step3::walk(&lab, &ray, t0, t1, &mut NoStats, |_, a, _, _| {
                after.push(a);
                first_end
            });
            let beyond = after.iter().filter(|&&a| a > first_end * 1.001).count();
            assert_eq!(
                beyond,
                0,
                "{}: leaves entered beyond the limit: {after:?}",
                ray.to_line()
            );
        }
        let mut count = 0;
        step3::walk(&lab, &ray, t0, t1, &mut NoStats, |_, _, _, _| {
            count += 1;
            f32::NEG_INFINITY
        });
        assert_eq!(count, 1, "the walk goes on after visit returned -inf");
    }
}

#[test]
fn step_3_walk_counts_every_node_it_enters() {
    let lab = soup_tree(9, 300);
    let ray = Ray::new(Vec3::new(-2.0, -1.9, -1.8), Vec3::ONE.normalize());
    let (t0, t1) = lab.tree.bounds().intersect(&ray, ray.t_max).unwrap();
    let mut stats = Counters::default();
    let mut leaves = 0;
    step3::walk(&lab, &ray, t0, t1, &mut stats, |_, _, _, _| {
        leaves += 1;
        f32::INFINITY
    });
    assert!(
        leaves > 1,
        "ray {} crosses the soup: the walk reaches more than one leaf",
        ray.to_line()
    );
    assert!(
        stats.node_visits > leaves,
        "{} nodes entered for {leaves} leaves: interior nodes count too",
        stats.node_visits
    );
}

rt_conformance::conformance_tests!(closest_hit: step_4_closest_hit, LabKdTree, KdLabParams::default());

#[test]
fn step_4_a_hit_beyond_the_leaf_does_not_end_the_walk() {
    // A long triangle hit far away, listed in many leaves, and small ones hit nearer in later
    // leaves: stopping at the first leaf with a hit returns the long one.
    let mut tris = vec![Triangle::new(
        Vec3::new(-10.0, -10.0, 9.0),
        Vec3::new(10.0, -10.0, 0.0),
        Vec3::new(0.0, 10.0, 4.0),
    )];
    tris.extend(
        small_triangles(3, 300, 0.05)
            .into_iter()
            .map(|t| Triangle::new(t.v0 * 10.0, t.v1 * 10.0, t.v2 * 10.0)),
    );
    let lab = LabKdTree::build(&tris, &KdLabParams::default());
    let reference = BruteForce::build(&tris, &());
    for ray in rays_into_cube(4, 500)
        .iter()
        .map(|r| Ray::new(r.origin * 10.0, r.dir()))
    {
        assert!(
            Hit::agree(reference.intersect(&ray), lab.intersect(&ray)),
            "{}",
            ray.to_line()
        );
    }
}

#[test]
fn step_4_the_mailbox_skips_repeated_tests_and_changes_no_answer() {
    // Large triangles among small ones: each large one is listed in many leaves.
    let mut tris = small_triangles(9, 500, 0.05);
    tris.extend((0..10).map(|i| {
        let z = -0.9 + 0.18 * i as f32;
        Triangle::new(
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z + 0.1),
            Vec3::new(0.0, 1.0, z),
        )
    }));
    let with = LabKdTree::build(&tris, &KdLabParams::default());
    let without = LabKdTree::build(&tris, &LabKdTree::presets()[1].1);
    assert!(
        without.params.no_mailbox,
        "the second preset turns the mailbox off"
    );
    let (mut a, mut b) = (Counters::default(), Counters::default());
    for ray in rays_into_cube(10, 500) {
        let x = with.intersect_with(&ray, &mut a);
        let y = without.intersect_with(&ray, &mut b);
        assert_eq!(x, y, "{}", ray.to_line());
    }
    assert!(a.mailbox_skips > 0, "no test was skipped: {a:?}");
    assert_eq!(b.mailbox_skips, 0, "{b:?}");
    assert_eq!(
        a.prim_tests + a.mailbox_skips,
        b.prim_tests,
        "each skip replaces one test"
    );
}

// The conformance kit, as any structure meets it: every query against brute force, on every
// scene of the kit (one test each) and on random scenes.
rt_conformance::conformance_tests!(step_5_kit, LabKdTree, KdLabParams::default());

#[test]
fn step_5_any_hit_stops_at_the_first_hit() {
    // 64 copies of one triangle share a leaf: the closest hit must test them all (equal t, the
    // smallest index wins), the any-hit query only until the first.
    let tri = Triangle::new(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(3.0, -1.0, 0.0),
        Vec3::new(-1.0, 3.0, 0.0),
    );
    let lab = LabKdTree::build(&vec![tri; 64], &KdLabParams::default());
    let (mut closest, mut any) = (Counters::default(), Counters::default());
    for i in 0..100 {
        let ray = Ray::new(Vec3::new(-0.5 + i as f32 * 0.01, 0.3, 5.0), -Vec3::Z);
        assert_eq!(
            lab.intersect_with(&ray, &mut closest).map(|h| h.prim),
            Some(0),
            "ray {} hits 64 copies of one triangle at the same t: the tie goes to the smallest index, 0",
            ray.to_line()
        );
        assert!(
            lab.occluded_with(&ray, &mut any),
            "ray {} must be blocked by the 64 copies (any hit)",
            ray.to_line()
        );
    }
    assert!(closest.prim_tests >= 6400, "{closest:?}");
    assert!(
        any.prim_tests <= 100,
        "any hit made {} tests for 100 rays",
        any.prim_tests
    );
}

//! The lab's tests, step by step: `cargo test step_3` runs step 3's. Each step's tests use only
//! what that step and the ones before it build, and draw their scenes and rays from the
//! conformance kit (`rt_conformance`) and brute force.

use lab_octree::{LabOctree, OctreeLabParams, OctreeParams, child_box, step1, step2, step3};
use rt_conformance::{check_case, edge_grazing_case, rays_into_cube, small_triangles};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Accel, BruteForce, Counters, Hit, NoStats, Ray, Rng, Triangle};

/// The unit cube, as a box's corners.
const LO: Vec3 = Vec3::ZERO;
const HI: Vec3 = Vec3::ONE;

/// An octree over a soup of small triangles in the cube `[-1, 1]³`.
fn soup_tree(seed: u64, n: usize) -> LabOctree {
    LabOctree::build(&small_triangles(seed, n, 0.2), &OctreeLabParams::default())
}

/// A block of eight children that are all leaves listing something (so that none is skipped
/// as empty), taken from a tree over a dense soup.
fn full_block(lab: &LabOctree) -> lab_octree::Block {
    let mut block = lab.tree.blocks()[0];
    for node in &mut block.0 {
        if node.is_empty_leaf() {
            *node = lab.tree.root();
        }
    }
    block
}

#[test]
fn step_1_axes_mirror_negative_directions_and_flag_flat_ones() {
    let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0, -2.0, 0.0));
    let r = step1::axes(&ray);
    assert_eq!(
        (r.neg, r.flat),
        (0b010, 0b100),
        "ray {}: y runs down (neg bit 1), z is flat (flat bit 2)",
        ray.to_line()
    );
    let ray = Ray::new(Vec3::ZERO, Vec3::new(-0.0, 1.0, -3.0));
    let r = step1::axes(&ray);
    assert_eq!(
        (r.neg, r.flat),
        (0b100, 0b001),
        "ray {}: -0.0 is flat, not negative; z runs down",
        ray.to_line()
    );
    assert_eq!(
        (r.origin, r.inv),
        (ray.origin, ray.inv_dir()),
        "the origin and ray.inv_dir() as given"
    );
}

#[test]
fn step_1_faces_in_the_rays_order() {
    let up = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(1.0, 0.5, 0.25));
    let (near, far) = step1::faces(&step1::axes(&up), LO, HI);
    assert_eq!(
        (near.x, far.x),
        (1.0, 2.0),
        "ray {} runs up x: it meets x = 0 at t = 1, x = 1 at t = 2",
        up.to_line()
    );
    let down = Ray::new(Vec3::new(2.0, 0.5, 0.5), Vec3::new(-1.0, 0.5, 0.25));
    let (near, far) = step1::faces(&step1::axes(&down), LO, HI);
    assert_eq!(
        (near.x, far.x),
        (1.0, 2.0),
        "ray {} runs down x: mirrored, it meets x = 1 first (t = 1), x = 0 at t = 2",
        down.to_line()
    );
    assert!(
        near.y < far.y && near.z < far.z,
        "ray {}: near is the smaller parameter on every axis, got {near} and {far}",
        down.to_line()
    );
    // Flat on z: inside the slab for all t when the origin is in it, never when it is not.
    for (z, inside) in [
        (0.5, true),
        (0.0, true),
        (1.0, true),
        (1.5, false),
        (-0.5, false),
    ] {
        let flat = Ray::new(Vec3::new(-1.0, 0.5, z), Vec3::X);
        let (near, far) = step1::faces(&step1::axes(&flat), LO, HI);
        let want = if inside {
            (f32::NEG_INFINITY, f32::INFINITY)
        } else {
            (f32::INFINITY, f32::NEG_INFINITY)
        };
        assert_eq!(
            (near.z, far.z),
            want,
            "ray {} is flat on z with its origin {} the slab [0, 1]",
            flat.to_line(),
            if inside { "in" } else { "outside" }
        );
    }
}

#[test]
fn step_1_faces_agree_with_the_slab_test() {
    let b = Aabb::new(Vec3::new(-0.5, -0.25, 0.0), Vec3::new(0.5, 0.75, 0.5));
    // The slab test widens its far end by SLAB_FAR_SCALE (1 + 2⁻¹⁶).
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * b.abs().max(1.0);
    for ray in rays_into_cube(11, 4000) {
        let (near, far) = step1::faces(&step1::axes(&ray), b.min, b.max);
        let (enter, exit) = (near.max_element(), far.min_element());
        let grazes = (exit - enter).abs() <= 1e-4;
        match b.intersect(&ray, f32::INFINITY) {
            // `intersect` starts at t_min = 0; the faces do not.
            Some((t0, t1)) => assert!(
                grazes || (close(enter.max(0.0), t0) && close(exit, t1)),
                "ray {}: the faces give [{enter}, {exit}], the slab test [{t0}, {t1}]",
                ray.to_line()
            ),
            None => assert!(
                grazes || enter > exit || exit < 0.0,
                "ray {}: the faces give [{enter}, {exit}], but the slab test finds the box \
                 missed (or behind the ray)",
                ray.to_line()
            ),
        }
    }
}

#[test]
fn step_2_mid_params_and_child_faces() {
    let ray = Ray::new(Vec3::new(-1.0, 0.25, 0.75), Vec3::new(1.0, 0.0, -0.0));
    let r = step1::axes(&ray);
    let tm = step2::mid_params(&r, LO, HI);
    assert_eq!(
        tm,
        Vec3::new(1.5, f32::INFINITY, f32::NEG_INFINITY),
        "ray {}: crosses x = 0.5 at t = 1.5; flat on y in the lower half (+inf: never \
         crossed); flat on z in the upper half (-inf: crossed before it starts)",
        ray.to_line()
    );
    let on_plane = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
    let tm = step2::mid_params(&step1::axes(&on_plane), LO, HI);
    assert_eq!(
        (tm.y, tm.z),
        (f32::NEG_INFINITY, f32::NEG_INFINITY),
        "ray {}: an origin on a flat axis' mid-plane counts as the upper half",
        on_plane.to_line()
    );
    let near = Vec3::new(1.0, 2.0, 3.0);
    let far = Vec3::new(7.0, 8.0, 9.0);
    let tm = Vec3::new(4.0, 5.0, 6.0);
    assert_eq!(
        step2::child_faces(near, far, tm, 0b101),
        (Vec3::new(4.0, 2.0, 6.0), Vec3::new(7.0, 5.0, 9.0)),
        "child 0b101 is the far half on x and z, the near half on y"
    );
    // A child's faces from its parent's are its own faces, to the bit.
    for ray in rays_into_cube(5, 500) {
        let r = step1::axes(&ray);
        if r.flat != 0 {
            continue;
        }
        let faces = step1::faces(&r, LO, HI);
        let tm = step2::mid_params(&r, LO, HI);
        for c in 0..8 {
            let (lo, hi) = child_box(LO, HI, c ^ r.neg);
            assert_eq!(
                step2::child_faces(faces.0, faces.1, tm, c),
                step1::faces(&r, lo, hi),
                "ray {}: child {c} in the ray's order (block index {}) has other faces \
                 computed from its parent's than from its own box",
                ray.to_line(),
                c ^ r.neg
            );
        }
    }
}

#[test]
fn step_2_order_is_front_to_back_and_covers_the_ray() {
    let lab = soup_tree(1, 3000);
    let block = full_block(&lab);
    for ray in rays_into_cube(6, 2000) {
        let r = step1::axes(&ray);
        let (near, far) = step1::faces(&r, LO, HI);
        let (enter, exit) = (near.max_element(), far.min_element());
        let tm = step2::mid_params(&r, LO, HI);
        let order = step2::order(&r, (near, far), tm, &block, f32::NEG_INFINITY);
        let got = order.as_slice();
        if enter > step2::widen(exit) {
            assert!(
                got.is_empty(),
                "ray {} misses the cube, but passes through children {got:?}",
                ray.to_line()
            );
            continue;
        }
        assert!(
            !got.is_empty() && got.len() <= 8,
            "ray {} passes through the cube, so through 1 to 8 of its children: {got:?}",
            ray.to_line()
        );
        for w in got.windows(2) {
            assert!(
                w[0].1 <= w[1].1 && w[1].1 <= step2::widen(w[0].2),
                "ray {}: children out of order or with a gap between them: {w:?}",
                ray.to_line()
            );
        }
        assert!(
            got[0].1 == enter && got[got.len() - 1].2 == exit,
            "ray {}: the children run from the cube's entry {enter} to its exit {exit}: {got:?}",
            ray.to_line()
        );
        // Every child whose box the ray crosses for a while is in the order.
        for i in 0..8u32 {
            let (lo, hi) = child_box(LO, HI, i);
            let crossed = Aabb::new(lo, hi)
                .intersect(&Ray::with_interval(ray.origin, ray.dir(), -1e9, 1e9), 1e9)
                .is_some_and(|(t0, t1)| t1 - t0 > 1e-3);
            assert!(
                !crossed || got.iter().any(|c| c.0 == i),
                "ray {} crosses child {i} (block index) but the order leaves it out: {got:?}",
                ray.to_line()
            );
        }
    }
}

#[test]
fn step_2_order_keeps_children_crossed_at_a_tie() {
    // Through the cube's centre along a diagonal: all three mid-planes are crossed at once, so
    // the ray passes through two children only, but rounding may order the crossings either
    // way: every child entered within the tie must be kept, in the order of entry.
    let lab = soup_tree(1, 3000);
    let block = full_block(&lab);
    let ray = Ray::new(Vec3::splat(-1.0), Vec3::ONE);
    let r = step1::axes(&ray);
    let faces = step1::faces(&r, LO, HI);
    let tm = step2::mid_params(&r, LO, HI);
    let order = step2::order(&r, faces, tm, &block, 0.0);
    let got: Vec<u32> = order.as_slice().iter().map(|c| c.0).collect();
    assert!(
        got.first() == Some(&0) && got.last() == Some(&7) && got.len() == 8,
        "ray {} crosses all three mid-planes at t = 1.5: children 0 to 7 are all entered \
         there (six of them at a single point), first 0 and last 7, got {got:?}",
        ray.to_line()
    );
    // A child ending before `t_from` is left out.
    let later = step2::order(&r, faces, tm, &block, 1.75);
    let got: Vec<u32> = later.as_slice().iter().map(|c| c.0).collect();
    assert_eq!(
        got,
        [7],
        "ray {} from t = 1.75 on is in child 7 only",
        ray.to_line()
    );
}

#[test]
fn step_2_order_skips_empty_leaves() {
    // Triangles in two opposite corners of the cube: the root's other children are empty.
    let corner =
        |t: Triangle, c: f32| Triangle::new(t.v0 * 0.1 + c, t.v1 * 0.1 + c, t.v2 * 0.1 + c);
    let mut tris: Vec<Triangle> = small_triangles(2, 40, 0.2)
        .into_iter()
        .map(|t| corner(t, -0.9))
        .collect();
    tris.extend(
        small_triangles(3, 40, 0.2)
            .into_iter()
            .map(|t| corner(t, 0.9)),
    );
    let lab = LabOctree::build(&tris, &OctreeLabParams::default());
    let root = lab.tree.root();
    let block = lab.tree.blocks()[root.children().expect("80 triangles: the root is cut")];
    let cube = lab.tree.bounds();
    for ray in rays_into_cube(12, 500) {
        let r = step1::axes(&ray);
        let faces = step1::faces(&r, cube.min, cube.max);
        let tm = step2::mid_params(&r, cube.min, cube.max);
        for &(i, _, _) in step2::order(&r, faces, tm, &block, f32::NEG_INFINITY).as_slice() {
            assert!(
                !block.0[i as usize].is_empty_leaf(),
                "ray {}: child {i} is an empty leaf, but the order keeps it",
                ray.to_line()
            );
        }
    }
}

#[test]
fn step_3_walk_visits_leaves_in_order() {
    let lab = soup_tree(7, 400);
    let reference = BruteForce::build(&lab.tris, &());
    for ray in rays_into_cube(8, 300) {
        let mut walked = Vec::new();
        step3::walk(&lab, &ray, &mut NoStats, |leaf, a, b, _| {
            walked.push((leaf.references(), a, b));
            f32::INFINITY
        });
        for w in walked.windows(2) {
            assert!(
                w[0].1 <= w[1].1,
                "ray {}: leaves out of order: {w:?}",
                ray.to_line()
            );
        }
        // Every triangle the ray hits is listed in a leaf the walk reached.
        if let Some(hit) = reference.intersect(&ray) {
            let listed = walked
                .iter()
                .any(|(refs, _, _)| lab.tree.references()[refs.clone()].contains(&hit.prim));
            assert!(
                listed,
                "ray {} hits triangle {} at t = {}, in no leaf the walk reached",
                ray.to_line(),
                hit.prim,
                hit.t
            );
        }
        // A limit skips every leaf starting beyond it.
        if let Some(&(_, _, first_end)) = walked.first() {
            let mut after = Vec::new();
            step3::walk(&lab, &ray, &mut NoStats, |_, a, _, _| {
                after.push(a);
                first_end
            });
            let beyond = after.iter().filter(|&&a| a > first_end * 1.001).count();
            assert_eq!(
                beyond,
                0,
                "ray {}: leaves entered beyond the limit: {after:?}",
                ray.to_line()
            );
        }
        let mut count = 0;
        step3::walk(&lab, &ray, &mut NoStats, |_, _, _, _| {
            count += 1;
            f32::NEG_INFINITY
        });
        assert!(
            count <= 1,
            "ray {}: the walk goes on after visit returned -inf ({count} leaves)",
            ray.to_line()
        );
    }
}

#[test]
fn step_3_walk_counts_every_node_it_enters_and_skips_invalid_rays() {
    let lab = soup_tree(9, 300);
    let ray = Ray::new(Vec3::new(-2.0, -1.9, -1.8), Vec3::ONE.normalize());
    let mut stats = Counters::default();
    let mut leaves = 0;
    step3::walk(&lab, &ray, &mut stats, |_, _, _, _| {
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
        "{} nodes entered for {leaves} leaves: the root and interior nodes count too",
        stats.node_visits
    );
    let nan = Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X);
    let mut stats = Counters::default();
    step3::walk(&lab, &nan, &mut stats, |_, _, _, _| f32::INFINITY);
    assert_eq!(
        stats.node_visits, 0,
        "a ray with a NaN origin is invalid: the walk visits nothing"
    );
}

rt_conformance::conformance_tests!(closest_hit: step_4_closest_hit, LabOctree, OctreeLabParams::default());

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
    let lab = LabOctree::build(&tris, &OctreeLabParams::default());
    let reference = BruteForce::build(&tris, &());
    for ray in rays_into_cube(4, 500)
        .iter()
        .map(|r| Ray::new(r.origin * 10.0, r.dir()))
    {
        assert!(
            Hit::agree(reference.intersect(&ray), lab.intersect(&ray)),
            "ray {}: brute force finds {:?}, the octree {:?}",
            ray.to_line(),
            reference.intersect(&ray),
            lab.intersect(&ray)
        );
    }
}

#[test]
fn step_4_rays_grazing_node_edges_from_afar() {
    // Tiny triangles hugging the edges of cells, one in each cell around an edge, and rays at
    // them from up to 10⁴ away: rounding puts such a ray's computed crossings of two mid-planes
    // in the wrong order, and the walk must still visit the sliver of a child between them
    // (step 2's `widen`). The tree is cut down to cells of side 1/8 on the lattice.
    let params = OctreeLabParams {
        tree: OctreeParams {
            max_prims: 1,
            max_depth: 5,
            ..OctreeParams::default()
        },
        no_mailbox: false,
    };
    let mut rng = Rng::new(5);
    for case in 0..300 {
        let (tris, rays) = edge_grazing_case(&mut rng);
        if let Err(e) = check_case::<LabOctree>(&params, &tris, &rays) {
            panic!("edge-grazing case {case}: {e}");
        }
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
    let with = LabOctree::build(&tris, &OctreeLabParams::default());
    let without = LabOctree::build(&tris, &LabOctree::presets()[1].1);
    assert!(
        without.params.no_mailbox,
        "the second preset turns the mailbox off"
    );
    let (mut a, mut b) = (Counters::default(), Counters::default());
    for ray in rays_into_cube(10, 500) {
        let x = with.intersect_with(&ray, &mut a);
        let y = without.intersect_with(&ray, &mut b);
        assert_eq!(
            x,
            y,
            "ray {}: the mailbox changed the answer",
            ray.to_line()
        );
    }
    assert!(a.mailbox_skips > 0, "no test was skipped: {a:?}");
    assert_eq!(
        b.mailbox_skips, 0,
        "without the mailbox nothing is skipped: {b:?}"
    );
    assert!(
        a.prim_tests < b.prim_tests,
        "the mailbox saves tests: {} with it, {} without",
        a.prim_tests,
        b.prim_tests
    );
}

#[test]
fn step_5_any_hit_stops_at_the_first_hit() {
    let tri = Triangle::new(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(3.0, -1.0, 0.0),
        Vec3::new(-1.0, 3.0, 0.0),
    );
    let lab = LabOctree::build(&vec![tri; 64], &OctreeLabParams::default());
    let (mut closest, mut any) = (Counters::default(), Counters::default());
    for i in 0..100 {
        let ray = Ray::new(Vec3::new(-0.5 + i as f32 * 0.01, 0.3, 5.0), -Vec3::Z);
        assert_eq!(
            lab.intersect_with(&ray, &mut closest).map(|h| h.prim),
            Some(0),
            "ray {} hits 64 copies of one triangle at the same t: the tie goes to the \
             smallest index, 0",
            ray.to_line()
        );
        assert!(
            lab.occluded_with(&ray, &mut any),
            "ray {} must be blocked by the 64 copies (any hit)",
            ray.to_line()
        );
    }
    assert!(
        any.prim_tests <= 100,
        "any hit made {} tests for 100 rays: it stops at the first triangle that blocks",
        any.prim_tests
    );
}

// The conformance kit, as any structure meets it: every query against brute force, on every
// scene of the kit (one test each) and on random scenes.
rt_conformance::conformance_tests!(step_5_kit, LabOctree, OctreeLabParams::default());

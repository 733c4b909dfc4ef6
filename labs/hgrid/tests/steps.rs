//! The lab's tests, step by step: `cargo test step_3` runs step 3's. Each step's tests use only
//! what that step and the ones before it build, and draw their scenes and rays from the
//! conformance kit (`rt_conformance`) and brute force.

use lab_hgrid::{HGridLabParams, HGridParams, LabHGrid, RayAxes, step1, step2, step3};
use rt_conformance::{
    check_case, edge_grazing_case, lattice_rays, lattice_triangles, rays_into_cube, small_triangles,
};
use rt_core::glam::Vec3;
use rt_core::{Accel, BruteForce, Counters, Hit, NoStats, Ray, Rng, Triangle};

/// A 4³ top grid for `n` triangles, and a 2³ nested grid in every cell with at least two
/// triangles: the lattice's planes are cell boundaries on both levels.
fn lattice_levels(n: usize) -> HGridLabParams {
    HGridLabParams {
        grid: HGridParams {
            top_density: 64.0 / n as f32,
            density: 8.0 / 3.0,
            split_min: 2,
            max_levels: 2,
            ..HGridParams::default()
        },
        no_mailbox: false,
    }
}

/// A hierarchy with nested grids: a dense cluster of small triangles in one corner of a box
/// spanned by a few large ones (a teapot in a stadium in small).
fn clustered(seed: u64) -> LabHGrid {
    let mut tris: Vec<Triangle> = small_triangles(seed, 600, 0.2)
        .into_iter()
        .map(|t| Triangle::new(t.v0 * 0.1 + 0.8, t.v1 * 0.1 + 0.8, t.v2 * 0.1 + 0.8))
        .collect();
    tris.extend([
        Triangle::new(
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
        ),
        Triangle::new(
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, 0.9),
        ),
    ]);
    LabHGrid::build(&tris, &HGridLabParams::default())
}

/// Every `(level, cell)` of the hierarchy.
fn all_cells(lab: &LabHGrid) -> Vec<(usize, [u32; 3])> {
    let mut out = Vec::new();
    for (g, level) in lab.grid.levels().iter().enumerate() {
        for i in 0..level.shape.cell_count() {
            out.push((g, level.shape.coords(i)));
        }
    }
    out
}

#[test]
fn step_1_a_parent_cells_nested_grid_covers_exactly_that_cell() {
    let lab = clustered(1);
    let levels = lab.grid.levels();
    assert!(
        levels.len() > 1,
        "the clustered scene must have nested grids; it has {} grid",
        levels.len()
    );
    let mut parents = vec![0; levels.len()];
    for (g, c) in all_cells(&lab) {
        if let Some(nested) = step1::cell(&lab, g, c).nested() {
            parents[nested] += 1;
            assert_eq!(
                levels[nested].shape.bounds(),
                levels[g].shape.cell_box(c),
                "cell {c:?} of grid {g} holds grid {nested}, whose box must be that cell's"
            );
        }
    }
    assert_eq!(parents[0], 0, "the top grid is no cell's nested grid");
    for (g, &n) in parents.iter().enumerate().skip(1) {
        assert_eq!(
            n, 1,
            "grid {g} must be the nested grid of exactly one cell, not {n}"
        );
    }
}

#[test]
fn step_1_a_grazed_parent_cell_lists_its_whole_nested_grid() {
    let lab = clustered(2);
    let refs = lab.grid.references();
    for (g, c) in all_cells(&lab) {
        let cell = step1::cell(&lab, g, c);
        let grazed = step1::grazed_ids(&lab, &cell);
        match cell.nested() {
            None => assert_eq!(
                grazed,
                &refs[cell.references()],
                "leaf cell {c:?} of grid {g}: a grazed leaf is tested by its own list"
            ),
            Some(nested) => {
                // Every triangle listed anywhere in the nested grid (one level down) is in it.
                let level = &lab.grid.levels()[nested];
                for i in 0..level.shape.cell_count() {
                    let inner = step1::cell(&lab, nested, level.shape.coords(i));
                    for id in step1::grazed_ids(&lab, &inner) {
                        assert!(
                            grazed.contains(id),
                            "parent cell {c:?} of grid {g}: triangle {id} of its nested grid \
                             {nested} is missing from the grazed list"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn step_1_enter_starts_in_the_cell_holding_the_point() {
    let lab = clustered(3);
    let top = lab.grid.levels()[0].shape;
    for ray in rays_into_cube(4, 500) {
        let Some((t0, _)) = top.bounds().intersect(&ray, ray.t_max) else {
            continue;
        };
        let w = step1::enter(&lab, 0, &RayAxes::new(&ray), t0);
        let cell = top.cell_box(w.dda.cell);
        let p = ray.at(t0);
        let slack = 1e-4 * (1.0 + p.abs().max_element());
        assert!(
            (w.level, w.t_enter, w.visited) == (0, t0, false)
                && (cell.min - slack).cmple(p).all()
                && p.cmple(cell.max + slack).all(),
            "ray {}: entering the top grid at t = {t0} ({p}) must start in the cell holding \
             that point, at that t, not visited yet; got cell {:?} ({cell:?}), {:?}",
            ray.to_line(),
            w.dda.cell,
            (w.level, w.t_enter, w.visited)
        );
    }
}

#[test]
fn step_2_beside_visits_each_side_cell_by_its_grazed_list() {
    let mut sides = 0;
    for seed in 0..10 {
        let tris = lattice_triangles(seed, 40);
        let lab = LabHGrid::build(&tris, &lattice_levels(tris.len()));
        let top = lab.grid.levels()[0].shape;
        for ray in lattice_rays(seed, 200) {
            if !ray.is_valid() {
                continue;
            }
            let Some((t0, t1)) = top.bounds().intersect(&ray, ray.t_max) else {
                continue;
            };
            let r = RayAxes::new(&ray);
            let mut w = step1::enter(&lab, 0, &r, t0);
            loop {
                let (axis, t_exit) = w.dda.exit();
                if t_exit > t1 {
                    break;
                }
                let want: Vec<[u32; 3]> = w.dda.side_cells(&top, &r, axis).collect();
                let mut got = Vec::new();
                let mut stats = Counters::default();
                let limit = step2::beside(
                    &lab,
                    &w,
                    &r,
                    axis,
                    t_exit,
                    &mut stats,
                    &mut |ids, a, b, _| {
                        got.push((ids.to_vec(), a, b));
                        got.len() as f32
                    },
                );
                let expected: Vec<(Vec<u32>, f32, f32)> = want
                    .iter()
                    .map(|&c| {
                        let cell = step1::cell(&lab, 0, c);
                        (step1::grazed_ids(&lab, &cell).to_vec(), t_exit, t_exit)
                    })
                    .collect();
                assert!(
                    got == expected
                        && stats.node_visits == want.len() as u64
                        && limit == if want.is_empty() { f32::INFINITY } else { 1.0 },
                    "ray {}: at the exit t = {t_exit} through axis {axis} of cell {:?}, the \
                     cells beside the path {want:?} must each be visited once (a node visit), \
                     by their grazed list, at the exit, and the smallest limit returned; got \
                     {} visits, {} calls, limit {limit}",
                    ray.to_line(),
                    w.dda.cell,
                    stats.node_visits,
                    got.len()
                );
                sides += want.len();
                if !w.dda.step(&top, &r, axis) {
                    break;
                }
            }
        }
    }
    assert!(
        sides > 0,
        "the lattice rays pass through cell edges: some cells are beside the path"
    );
}

#[test]
fn step_3_walk_visits_cells_in_order() {
    let lab = clustered(7);
    let reference = BruteForce::build(&lab.tris, &());
    for ray in rays_into_cube(8, 300) {
        let mut walked: Vec<(Vec<u32>, f32, f32)> = Vec::new();
        step3::walk(&lab, &ray, &mut NoStats, |ids, a, b, _| {
            walked.push((ids.to_vec(), a, b));
            f32::INFINITY
        });
        for w in walked.windows(2) {
            assert!(
                w[0].1 <= w[1].1,
                "ray {}: cells out of order: entered at {} then at {}",
                ray.to_line(),
                w[0].1,
                w[1].1
            );
        }
        if let Some(hit) = reference.intersect(&ray) {
            assert!(
                walked.iter().any(|(ids, _, _)| ids.contains(&hit.prim)),
                "ray {} hits triangle {} at t = {}, in no cell the walk reached",
                ray.to_line(),
                hit.prim,
                hit.t
            );
        }
        // A limit ends the walk at the first cell starting beyond it.
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
                "ray {}: cells entered beyond the limit: {after:?}",
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
            "ray {}: the walk goes on after visit returned -inf ({count} cells)",
            ray.to_line()
        );
    }
}

#[test]
fn step_3_walk_goes_down_into_nested_grids_and_counts_every_cell() {
    let lab = clustered(9);
    // From outside the box, through the cluster's corner.
    let ray = Ray::new(Vec3::splat(-2.0), Vec3::ONE.normalize());
    let mut stats = Counters::default();
    let mut small = 0;
    step3::walk(&lab, &ray, &mut stats, |ids, _, _, _| {
        small += ids.iter().filter(|&&id| id < 600).count();
        f32::INFINITY
    });
    assert!(
        small > 0,
        "ray {} passes through the cluster: its nested grid's cells must be walked",
        ray.to_line()
    );
    assert!(
        stats.node_visits > 4,
        "ray {}: {} cells visited: the parent cells count too",
        ray.to_line(),
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

rt_conformance::conformance_tests!(closest_hit: step_4_closest_hit, LabHGrid, HGridLabParams::default());

#[test]
fn step_4_rays_grazing_cell_edges_from_afar() {
    // Tiny triangles hugging the edges of cells on both levels, and rays at them from up to 10⁴
    // away: rounding puts such a ray's crossings of two boundaries in the wrong order, and the
    // walk must still test the cell beside its path (step 2).
    let mut rng = Rng::new(5);
    for case in 0..300 {
        let (tris, rays) = edge_grazing_case(&mut rng);
        if let Err(e) = check_case::<LabHGrid>(&lattice_levels(tris.len()), &tris, &rays) {
            panic!("edge-grazing case {case}: {e}");
        }
    }
}

#[test]
fn step_4_a_hit_beyond_the_cell_does_not_end_the_walk() {
    // A long triangle hit far away, listed in many cells, and small ones hit nearer in later
    // cells: stopping at the first cell with a hit returns the long one.
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
    let lab = LabHGrid::build(&tris, &HGridLabParams::default());
    let reference = BruteForce::build(&tris, &());
    for ray in rays_into_cube(4, 500)
        .iter()
        .map(|r| Ray::new(r.origin * 10.0, r.dir()))
    {
        assert!(
            Hit::agree(reference.intersect(&ray), lab.intersect(&ray)),
            "ray {}: brute force finds {:?}, the hierarchical grid {:?}",
            ray.to_line(),
            reference.intersect(&ray),
            lab.intersect(&ray)
        );
    }
}

#[test]
fn step_4_the_mailbox_skips_repeated_tests_and_changes_no_answer() {
    // Large triangles among small ones: each large one is listed in many cells.
    let mut tris = small_triangles(9, 500, 0.05);
    tris.extend((0..10).map(|i| {
        let z = -0.9 + 0.18 * i as f32;
        Triangle::new(
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z + 0.1),
            Vec3::new(0.0, 1.0, z),
        )
    }));
    let with = LabHGrid::build(&tris, &HGridLabParams::default());
    let without = LabHGrid::build(&tris, &LabHGrid::presets()[1].1);
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
}

#[test]
fn step_5_any_hit_stops_at_the_first_hit() {
    let tri = Triangle::new(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(3.0, -1.0, 0.0),
        Vec3::new(-1.0, 3.0, 0.0),
    );
    let lab = LabHGrid::build(&vec![tri; 64], &HGridLabParams::default());
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
rt_conformance::conformance_tests!(step_5_kit, LabHGrid, HGridLabParams::default());

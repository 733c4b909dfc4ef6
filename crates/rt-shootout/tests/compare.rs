//! `compare` as a library runs it: whole comparisons through the public API, with structures
//! that are wrong on purpose to show that the checks catch them (on the rays brute force checks
//! and on the others), instances, both views, bundles and closest points.

use rt_core::{Aabb, Accel, BuildStats, Hit, PrimHit, Ray, RayQuery, Stats, Triangle};
use rt_kdtree::{KdParams, KdTree};
use rt_shootout::compare::to_table;
use rt_shootout::{Args, Entry, Report, Shootout, args_from, entries_of_triangles};

// The structures wrapped here are kd-trees: a wrapper instantiates the walks of the structure
// it wraps, in this test binary, for every query type the shootout passes it. The kd-tree has
// two walks per query, the wide BVH sixteen (four kinds of leaves, four instruction sets).
// PERF: with the wide BVH wrapped, this binary was the fourth-largest unit of a CI build. Built
// after touching this file (`cargo test -p rt-shootout --test compare --no-run`, 2 cores): 97 s
// (123 s of CPU) with the BVH wrapped, 3.6 s (5 s) with the kd-tree; the tests run in 5.8 s
// instead of 5.1.

/// A structure that is wrong on purpose: it loses every hit on an even primitive.
#[derive(Debug)]
struct LosesEvenHits<P: rt_core::Primitive>(KdTree<P>);

impl<P: rt_core::Primitive> Accel for LosesEvenHits<P> {
    type Prim = P;
    type Params = ();
    const NAME: &'static str = "broken";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[P], _: &()) -> Self {
        Self(KdTree::build(prims, &KdParams::sah()))
    }
    /// Offers the query the odd primitives' hits only.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, &mut OddHits(query), stats);
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    /// Loses even primitives here too.
    fn ball_query<Q: rt_core::BallQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(&mut OddOnly(query), stats);
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
}

/// Passes on only the hits on odd primitives offered to it.
struct OddHits<'a, Q>(&'a mut Q);

impl<Q: RayQuery> RayQuery for OddHits<'_, Q> {
    const OCCLUSION: bool = Q::OCCLUSION;
    const REPEATABLE: bool = Q::REPEATABLE;
    fn t_far(&self) -> f32 {
        self.0.t_far()
    }
    fn offer(&mut self, prim: u32, hit: PrimHit) -> std::ops::ControlFlow<()> {
        if prim % 2 == 1 {
            self.0.offer(prim, hit)
        } else {
            std::ops::ControlFlow::Continue(())
        }
    }
}

/// Passes on only the odd primitives offered to it.
struct OddOnly<'a, Q>(&'a mut Q);

impl<P, Q: rt_core::BallQuery<P>> rt_core::BallQuery<P> for OddOnly<'_, Q> {
    fn center(&self) -> rt_core::glam::Vec3 {
        self.0.center()
    }
    fn radius_sq(&self) -> f32 {
        self.0.radius_sq()
    }
    fn test(&mut self, prim: &P, id: u32) {
        if id % 2 == 1 {
            self.0.test(prim, id);
        }
    }
    fn test_triangle(
        &mut self,
        v0: rt_core::glam::Vec3,
        e1: rt_core::glam::Vec3,
        e2: rt_core::glam::Vec3,
        id: u32,
    ) {
        if id % 2 == 1 {
            self.0.test_triangle(v0, e1, e2, id);
        }
    }
}

/// `compare`'s flags and `extra`, on one thread.
fn args(extra: &[&str]) -> Args {
    args_from(["--threads", "1"].iter().chain(extra)).expect("valid flags")
}

/// Every built-in row.
fn all() -> Vec<Entry> {
    Shootout::new().entries().to_vec()
}

/// The report of `entries` on the one scene of `args`, as `cargo xtask compare` makes it.
fn measure(args: &Args, entries: Vec<Entry>) -> Result<Report, String> {
    Shootout::empty()
        .with_entries(entries)
        .run(args)
        .map(|mut reports| reports.remove(0))
}

/// The default preset of a structure over triangles.
fn entry_of<A: Accel<Prim = Triangle> + 'static>() -> Entry {
    entries_of_triangles::<A>().remove(0)
}

#[test]
fn a_field_of_instances_agrees_on_every_row_and_every_ray_kind() {
    // Forty teapots of about 1,000 triangles, every row's structure under the instances.
    for kind in ["primary", "incoherent", "shadow", "diffuse"] {
        let a = args(&[
            "--scene",
            "teapot:1000",
            "--instances",
            "40",
            "--rays",
            kind,
            "--width",
            "96",
            "--height",
            "64",
            "--repeats",
            "1",
            "--check-rays",
            "6144",
        ]);
        let report = measure(&a, all()).expect("the field runs");
        let one = rt_shootout::compare::load_scene("teapot:1000")
            .unwrap()
            .1
            .len();
        assert_eq!(
            report.triangles,
            40 * one,
            "every instance's triangles counted"
        );
        assert_eq!(
            report.checked_rays, report.rays,
            "every ray checked by brute force"
        );
        assert!(report.rows.len() > 5);
        let hits = report.rows[1].hits;
        if kind == "primary" {
            assert!(
                hits > report.rays / 20,
                "the field fills the view ({hits} hits)"
            );
        }
        assert!(hits > 0, "{kind}: some rays hit");
        for row in &report.rows {
            assert_eq!(row.mismatches, 0, "{kind}: {} disagrees", row.name);
            assert_eq!(row.hits, hits, "{kind}: {}", row.name);
        }
    }
}

#[test]
fn a_field_rejects_bad_counts_and_closest_points_in_one_line() {
    let bad = measure(
        &args(&["--scene", "teapot:1000", "--instances", "0"]),
        all(),
    );
    assert_eq!(
        bad.unwrap_err(),
        "--instances must be from 1 to 1000000, not 0"
    );
    let points = args(&[
        "--scene",
        "teapot:1000",
        "--instances",
        "4",
        "--query",
        "closest-point",
    ]);
    let err = measure(&points, all()).unwrap_err();
    assert!(err.starts_with("--query closest-point runs on one mesh") && !err.contains('\n'));
}

#[test]
fn a_wrong_structure_is_caught_on_and_off_the_checked_subset() {
    // 2,000 rays checked by brute force out of 3,072: disagreements outside the subset must
    // be found by the cross-check against the other structures.
    let a = args(&[
        "--scene",
        "random-soup",
        "--width",
        "64",
        "--height",
        "48",
        "--check-rays",
        "2000",
        "--repeats",
        "1",
    ]);
    let mut entries = all();
    entries.push(entry_of::<LosesEvenHits<Triangle>>());
    let report = measure(&a, entries).unwrap();
    let broken = report.rows.iter().find(|r| r.name == "broken").unwrap();
    let bvh = report.rows.iter().find(|r| r.name == "bvh").unwrap();
    assert_eq!(bvh.mismatches, 0);
    // The broken row loses exactly the rays whose true answer is an even primitive.
    let expected = bvh
        .answers()
        .iter()
        .filter(|a| a.is_some_and(|h| h.prim % 2 == 0))
        .count();
    assert!(
        expected > 100,
        "the test scene must exercise the broken path"
    );
    assert_eq!(broken.mismatches, expected);
    assert!(
        report.checked_rays > 2000,
        "rays outside the subset were settled by brute force"
    );
    assert!(!report.disagreements.is_empty());
}

/// The kd-tree's single queries behind the default bundle loop (`BROKEN = false`: a
/// structure without a bundle traversal of its own), or behind its bundle queries with every
/// hit on an even primitive lost (`BROKEN = true`).
#[derive(Debug)]
struct Wrapped<P: rt_core::Primitive, const BROKEN: bool>(KdTree<P>);

impl<P: rt_core::Primitive, const BROKEN: bool> Accel for Wrapped<P, BROKEN> {
    type Prim = P;
    type Params = ();
    const NAME: &'static str = if BROKEN {
        "bundles-broken"
    } else {
        "singles-only"
    };
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[P], _: &()) -> Self {
        Self(KdTree::build(prims, &KdParams::sah()))
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
        if !BROKEN {
            rt_core::bundle::intersect_each(self, rays, out, stats);
            return;
        }
        self.0.intersect_bundle_with(rays, out, stats);
        for o in out.iter_mut() {
            *o = o.filter(|h| h.prim % 2 == 1);
        }
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn ball_query<Q: rt_core::BallQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
}

/// The filled view (the default) sees the mesh large: more of its rays hit than the
/// sparse view's, and the header names the view.
#[test]
fn the_filled_view_hits_more_than_the_sparse_one_and_is_named() {
    let run = |view: &str| {
        let a = args(&[
            "--scene",
            "teapot:1000",
            "--width",
            "64",
            "--height",
            "48",
            "--repeats",
            "0",
            "--view",
            view,
        ]);
        let entries = all().into_iter().filter(|e| e.name == "bvh").collect();
        measure(&a, entries).unwrap()
    };
    let (filled, sparse) = (run("filled"), run("sparse"));
    let (f, s) = (filled.hit_share().unwrap(), sparse.hit_share().unwrap());
    assert!(f > 0.4 && f > 1.5 * s, "filled {f}, sparse {s}");
    assert!(
        to_table(&filled).contains("primary rays from the filled view ("),
        "{}",
        to_table(&filled)
    );
    assert!(to_table(&sparse).contains("primary rays from the sparse view ("));
}

#[test]
fn bundles_are_checked_bit_for_bit_against_the_single_rays() {
    let a = args(&[
        "--scene",
        "teapot:1000",
        "--width",
        "64",
        "--height",
        "48",
        "--repeats",
        "1",
        "--bundle",
        "8x8",
    ]);
    let mut entries: Vec<_> = all()
        .into_iter()
        .filter(|e| e.name == "bvh" || e.name == "bvh-binary")
        .collect();
    entries.push(entry_of::<Wrapped<Triangle, true>>());
    entries.push(entry_of::<Wrapped<Triangle, false>>());
    let report = measure(&a, entries).unwrap();
    let row = |name: &str| report.rows.iter().find(|r| r.name == name).unwrap();
    let (bvh, binary, broken) = (row("bvh"), row("bvh-binary"), row("bundles-broken"));
    let singles = row("singles-only");
    let even = bvh
        .answers()
        .iter()
        .filter(|a| a.is_some_and(|h| h.prim % 2 == 0))
        .count();
    assert!(even > 100, "the view must exercise the broken path");
    // Its single answers agree with brute force; its bundle answers are caught.
    assert_eq!(broken.mismatches, 0);
    assert_eq!(broken.bundle.as_ref().unwrap().differences, even);
    assert_eq!(report.total_mismatches(), even);
    // Both trees trace bundles (their lanes counted); a structure without a bundle
    // traversal traces every ray alone.
    for tree in [bvh, binary] {
        let b = tree.bundle.as_ref().unwrap();
        assert_eq!(b.differences, 0, "{}", tree.name);
        assert!(b.lane_utilisation.is_some_and(|u| u > 0.0 && u <= 1.0));
        assert!(
            b.avg_visits < tree.avg_visits,
            "a bundle's step counts once"
        );
    }
    let k = singles.bundle.as_ref().unwrap();
    assert_eq!((k.single_share, k.lane_utilisation), (1.0, None));
    let table = to_table(&report);
    assert!(
        table.contains("\nBundles: the same rays traced as bundles"),
        "{table}"
    );
}

#[test]
fn a_wrong_closest_point_query_is_caught_on_and_off_the_checked_subset() {
    // 1,000 of 3,000 points checked by brute force; the rest by the cross-check.
    let a = args(&[
        "--scene",
        "random-soup",
        "--query",
        "closest-point",
        "--points",
        "3000",
        "--check-rays",
        "1000",
        "--repeats",
        "1",
    ]);
    let mut entries = all();
    entries.retain(|e| ["bvh", "kdtree", "grid", "hgrid", "octree"].contains(&e.name.as_str()));
    entries.push(entry_of::<LosesEvenHits<Triangle>>());
    let report = measure(&a, entries).unwrap();
    assert_eq!(report.ray_kind, "closest-point");
    for row in &report.rows {
        let expect_wrong = row.name == "broken";
        assert_eq!(
            row.mismatches > 0,
            expect_wrong,
            "{}: {}",
            row.name,
            row.mismatches
        );
    }
    let broken = report.rows.iter().find(|r| r.name == "broken").unwrap();
    // About half the answers are even primitives, and every one of them is caught.
    assert!(broken.mismatches > 1000, "{}", broken.mismatches);
    assert!(
        report.checked_rays > 1000,
        "points outside the subset were settled"
    );
    let d = &report.query_disagreements[0];
    assert_eq!(d.structure, "broken");
    assert!(d.rust.starts_with("closest_point(Vec3::new("), "{d:?}");
    // Brute force's answer names an even primitive, the kind the broken row loses.
    let prim: u32 = d
        .expected
        .split("prim: ")
        .nth(1)
        .and_then(|rest| rest.split(',').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no primitive in {d:?}"));
    assert_eq!(prim % 2, 0, "{d:?}");
    let table = to_table(&report);
    assert!(
        table.contains("Mqueries/s") && table.contains("3000 closest-point queries"),
        "{table}"
    );
}

#[test]
fn a_wrong_box_query_is_caught_on_and_off_the_checked_subset() {
    // The broken row's box query runs the trait's default (the ball around the box) through
    // its ball query, which loses every even primitive.
    let a = args(&[
        "--scene",
        "random-soup",
        "--query",
        "overlap",
        "--points",
        "3000",
        "--box-size",
        "0.05",
        "--check-rays",
        "1000",
        "--repeats",
        "1",
    ]);
    let mut entries = all();
    entries.retain(|e| ["bvh", "kdtree", "grid", "hgrid", "octree"].contains(&e.name.as_str()));
    entries.push(entry_of::<LosesEvenHits<Triangle>>());
    let report = measure(&a, entries).unwrap();
    assert_eq!(report.ray_kind, "overlap");
    for row in &report.rows {
        assert_eq!(
            row.mismatches > 0,
            row.name == "broken",
            "{}: {}",
            row.name,
            row.mismatches
        );
    }
    let broken = report.rows.iter().find(|r| r.name == "broken").unwrap();
    assert!(broken.mismatches > 1000, "{}", broken.mismatches);
    assert!(
        report.checked_rays > 1000,
        "boxes outside the subset were settled"
    );
    let d = &report.query_disagreements[0];
    assert!(d.rust.starts_with("overlapping(&Aabb::new("), "{d:?}");
    let table = to_table(&report);
    assert!(table.contains("3000 box overlap queries"), "{table}");
}

//! A structure defined outside the workspace's crates joins the shootout through the public API
//! alone, next to the built-in rows: what a student's crate does (with the example's structure).

#[path = "../examples/groups/groups.rs"]
mod groups;

use groups::{GROUP, Groups};
use rt_core::{Accel, BuildStats, Hit, Ray, Stats, Triangle};

#[test]
fn a_structure_from_outside_runs_next_to_the_built_in_rows() {
    let shootout = rt_shootout::Shootout::new().with_triangles::<Groups>();
    assert!(shootout.entries().iter().any(|e| e.name == "groups"));
    let args = rt_shootout::args_from([
        "--scene",
        "random-soup",
        "--structures",
        "groups,bvh,grid",
        "--width",
        "64",
        "--height",
        "48",
        "--repeats",
        "1",
        "--json",
    ])
    .unwrap();
    let reports = shootout.run(&args).unwrap();
    let names: Vec<&str> = reports[0].rows.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["brute-force", "groups", "bvh", "grid"]);
    let groups = &reports[0].rows[1];
    // Every answer checked and right; a ray visits every group box.
    assert_eq!(groups.mismatches, 0);
    assert_eq!(groups.avg_visits, (20_000usize.div_ceil(GROUP)) as f64);
    assert!(groups.avg_prim_tests > 0.0);
    assert_eq!(reports[0].total_mismatches(), 0);
    // Unknown rows are still one-line errors that list the added structure.
    let bad = rt_shootout::args_from(["--structures", "nope"]).unwrap();
    let err = shootout.run(&bad).unwrap_err();
    assert!(
        err.contains("unknown structure `nope`") && err.contains("groups"),
        "{err}"
    );
}

/// [`Groups`] with a classic bug: it forgets the last triangle of every group.
struct DropsLast(Groups);

impl Accel for DropsLast {
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "drops-last";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(Groups::build(prims, &()))
    }
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        let tris = &self.0.tris;
        let last_of_group = |h: &Hit| {
            let pos = tris.iter().position(|(id, _)| *id == h.prim).unwrap_or(0);
            pos % GROUP == GROUP - 1 || pos + 1 == tris.len()
        };
        self.0
            .intersect_with(ray, stats)
            .filter(|h| !last_of_group(h))
    }
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        self.intersect_with(ray, stats).is_some()
    }
    fn bounds(&self) -> rt_core::Aabb {
        self.0.bounds()
    }
    fn ball_query<Q: rt_core::BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
}

#[test]
fn grading_writes_every_check_and_the_first_failing_ray() {
    let dir = std::env::temp_dir().join(format!("rt-shootout-grade-{}", std::process::id()));
    let shootout = rt_shootout::Shootout::new()
        .with_triangles::<Groups>()
        .with_triangles::<DropsLast>();
    let args = |row: &str| {
        rt_shootout::args_from([
            "--grade",
            row,
            "--scene",
            "random-soup",
            "--structures",
            "bvh",
            "--width",
            "32",
            "--height",
            "24",
            "--repeats",
            "1",
            "--out",
            dir.to_str().unwrap(),
        ])
        .unwrap()
    };
    let md = shootout.grade(&args("groups")).unwrap();
    let text = std::fs::read_to_string(&md).unwrap();
    // Every fixed scene, and the random scenes.
    let checks = rt_conformance::SCENES.len() + 1;
    assert!(
        text.contains(&format!("{checks} of {checks} checks passed")),
        "{text}"
    );

    shootout.grade(&args("drops-last")).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("grade.json")).unwrap()).unwrap();
    assert_eq!(json["structure"], "drops-last");
    let results = json["kit"]["results"].as_array().unwrap();
    assert_eq!(results.len(), checks);
    let one = results
        .iter()
        .find(|r| r["scene"] == "one_triangle")
        .unwrap();
    assert_eq!(one["passed"], false);
    assert!(
        one["failure"]
            .as_str()
            .unwrap()
            .contains("Ray::with_interval("),
        "{one}"
    );
    let random = results
        .iter()
        .find(|r| r["scene"] == "random_scenes")
        .unwrap();
    assert_eq!(random["passed"], false);
    assert!(
        random["failure"].as_str().unwrap().lines().count() <= 8,
        "{random}"
    );
    // The shootout ran against the reference row, and found the same bug on the soup.
    let rows = json["shootout"][0]["rows"].as_array().unwrap();
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["structure"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["brute-force", "drops-last", "bvh"]);
    assert!(rows[1]["mismatches"].as_u64().unwrap() > 0);
    std::fs::remove_dir_all(&dir).ok();
}

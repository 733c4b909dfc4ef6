//! A structure defined outside the workspace's crates joins the shootout through the public API
//! alone, next to the built-in rows: what a student's crate does (with the example's structure).

#[path = "../examples/groups/groups.rs"]
mod groups;

use groups::{GROUP, Groups};

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

#[test]
fn kit_scenes_replay_in_compare_and_explain_on_an_added_row() {
    let shootout = rt_shootout::Shootout::new().with_triangles::<Groups>();
    // `--scene kit:NAME` is the kit's scene with the kit's own rays.
    let args = rt_shootout::args_from([
        "--scene",
        "kit:lattice",
        "--structures",
        "groups",
        "--repeats",
        "1",
    ])
    .unwrap();
    let reports = shootout.run(&args).unwrap();
    let lattice = rt_conformance::scene("lattice");
    assert_eq!(
        (
            reports[0].ray_kind,
            reports[0].rays,
            reports[0].total_mismatches()
        ),
        ("kit", lattice.rays.len(), 0),
        "compare on kit:lattice traces the kit's rays"
    );
    let err = shootout
        .run(&rt_shootout::args_from(["--scene", "kit:nope"]).unwrap())
        .unwrap_err();
    assert!(
        err.contains("no conformance kit scene named `nope`") && err.contains("lattice"),
        "{err}"
    );
    // `explain` walks an added row on a kit scene; a row that reports no steps says so.
    let ray = lattice.rays[3];
    let explain = rt_shootout::explain::ExplainArgs {
        structures: vec!["groups".into()],
        scene: "kit:lattice".into(),
        ray: Some(ray.to_line()),
        pixel: None,
        width: 64,
        height: 48,
        any: false,
        max_steps: 400,
    };
    let text = rt_shootout::explain::explain(&explain, shootout.entries()).unwrap();
    assert!(
        text.contains("groups on kit:lattice")
            && text.contains("groups reports no steps, only the counts below")
            && text.contains("brute force gives the same answer"),
        "{text}"
    );
}

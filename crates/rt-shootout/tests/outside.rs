//! A structure defined outside the workspace's crates joins the shootout through the public API
//! alone, next to the built-in rows: what a student's crate does (with the example's structure).

#[path = "../examples/shootout/groups.rs"]
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

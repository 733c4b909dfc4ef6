//! `cargo xtask scale` as a user runs it: a small ladder, its JSON, and bad flags.

mod common;

use common::{assert_one_line_error, xtask};

#[test]
fn a_small_ladder_measures_every_row_at_every_size() {
    let out = xtask(
        "scale",
        &[
            "--scene",
            "random-soup",
            "--structures",
            "bvh,grid,octree",
            "--min",
            "1k",
            "--max",
            "5k",
            "--width",
            "24",
            "--height",
            "16",
            "--json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let points = v["points"].as_array().unwrap();
    // Sizes 1k, 3k and 5k, three rows each.
    assert_eq!(points.len(), 9);
    for p in points {
        assert_eq!(p["disagreements"], 0, "{p}");
        // xtask installs the counting allocator: the build's peak holds at least the structure.
        let peak = p["peak_build_bytes"].as_u64().expect("a measured peak");
        assert!(peak >= p["structure_bytes"].as_u64().unwrap(), "{p}");
        assert!(p["trace_ns_per_ray"].as_f64().unwrap() > 0.0);
    }
    assert_eq!(points[0]["triangles"], 1000);
    assert_eq!(points[8]["triangles"], 5000);
}

#[test]
fn bad_flags_are_one_line_errors() {
    assert_one_line_error(
        &xtask("scale", &["--scene", "atlantis"]),
        "built-in scene kind",
    );
    assert_one_line_error(
        &xtask("scale", &["--scene", "terrain:1M"]),
        "built-in scene kind",
    );
    assert_one_line_error(&xtask("scale", &["--max", "lots"]), "--max lots");
    assert_one_line_error(
        &xtask("scale", &["--min", "2M", "--max", "1M"]),
        "above --max",
    );
    assert_one_line_error(
        &xtask("scale", &["--structures", "bvh,nope"]),
        "unknown structure",
    );
}

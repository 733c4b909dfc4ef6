//! `cargo xtask scale` as a user runs it: a small ladder, its JSON, and bad flags.

mod common;

use common::{assert_one_line_error, json, xtask};

#[test]
fn a_small_ladder_measures_every_row_at_every_size() {
    let v = json(
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

/// A scene file gives a ladder of its own first triangles, up to all of them, and the chart goes
/// where `--out` says.
#[test]
fn a_file_ladder_grows_to_the_whole_file() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("scale-file");
    std::fs::create_dir_all(&dir).unwrap();
    // A 40 × 40 grid of vertices: 39 × 39 × 2 = 3,042 triangles.
    let mut obj = String::new();
    for i in 0..1600 {
        obj += &format!("v {} {} {}\n", i % 40, i / 40, (i % 7) as f32 * 0.1);
    }
    for y in 0..39 {
        for x in 0..39 {
            let v = y * 40 + x + 1;
            obj += &format!(
                "f {} {} {}\nf {} {} {}\n",
                v,
                v + 1,
                v + 41,
                v,
                v + 41,
                v + 40
            );
        }
    }
    let file = dir.join("grid.obj");
    std::fs::write(&file, obj).unwrap();
    let chart = dir.join("ladder.svg");
    let v = json(
        "scale",
        &[
            "--scene",
            file.to_str().unwrap(),
            "-s",
            "bvh,grid",
            "--min",
            "1k",
            "-o",
            chart.to_str().unwrap(),
            "--width",
            "24",
            "--height",
            "16",
            "--json",
        ],
    );
    let sizes: Vec<u64> = v["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["triangles"].as_u64().unwrap())
        .collect();
    assert_eq!(sizes, [1000, 1000, 3000, 3000, 3042, 3042]);
    assert!(std::fs::read_to_string(&chart).unwrap().starts_with("<svg"));
}

#[test]
fn bad_flags_are_one_line_errors() {
    assert_one_line_error(
        &xtask("scale", &["--scene", "atlantis"]),
        "no built-in scene or file named `atlantis`",
    );
    assert_one_line_error(
        &xtask("scale", &["--scene", "terrain:1M"]),
        "give the kind alone",
    );
    assert_one_line_error(
        &xtask("scale", &["--max", "lots"]),
        "invalid value 'lots' for '--max",
    );
    assert_one_line_error(
        &xtask("scale", &["--min", "2M", "--max", "1M"]),
        "above --max",
    );
    assert_one_line_error(
        &xtask("scale", &["--structures", "bvh,nope"]),
        "unknown structure",
    );
}

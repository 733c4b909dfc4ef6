//! `cargo xtask draw` as a user runs it: the real binary, its exit status and the SVG it writes.

mod common;

use common::assert_one_line_error;
use std::process::Output;

fn draw(args: &[&str]) -> Output {
    common::xtask("draw", args)
}

#[test]
fn every_structure_draws_its_slice() {
    let dir = std::env::temp_dir().join(format!("rt-accel-draw-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (structure, interior) in [
        ("bvh", true),
        ("kdtree", true),
        ("grid", false),
        ("hgrid", true),
        ("octree", true),
    ] {
        let out = dir.join(format!("{structure}.svg"));
        let o = draw(&[
            "--scene",
            "random-soup",
            "--structures",
            structure,
            "--axis",
            "x",
            "--at",
            "0.4",
            "--fill",
            "prims",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{structure}: {o:?}");
        let svg = std::fs::read_to_string(&out).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains(&format!("{structure} on random-soup: slice x")));
        // The summary line counts what was drawn: cells, and interior nodes where the
        // structure has them, and the soup's cross-section.
        let line = String::from_utf8_lossy(&o.stdout).to_string();
        let count = |what: &str| -> usize {
            let end = line.find(what).unwrap();
            line[..end]
                .split_whitespace()
                .last()
                .unwrap()
                .parse()
                .unwrap()
        };
        assert!(count(" leaves or cells") > 10, "{line}");
        assert_eq!(count(" interior nodes") > 0, interior, "{line}");
        assert!(count(" mesh segments") > 100, "{line}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Several rows each get a file of their own, named after the row.
#[test]
fn several_rows_draw_a_file_each() {
    let dir = std::env::temp_dir().join(format!("rt-accel-draw-rows-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("slice.svg");
    let o = draw(&[
        "--scene",
        "random-soup",
        "-s",
        "kdtree,octree",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{o:?}");
    for row in ["kdtree", "octree"] {
        let svg = std::fs::read_to_string(dir.join(format!("slice-{row}.svg"))).unwrap();
        assert!(svg.contains(&format!("{row} on random-soup: slice z")));
    }
    assert!(!out.exists());
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 2);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    assert_one_line_error(&draw(&["--axis", "w"]), "invalid value 'w' for '--axis");
    assert_one_line_error(&draw(&["--at", "1.5"]), "--at 1.5 is outside 0 to 1");
    assert_one_line_error(
        &draw(&["--fill", "pink"]),
        "invalid value 'pink' for '--fill",
    );
    assert_one_line_error(
        &draw(&["--structures", "octopus"]),
        "unknown structure `octopus`",
    );
    assert_one_line_error(
        &draw(&["--scene", "atlantis"]),
        "built-in scenes: sphereflake",
    );
    assert_one_line_error(&draw(&["--width", "5"]), "--width 5 is not usable");
    assert_one_line_error(
        &draw(&["--out", "/no/such/dir/s.svg"]),
        "/no/such/dir/s.svg: cannot write SVG",
    );
    assert_one_line_error(
        &draw(&["--structures", "brute-force"]),
        "brute-force does not describe its nodes",
    );
}

//! `cargo xtask explain` as a user runs it: every structure's walk is printed, and each printed
//! walk accounts for exactly the visits and tests the structure counted.

mod common;

use common::assert_one_line_error;
use std::process::Output;

fn explain(args: &[&str]) -> Output {
    common::xtask("explain", args)
}

/// The figure on the line that ends with `suffix`, e.g. "12 primitive tests" → 12.
fn count_before(text: &str, label: &str) -> usize {
    let line = text
        .lines()
        .find(|l| l.contains(label))
        .unwrap_or_else(|| panic!("no line with `{label}` in:\n{text}"));
    let at = line.find(label).unwrap();
    line[..at]
        .rsplit([' ', ','])
        .find(|w| !w.is_empty())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no number before `{label}` in `{line}`"))
}

#[test]
fn every_structure_explains_the_walk_it_counted() {
    // The spectator's pixel that looks at the teapot: the hierarchical grid walks a nested grid,
    // the uniform grid tests many triangles in one cell, and the trees descend far.
    for (structure, words) in [
        ("bvh", &["child node", "push ", "test primitive"][..]),
        ("bvh-binary", &["box (", "child node", "pop node"]),
        (
            "kdtree",
            &["split ", "near first, far pushed", "near side only"],
        ),
        ("kdtree-restart", &["split ", "restart from the top node"]),
        ("grid", &["enter cell [", "already tested (mailbox)"]),
        ("hgrid", &["refined by a nested grid", "of nested grid"]),
        ("octree", &["child node", "box ("]),
    ] {
        let o = explain(&[
            "--structures",
            structure,
            "--scene",
            "teapot-in-stadium",
            "--width",
            "64",
            "--height",
            "48",
            "--pixel",
            "32,25",
            "--max-steps",
            "100000",
        ]);
        assert!(o.status.success(), "{structure}: {o:?}");
        let text = String::from_utf8(o.stdout).unwrap();
        for w in words {
            assert!(text.contains(w), "{structure}: no `{w}` in:\n{text}");
        }
        let enters = text.lines().filter(|l| l.starts_with("enter ")).count();
        let tests = text.matches("test primitive").count();
        let skips = text.matches("already tested (mailbox)").count();
        assert_eq!(
            enters,
            count_before(&text, "nodes or cells entered"),
            "{structure}"
        );
        assert_eq!(tests, count_before(&text, "primitive tests"), "{structure}");
        assert_eq!(skips, count_before(&text, "mailbox skips"), "{structure}");
        assert!(text.contains("answer: primitive"), "{structure}:\n{text}");
        assert!(
            text.contains("brute force gives the same answer"),
            "{structure}:\n{text}"
        );
    }
}

/// Several rows explain the same ray one after another; the default row is the BVH.
#[test]
fn several_rows_explain_the_same_ray() {
    let text = |args: &[&str]| {
        let o = explain(args);
        assert!(o.status.success(), "{o:?}");
        String::from_utf8(o.stdout).unwrap()
    };
    let both = text(&["-s", "kdtree,grid", "--scene", "random-soup"]);
    let kd = both
        .find("kdtree on random-soup")
        .expect("the kd-tree's walk");
    let grid = both.find("grid on random-soup").expect("the grid's walk");
    assert!(kd < grid, "{both}");
    assert_eq!(both.matches("\nray: ").count(), 2, "{both}");
    assert!(text(&["--scene", "random-soup"]).starts_with("bvh on random-soup"));
}

#[test]
fn any_hit_and_long_walks_are_explained() {
    let run = |max_steps: &str| {
        let o = explain(&[
            "--structures",
            "grid",
            "--scene",
            "teapot-in-stadium",
            "--ray",
            "0 9 26 0.0077895224 -0.3089879 -0.95103407",
            "--any",
            "--max-steps",
            max_steps,
        ]);
        assert!(o.status.success(), "{o:?}");
        String::from_utf8(o.stdout).unwrap()
    };
    let whole = run("400");
    assert!(whole.contains("any-hit query"), "{whole}");
    assert!(whole.contains("blocks the ray"), "{whole}");
    assert!(whole.contains("answer: occluded"), "{whole}");
    let cut = run("5");
    assert!(!cut.contains("blocks the ray"), "{cut}");
    assert!(
        cut.contains("more steps (--max-steps to see them)"),
        "{cut}"
    );
    assert!(cut.contains("answer: occluded"), "{cut}");
}

#[test]
fn bad_input_gets_one_line() {
    for (args, needle) in [
        (&["--structures", "nope"][..], "unknown structure"),
        (&["--scene", "nope"], "no built-in scene"),
        (&["--ray", "1 2 3"], "expected 6 or 8 numbers"),
        (&["--ray", "0 0 0 0 0 0"], "invalid ray"),
        (&["--pixel", "5000,1"], "inside the 1024x768 image"),
        (&["--pixel", "a,b"], "expected X,Y"),
        (&["--width", "0"], "each must be 1 to 32768"),
    ] {
        assert_one_line_error(&explain(args), needle);
    }
}

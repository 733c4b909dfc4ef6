//! `cargo xtask animate` as a user runs it: an explosion followed by refitting and rebuilding,
//! its JSON, and bad flags.

mod common;

use common::{assert_one_line_error, json, xtask};

fn frames(track: &serde_json::Value) -> &Vec<serde_json::Value> {
    track["frames"].as_array().expect("frames")
}

#[test]
fn an_explosion_shows_the_refitted_tree_drifting_from_rebuilt_ones() {
    let v = json(
        "animate",
        &[
            "--scene",
            "teapot:5k",
            "--animation",
            "explode",
            "--frames",
            "4",
            "--structures",
            "bvh,grid",
            "--width",
            "64",
            "--height",
            "48",
            "--repeats",
            "1",
            "--json",
        ],
    );
    assert_eq!(v["mismatches"], 0);
    let tracks = v["tracks"].as_array().unwrap();
    let names: Vec<String> = tracks
        .iter()
        .map(|t| {
            format!(
                "{} {}",
                t["structure"].as_str().unwrap(),
                t["strategy"].as_str().unwrap()
            )
        })
        .collect();
    assert_eq!(names, ["bvh refit", "bvh rebuild", "grid rebuild"]);
    for t in tracks {
        assert_eq!(frames(t).len(), 5, "{t}");
        for f in frames(t) {
            assert_eq!(f["mismatches"], 0, "{f}");
            assert!(f["update_ms"].as_f64().unwrap() > 0.0, "{f}");
        }
    }
    let sah = |t: &serde_json::Value, f: usize| frames(t)[f]["sah"].as_f64().unwrap();
    // The same tree on the first frame; then the refitted one costs more and more.
    assert_eq!(sah(&tracks[0], 0), sah(&tracks[1], 0));
    let ratios: Vec<f64> = (1..5)
        .map(|f| sah(&tracks[0], f) / sah(&tracks[1], f))
        .collect();
    assert!(
        ratios[0] > 1.0 && ratios.windows(2).all(|w| w[1] > w[0]),
        "{ratios:?}"
    );
}

#[test]
fn the_table_says_where_refitting_stops_paying() {
    let out = xtask(
        "animate",
        &[
            "--scene",
            "teapot:5k",
            "--animation",
            "wave",
            "--frames",
            "2",
            "--structures",
            "bvh",
            "--width",
            "32",
            "--height",
            "24",
            "--repeats",
            "1",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("refit ms") && text.contains("rebuild ms"),
        "{text}"
    );
    assert!(text.contains("refitting pays"), "{text}");
}

#[test]
fn bad_flags_are_one_line_errors() {
    assert_one_line_error(
        &xtask("animate", &["--animation", "melt"]),
        "invalid value 'melt' for '--animation <ANIMATION>' [possible values: wave, explode]",
    );
    assert_one_line_error(&xtask("animate", &["--frames", "0"]), "--frames 0");
    assert_one_line_error(&xtask("animate", &["--scene", "atlantis"]), "atlantis");
    assert_one_line_error(
        &xtask("animate", &["--structures", "bvh,quadtree"]),
        "unknown structure `quadtree`",
    );
    assert_one_line_error(
        &xtask("animate", &["--scene", "../shared/meshes/bad/missing.obj"]),
        "missing.obj",
    );
}

//! A crate of its own, outside this workspace, runs the full shootout with its own structure next
//! to the built-in rows: this test writes such a crate (the example's `main.rs` and `groups.rs`,
//! the two files a student's crate holds) into the target directory, with path dependencies on
//! `rt-core` and `rt-shootout` and nothing else, and runs it with cargo. No file of the
//! workspace names it.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace's root directory.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn a_crate_outside_the_workspace_runs_the_shootout_with_its_own_structure() {
    let root = root().canonicalize().unwrap();
    let krate = root.join("target/outside-crate");
    std::fs::create_dir_all(krate.join("src")).unwrap();
    let manifest = format!(
        r#"[package]
name = "outside-shootout"
version = "0.1.0"
edition = "2024"
publish = false

# Its own workspace: nothing in rt-accel's manifests lists this crate.
[workspace]

[dependencies]
rt-core = {{ path = "{core}" }}
rt-shootout = {{ path = "{shootout}" }}
"#,
        core = root.join("crates/rt-core").display(),
        shootout = root.join("crates/rt-shootout").display(),
    );
    let files = [
        ("Cargo.toml", manifest.as_str()),
        ("src/main.rs", include_str!("../examples/groups/main.rs")),
        (
            "src/groups.rs",
            include_str!("../examples/groups/groups.rs"),
        ),
    ];
    for (name, text) in files {
        std::fs::write(krate.join(name), text).unwrap();
    }
    // The workspace's lock file pins the same dependency versions, so the build needs no
    // network; cargo drops the entries this crate does not use.
    std::fs::copy(root.join("Cargo.lock"), krate.join("Cargo.lock")).unwrap();

    let out = Command::new(env!("CARGO"))
        .current_dir(&krate)
        .env("CARGO_TARGET_DIR", root.join("target/outside"))
        // Nobody steps through this build in a debugger: without debug information it takes
        // less time and disk (the crate's own profile is cargo's default, full debug info).
        .env("CARGO_PROFILE_DEV_DEBUG", "false")
        .args(["run", "--quiet", "--offline", "--"])
        .args(
            "--scene random-soup --structures groups,bvh,kdtree --width 40 --height 30 \
             --repeats 1 --json"
                .split_whitespace(),
        )
        .output()
        .expect("cargo runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "the outside crate's shootout failed: {}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON report");
    let rows = report["results"]
        .as_array()
        .unwrap_or_else(|| panic!("no rows in {report}"));
    let names: Vec<&str> = rows
        .iter()
        .filter_map(|r| r["structure"].as_str())
        .collect();
    assert_eq!(names, ["brute-force", "groups", "bvh", "kdtree"]);
    for row in rows {
        assert_eq!(row["mismatches"], 0, "{row}");
    }
    // The added row did real work: every ray visits every group box of the 20k triangles.
    assert_eq!(rows[1]["avg_visits"], 1250.0, "{}", rows[1]);
}

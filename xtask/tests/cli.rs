//! `cargo xtask compare` as a user runs it: the real binary, its exit status and its output.

mod common;

use common::assert_one_line_error;
use rt_conformance::shared_meshes_dir;
use std::process::Output;

fn compare(args: &[&str]) -> Output {
    common::xtask("compare", args)
}

/// `compare --json` on `scene` with `structures`, at `width` × `height` primary rays, one repeat:
/// the report, after checking that it exited with status 0.
fn small_json(scene: &str, structures: &str, width: u32, height: u32) -> serde_json::Value {
    let (w, h) = (width.to_string(), height.to_string());
    json(&compare(&[
        "--scene",
        scene,
        "--structures",
        structures,
        "--width",
        &w,
        "--height",
        &h,
        "--repeats",
        "1",
        "--json",
    ]))
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "exit {:?}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

#[test]
fn missing_file_unknown_scene_and_unknown_structure_are_one_line_errors() {
    assert_one_line_error(
        &compare(&["--scene", "no/such/file.obj"]),
        "no/such/file.obj: cannot read file",
    );
    assert_one_line_error(
        &compare(&["--scene", "atlantis"]),
        "built-in scenes: sphereflake",
    );
    for bad in ["random-soup:0", "terrain:lots", "sphereflake:1G"] {
        assert_one_line_error(
            &compare(&["--scene", bad]),
            "the size must be a triangle count",
        );
    }
    assert_one_line_error(
        &compare(&["--structures", "bvh,octopus"]),
        "unknown structure `octopus`",
    );
    assert_one_line_error(
        &compare(&["--rays-file", "no/such.rays"]),
        "no/such.rays: cannot read file",
    );
}

#[test]
fn malformed_and_empty_obj_files_are_one_line_errors() {
    let Some(dir) = shared_meshes_dir() else {
        return;
    };
    let bad = dir.join("bad");
    let malformed = bad.join("malformed.obj");
    assert_one_line_error(
        &compare(&["--scene", malformed.to_str().unwrap()]),
        "malformed.obj:23: vertex index 12",
    );
    let empty = bad.join("empty.obj");
    assert_one_line_error(
        &compare(&["--scene", empty.to_str().unwrap()]),
        "empty.obj: no triangles",
    );
    let points = bad.join("testpoints.obj");
    assert_one_line_error(
        &compare(&["--scene", points.to_str().unwrap()]),
        "no triangles",
    );
}

#[test]
fn help_lists_built_in_scenes_and_rows() {
    let out = compare(&["--help"]);
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "sphereflake",
        "random-soup",
        "bvh-median",
        "--rays-file",
        "--json",
    ] {
        assert!(text.contains(needle), "--help lacks {needle}");
    }
}

#[test]
fn default_scene_json_has_every_field_and_no_mismatch() {
    let v = json(&compare(&[
        "--width",
        "64",
        "--height",
        "48",
        "--json",
        "--repeats",
        "1",
    ]));
    assert_eq!(v["scene"], "sphereflake");
    assert_eq!(v["ray_kind"], "primary");
    assert_eq!(v["rays"], 64 * 48);
    assert_eq!(v["triangles"], 82_002);
    let rows = v["results"].as_array().unwrap();
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["structure"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "brute-force",
            "bvh",
            "bvh-binary",
            "bvh-median",
            "bvh-middle",
            "bvh-reinserted",
            "bvh-stream",
            "kdtree",
            "kdtree-fewest-tests",
            "kdtree-wald-havran",
            "kdtree-restart",
            "kdtree-noclip",
            "kdtree-pbrt",
            "grid",
            "grid-nomailbox",
            "grid-bbox",
            "hgrid",
            "hgrid-lean",
            "octree",
            "octree-lean"
        ]
    );
    for r in rows {
        for field in [
            "structure",
            "build_ms",
            "memory_bytes",
            "nodes",
            "max_depth",
            "hits",
            "mismatches",
            "avg_visits",
            "avg_prim_tests",
            "mrays_per_s",
            "leaves",
            "empty_leaves",
            "avg_leaf_prims",
            "prim_refs",
            "duplication",
            "avg_mailbox_skips",
            "extra",
        ] {
            assert!(!r[field].is_null(), "{field} missing in {r}");
        }
        assert_eq!(r["mismatches"], 0, "{r}");
    }
    // Brute force tests every triangle on every ray.
    assert_eq!(rows[0]["avg_prim_tests"], 82_002.0);
    // The grid's mailbox skips repeated tests, and only with the mailbox; the grid names its
    // resolution among its own figures.
    let row = |name: &str| rows.iter().find(|r| r["structure"] == name).unwrap();
    assert!(row("grid")["avg_mailbox_skips"].as_f64().unwrap() > 0.0);
    assert_eq!(row("grid-nomailbox")["avg_mailbox_skips"], 0.0);
    assert!(row("grid")["extra"]["resolution_x"].as_f64().unwrap() >= 1.0);
}

#[test]
fn rays_file_replays_exactly_and_reports_every_answer() {
    let dir = std::env::temp_dir().join(format!("rt-accel-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("rays.txt");
    std::fs::write(
        &file,
        "# three rays at the sphereflake\n0 0 10 0 0 -1\n0 5 0 0 -1 0 0 2.5\n10 10 10 1 0 0 # points away\n",
    )
    .unwrap();
    let v = json(&compare(&[
        "--rays-file",
        file.to_str().unwrap(),
        "--json",
        "--structures",
        "bvh",
    ]));
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(v["ray_kind"], "file");
    assert_eq!(v["rays"], 3);
    let rows = v["results"].as_array().unwrap();
    let answers: Vec<&Vec<serde_json::Value>> = rows
        .iter()
        .map(|r| r["ray_hits"].as_array().unwrap())
        .collect();
    assert_eq!(
        answers[0], answers[1],
        "bvh and brute force agree ray by ray"
    );
    // The first ray meets the flake; the second stops at y = 2.5, above the flake (whose spheres
    // reach y < 2); the third points away from everything.
    assert!(answers[0][0]["t"].as_f64().unwrap() > 0.0);
    assert!(answers[0][1].is_null());
    assert!(answers[0][2].is_null());
}

/// The acceptance runs on the bunny and the teapot, at a reduced image size so the suite stays quick:
/// no mismatch for primary, incoherent and shadow rays; and, on primary rays, the SAH tree
/// needs at most 12 primitive tests per ray and fewer than the median split. The teapot too, and
/// the kd-tree's shape figures are present.
#[test]
fn meshes_all_ray_kinds_agree_and_sah_beats_median() {
    let Some(dir) = shared_meshes_dir() else {
        return;
    };
    for mesh in ["stanford-bunny.obj", "teapot.obj"] {
        let path = dir.join(mesh);
        for kind in ["primary", "incoherent", "shadow"] {
            let v = json(&compare(&[
                "--scene",
                path.to_str().unwrap(),
                "--rays",
                kind,
                "--width",
                "128",
                "--height",
                "96",
                "--check-rays",
                "1500",
                "--repeats",
                "1",
                "--json",
            ]));
            let rows = v["results"].as_array().unwrap();
            for r in rows {
                assert_eq!(r["mismatches"], 0, "{mesh} {kind}: {r}");
            }
            let row = |name: &str| {
                rows.iter()
                    .find(|r| r["structure"] == name)
                    .unwrap_or_else(|| panic!("no {name} row"))
            };
            let tests = |name: &str| row(name)["avg_prim_tests"].as_f64().unwrap();
            // The kd-tree's shape is reported: it duplicates references and has empty leaves.
            let kd = row("kdtree");
            assert!(kd["duplication"].as_f64().unwrap() > 1.0, "{kd}");
            assert!(kd["empty_leaves"].as_u64().unwrap() > 0, "{kd}");
            assert!(kd["empty_leaves"].as_u64() < kd["leaves"].as_u64(), "{kd}");
            if mesh == "stanford-bunny.obj" && kind == "primary" {
                assert!(tests("bvh") <= 12.0, "SAH: {} tests per ray", tests("bvh"));
                // Issue 3's target: the kd-tree priced down to one primitive needs fewer
                // primitive tests than the binary SAH BVH on the bunny's primary rays. The
                // default (`leaf_size: 3`) trades a few tests for speed, and the wide BVH tests
                // more triangles, four at a time.
                assert!(
                    tests("kdtree-fewest-tests") < tests("bvh-binary"),
                    "kd-tree {} vs BVH {}",
                    tests("kdtree-fewest-tests"),
                    tests("bvh-binary")
                );
                assert!(
                    tests("bvh-binary") < tests("bvh-median"),
                    "SAH {} vs median {}",
                    tests("bvh-binary"),
                    tests("bvh-median")
                );
                // Issue 5's target: the octree visits fewer cells per ray than the uniform grid
                // at a comparable memory budget (the lean preset takes less memory than the grid).
                let visits = |name: &str| row(name)["avg_visits"].as_f64().unwrap();
                let memory = |name: &str| row(name)["memory_bytes"].as_f64().unwrap();
                assert!(
                    memory("octree-lean") <= memory("grid"),
                    "{}",
                    row("octree-lean")
                );
                for octree in ["octree", "octree-lean"] {
                    assert!(
                        visits(octree) < visits("grid"),
                        "{octree} {} visits vs grid {}",
                        visits(octree),
                        visits("grid")
                    );
                }
            }
        }
    }
}

/// Issue 5's other target, on the built-in teapot in a stadium: the octree needs at most a third
/// of the uniform grid's primitive tests per primary ray, with no mismatch.
#[test]
fn octree_adapts_to_the_teapot_in_a_stadium() {
    let v = json(&compare(&[
        "--scene",
        "teapot-in-stadium",
        "--structures",
        "grid,octree",
        "--width",
        "128",
        "--height",
        "96",
        "--check-rays",
        "1000",
        "--repeats",
        "1",
        "--json",
    ]));
    let rows = v["results"].as_array().unwrap();
    let tests = |name: &str| {
        let r = rows.iter().find(|r| r["structure"] == name).unwrap();
        assert_eq!(r["mismatches"], 0, "{r}");
        r["avg_prim_tests"].as_f64().unwrap()
    };
    assert!(
        3.0 * tests("octree") <= tests("grid"),
        "octree {} vs grid {} tests per ray",
        tests("octree"),
        tests("grid")
    );
}

/// Every rt-bvh preset answers like brute force on every shared mesh and every built-in scene,
/// for all three ray kinds (issue 11's check of the wide tree, on small images so the test stays
/// quick; the full-size runs are in rt-bvh's documentation).
#[test]
fn every_bvh_preset_agrees_on_every_mesh_and_ray_kind() {
    let Some(dir) = shared_meshes_dir() else {
        return;
    };
    let mut scenes: Vec<String> = std::fs::read_dir(&dir)
        .expect("the shared meshes directory lists")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .map(|p| p.to_str().expect("a UTF-8 path").to_string())
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 12, "{scenes:?}");
    scenes.extend(["sphereflake", "random-soup", "teapot-in-stadium"].map(String::from));
    for scene in &scenes {
        for kind in ["primary", "incoherent", "shadow"] {
            let v = json(&compare(&[
                "--scene",
                scene,
                "--rays",
                kind,
                "--structures",
                "bvh,bvh-binary,bvh-median,bvh-middle",
                "--width",
                "96",
                "--height",
                "72",
                "--check-rays",
                "800",
                "--repeats",
                "1",
                "--json",
            ]));
            let rows = v["results"].as_array().unwrap();
            assert_eq!(rows.len(), 5, "brute force and four presets");
            for r in rows {
                assert_eq!(r["mismatches"], 0, "{scene} {kind}: {r}");
            }
        }
    }
}

#[test]
fn report_writes_markdown_charts_and_heatmaps_for_every_scene() {
    let dir = std::env::temp_dir().join(format!("rt-accel-report-{}", std::process::id()));
    let out = compare(&[
        "--scene",
        "random-soup",
        "--scene",
        "teapot-in-stadium",
        "--structures",
        "bvh,grid",
        "--width",
        "48",
        "--height",
        "36",
        "--repeats",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for file in [
        "mrays.svg",
        "tests.svg",
        "visits.svg",
        "memory.svg",
        "build.svg",
        "model-tests.svg",
        "model-visits.svg",
        "heatmap-random-soup.png",
        "heatmap-teapot-in-stadium.png",
    ] {
        assert!(md.contains(&format!("({file})")), "report.md lacks {file}");
        let bytes = std::fs::read(dir.join(file)).unwrap();
        assert!(bytes.len() > 1000, "{file} is nearly empty");
        if file.ends_with(".svg") {
            let text = String::from_utf8(bytes).unwrap();
            assert!(text.contains("<svg") && text.contains("bvh"), "{file}");
        }
    }
    // One section per scene, each with its table: brute force, bvh and grid.
    assert!(md.contains("## random-soup") && md.contains("## teapot-in-stadium"));
    assert_eq!(md.matches("| grid |").count(), 2);
    std::fs::remove_dir_all(&dir).ok();

    // An unwritable report directory is a one-line error before any measuring.
    assert_one_line_error(
        &compare(&["--out", "/proc/no-such-dir/report"]),
        "cannot create report directory",
    );
}

#[test]
fn json_carries_the_sah_prediction_for_structures_that_describe_themselves() {
    let v = small_json("random-soup", "kdtree,grid", 32, 24);
    for row in v["results"].as_array().unwrap() {
        let predicted = &row["predicted_tests"];
        if row["structure"] == "brute-force" {
            assert!(predicted.is_null());
        } else {
            let p = predicted.as_f64().unwrap();
            assert!(
                p > 0.1 && row["predicted_visits"].as_f64().unwrap() > 1.0,
                "{row}"
            );
        }
    }
}

/// Every row's per-ray answers are the same to the bit on one thread and on two: the parallel
/// builds and the parallel tracing change nothing a user can see.
#[test]
fn answers_are_bit_identical_on_one_thread_and_on_two() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("threads");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("rays.txt");
    let mesh = rt_scene::scenes::builtin("teapot-in-stadium").unwrap();
    let lines: Vec<String> = rt_scene::raygen::incoherent_rays(&mesh.bounds(), 3000, 11)
        .iter()
        .map(|r| r.to_line())
        .collect();
    std::fs::write(&file, lines.join("\n")).unwrap();
    let run = |threads: &str| {
        json(&compare(&[
            "--scene",
            "teapot-in-stadium",
            "--rays-file",
            file.to_str().unwrap(),
            "--json",
            "--threads",
            threads,
        ]))
    };
    let (one, two) = (run("1"), run("2"));
    let rows = |v: &serde_json::Value| v["results"].as_array().unwrap().clone();
    let (one, two) = (rows(&one), rows(&two));
    assert_eq!(one.len(), two.len());
    assert!(one.len() > 10, "every row runs: {}", one.len());
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(a["structure"], b["structure"]);
        assert_eq!(a["ray_hits"].as_array().unwrap().len(), 3000);
        assert!(
            a["ray_hits"] == b["ray_hits"],
            "{}: answers differ between --threads 1 and --threads 2",
            a["structure"]
        );
        assert_eq!(a["nodes"], b["nodes"], "{}", a["structure"]);
    }
}

/// A built-in scene with a size: about that many triangles, every answer checked.
#[test]
fn sized_built_in_scenes_run() {
    for (spec, least, most) in [
        ("terrain:50k", 45_000, 55_000),
        ("sphereflake:20k", 14_000, 28_000),
    ] {
        let v = small_json(spec, "bvh,grid", 32, 24);
        assert_eq!(v["scene"], spec);
        let n = v["triangles"].as_u64().unwrap();
        assert!((least..=most).contains(&n), "{spec}: {n} triangles");
        for row in v["results"].as_array().unwrap() {
            assert_eq!(row["mismatches"], 0, "{spec}: {row}");
        }
    }
}

#[test]
fn ply_and_gltf_files_run_and_broken_ones_are_one_line_errors() {
    use rt_scene::save::{PlyEncoding, glb_bytes, gltf_embedded, ply_bytes};
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-formats");
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = rt_scene::scenes::teapot_with_detail(0.0, 0.3);
    let files = [
        (
            "teapot.ply",
            ply_bytes(&mesh, PlyEncoding::BinaryLittleEndian),
        ),
        ("teapot.gltf", gltf_embedded(&mesh).into_bytes()),
        ("teapot.glb", glb_bytes(&mesh)),
    ];
    for (name, bytes) in &files {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = small_json(
            path.to_str().unwrap(),
            "bvh,kdtree,grid,hgrid,octree",
            64,
            48,
        );
        assert_eq!(out["triangles"], mesh.triangle_count(), "{name}");
        let rows = out["results"].as_array().unwrap();
        assert_eq!(rows.len(), 6, "{name}: brute force and five rows");
        for row in rows {
            assert_eq!(row["mismatches"], 0, "{name}: {}", row["structure"]);
        }
    }
    // Broken copies: one line naming the file and where.
    let mut bad_ply = files[0].1.clone();
    let n = bad_ply.len();
    bad_ply[n - 4..].copy_from_slice(&u32::MAX.to_le_bytes());
    let glb = &files[2].1;
    for (name, bytes, expected) in [
        ("bad.ply", bad_ply, "bad.ply: face "),
        ("cut.glb", glb[..glb.len() / 2].to_vec(), "cut.glb: glTF: "),
        (
            "scene.stl",
            b"solid x".to_vec(),
            "scene.stl: unknown scene format",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        assert_one_line_error(&compare(&["--scene", path.to_str().unwrap()]), expected);
    }
}

/// Issue 15's closest-point acceptance, and issue 29's box overlap: on every shared mesh, each
/// structure's default preset answers 4,000 closest-point queries and 1,000 box queries exactly
/// as brute force does (all of them checked).
/// The shared meshes' OBJ files, sorted (`None` outside CI when the meshes are not there; under
/// CI their absence fails).
fn shared_obj_meshes() -> Option<Vec<std::path::PathBuf>> {
    let dir = shared_meshes_dir()?;
    let mut meshes: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    meshes.sort();
    assert!(meshes.len() >= 10, "{meshes:?}");
    Some(meshes)
}

#[test]
fn closest_points_and_box_overlaps_agree_with_brute_force_on_every_shared_mesh() {
    let Some(meshes) = shared_obj_meshes() else {
        return;
    };
    for mesh in &meshes {
        let v = json(&compare(&[
            "--scene",
            mesh.to_str().unwrap(),
            "--query",
            "closest-point",
            "--structures",
            "bvh,bvh-binary,kdtree,grid,hgrid,octree",
            "--points",
            "4000",
            "--check-rays",
            "4000",
            "--repeats",
            "1",
            "--json",
        ]));
        assert_eq!(v["query"], "closest-point");
        assert_eq!(v["checked_rays"], 4000, "{}", mesh.display());
        let rows = v["results"].as_array().unwrap();
        assert_eq!(rows.len(), 7);
        for r in rows {
            assert_eq!(r["mismatches"], 0, "{}: {r}", mesh.display());
            assert_eq!(
                r["hits"], 4000,
                "no limit: every query finds a triangle; {r}"
            );
        }
        let v = json(&compare(&[
            "--scene",
            mesh.to_str().unwrap(),
            "--query",
            "overlap",
            "--structures",
            "bvh,bvh-binary,kdtree,grid,hgrid,octree",
            "--points",
            "1000",
            "--check-rays",
            "1000",
            "--box-size",
            "0.03",
            "--repeats",
            "1",
            "--json",
        ]));
        assert_eq!(v["query"], "overlap");
        assert_eq!(v["checked_rays"], 1000, "{}", mesh.display());
        let rows = v["results"].as_array().unwrap();
        assert_eq!(rows.len(), 7);
        for r in rows {
            assert_eq!(r["mismatches"], 0, "{}: {r}", mesh.display());
            let hits = r["hits"].as_u64().unwrap();
            assert!(
                hits > 200 && hits < 1000,
                "boxes that meet the mesh and boxes that miss it; {r}"
            );
        }
    }
}

#[test]
fn all_hits_and_filtered_hits_agree_with_brute_force_on_every_shared_mesh() {
    let Some(meshes) = shared_obj_meshes() else {
        return;
    };
    // Primary rays: many cross the mesh several times, and the alpha mask lets them on through
    // its holes (the any-hit answer is checked beside the closest).
    for (query, rays) in [("all-hits", "primary"), ("filtered", "primary")] {
        for mesh in &meshes {
            let v = json(&compare(&[
                "--scene",
                mesh.to_str().unwrap(),
                "--query",
                query,
                "--rays",
                rays,
                "--structures",
                "bvh,bvh-binary,kdtree,grid,hgrid,octree",
                "--width",
                "64",
                "--height",
                "48",
                "--check-rays",
                "1000",
                "--repeats",
                "1",
                "--json",
            ]));
            assert_eq!(v["query"], query);
            // Shadow rays start at the primary hits only: fewer than 1000 on some meshes.
            let rays = v["rays"].as_u64().unwrap();
            assert_eq!(v["checked_rays"], rays.min(1000), "{}", mesh.display());
            let rows = v["results"].as_array().unwrap();
            assert_eq!(rows.len(), 7);
            for r in rows {
                assert_eq!(r["mismatches"], 0, "{query}, {}: {r}", mesh.display());
            }
            // Rays that find something and rays that do not, or the check proves little.
            let share = v["hit_share"].as_f64().unwrap();
            assert!(
                share > 0.02 && share < 0.98,
                "{query}, {}: {share}",
                mesh.display()
            );
        }
    }
}

#[test]
fn signed_distances_agree_with_brute_force_on_every_shared_mesh() {
    let Some(meshes) = shared_obj_meshes() else {
        return;
    };
    for mesh in &meshes {
        let v = json(&compare(&[
            "--scene",
            mesh.to_str().unwrap(),
            "--query",
            "signed-distance",
            "--points",
            "600",
            "--structures",
            "bvh,kdtree,grid,hgrid,octree",
            "--check-rays",
            "600",
            "--repeats",
            "0",
            "--json",
        ]));
        assert_eq!(v["query"], "signed-distance");
        assert_eq!(v["checked_rays"], 600, "{}", mesh.display());
        let rows = v["results"].as_array().unwrap();
        assert_eq!(rows.len(), 6);
        for r in rows {
            assert_eq!(r["mismatches"], 0, "{}: {r}", mesh.display());
        }
        // Points inside and outside, or the sign is not checked; the two flat meshes (every
        // z is 0) enclose nothing, and their winding numbers stay at most ½.
        let share = v["hit_share"].as_f64().unwrap();
        let flat = ["alligator.obj", "woody.obj"]
            .iter()
            .any(|f| mesh.ends_with(f));
        if flat {
            assert_eq!(share, 0.0, "{}", mesh.display());
        } else {
            assert!(share > 0.02 && share < 0.98, "{}: {share}", mesh.display());
        }
        assert!(v["note"].as_str().unwrap().contains("winding tree"), "{v}");
    }
}

#[test]
fn closest_point_options_reject_bad_values_in_one_line() {
    assert_one_line_error(
        &compare(&["--query", "closest-point", "--points", "0"]),
        "--points must be at least 1",
    );
    assert_one_line_error(
        &compare(&["--query", "overlap", "--box-size", "0"]),
        "--box-size must be above 0 and at most 1",
    );
    assert_one_line_error(
        &compare(&["--query", "overlap", "--out", "report-dir"]),
        "--out writes a report of ray queries only; leave it out with --query overlap",
    );
    assert_one_line_error(
        &compare(&["--query", "closest-point", "--max-distance=-1"]),
        "--max-distance must be at least 0",
    );
}

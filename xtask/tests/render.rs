//! `cargo xtask render` as a user runs it: the real binary, its exit status, its output and the
//! PNG it writes.

mod common;

use common::assert_one_line_error;
use rt_conformance::shared_meshes_dir;
use std::path::{Path, PathBuf};
use std::process::Output;

fn render(args: &[&str]) -> Output {
    common::xtask("render", args)
}

/// A fresh directory for one test's output.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rt-accel-render-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Width and height from a PNG's header, after checking the signature.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn renders_a_png_of_the_requested_size() {
    let dir = scratch("ok");
    let out = dir.join("w.png");
    let o = render(&[
        "--width",
        "48",
        "--height",
        "32",
        "--depth",
        "3",
        "--structures",
        "kdtree",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{o:?}");
    assert_eq!(png_size(&out), (48, 32));
    let line = String::from_utf8_lossy(&o.stdout);
    assert!(
        line.starts_with("wrote ") && line.contains("kdtree"),
        "{line}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Several rows render the picture through each (short flags as the guide shows them): every
/// picture must be the same bytes, and the first row's is written.
#[test]
fn several_rows_render_the_same_picture() {
    let dir = scratch("rows");
    let out = dir.join("w.png");
    let o = render(&[
        "--width",
        "32",
        "--height",
        "24",
        "--depth",
        "2",
        "-s",
        "bvh,grid,octree",
        "-j",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{o:?}");
    assert_eq!(png_size(&out), (32, 24));
    let text = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(lines[0].starts_with("wrote ") && lines[0].contains(" bvh built"));
    assert!(lines[1].starts_with("same bytes as bvh:") && lines[1].contains(" grid built"));
    assert!(lines[2].starts_with("same bytes as bvh:") && lines[2].contains(" octree built"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The path tracer renders through every row with single rays, with batches and with both
/// paired: every picture is the same bytes, and each row prints a table of its bounce depths.
#[test]
fn path_tracing_renders_the_same_picture_with_single_rays_and_batches() {
    let dir = scratch("path");
    let out = dir.join("p.png");
    let o = render(&[
        "--integrator",
        "path",
        "--samples",
        "1",
        "--depth",
        "3",
        "--width",
        "32",
        "--height",
        "24",
        "-s",
        "bvh,grid",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{o:?}");
    assert_eq!(png_size(&out), (32, 24));
    let text = String::from_utf8_lossy(&o.stdout);
    let verdicts: Vec<&str> = text
        .lines()
        .filter(|l| l.contains(" rendered in "))
        .collect();
    assert_eq!(verdicts.len(), 2, "{text}");
    assert!(verdicts[0].starts_with("wrote ") && verdicts[0].contains(" bvh rendered"));
    assert!(
        verdicts[1].starts_with("same bytes as bvh:") && verdicts[1].contains(" grid rendered")
    );
    assert!(!text.contains("DIFFERENT"), "{text}");
    // Per row: the header and depths 0, 1 and 2; depth 0 traces one ray per pixel.
    let depth_rows: Vec<Vec<&str>> = text
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>())
        .filter(|w| w.len() > 2 && w[0].parse::<u32>().is_ok())
        .collect();
    assert_eq!(depth_rows.len(), 6, "{text}");
    assert_eq!(depth_rows[0][..2], ["0", "768"], "{text}");
    assert_eq!(depth_rows[2][0], "2", "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn heatmap_strip_has_one_panel_per_structure() {
    let dir = scratch("heat");
    let out = dir.join("h.png");
    let o = render(&[
        "--scene",
        "teapot-in-stadium",
        "--heatmap",
        "tests",
        "--structures",
        "bvh,grid",
        "--width",
        "40",
        "--height",
        "30",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{o:?}");
    let (w, _) = png_size(&out);
    // Two panels and three gaps of 8 pixels.
    assert_eq!(w, 2 * 40 + 3 * 8);
    let line = String::from_utf8_lossy(&o.stdout);
    // The uniform grid tests far more triangles per ray than the BVH on this scene.
    let mean = |name: &str| -> f64 {
        let rest = &line[line.find(&format!(" {name} ")).unwrap() + name.len() + 2..];
        rest.split_whitespace().next().unwrap().parse().unwrap()
    };
    assert!(mean("grid") > 10.0 * mean("bvh"), "{line}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let dir = scratch("bad");
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    assert_one_line_error(
        &render(&["--structures", "octopus", "--out", out]),
        "unknown structure `octopus`",
    );
    assert_one_line_error(
        &render(&["--scene", "atlantis", "--out", out]),
        "built-in scenes: whitted",
    );
    assert_one_line_error(
        &render(&["--scene", "no/such/file.obj", "--out", out]),
        "no/such/file.obj: cannot read file",
    );
    assert_one_line_error(
        &render(&["--width", "0", "--out", out]),
        "image size 0×768 is not usable",
    );
    assert_one_line_error(
        &render(&["--height", "100000", "--out", out]),
        "is not usable",
    );
    assert_one_line_error(&render(&["--depth", "0", "--out", out]), "--depth 0");
    assert_one_line_error(
        &render(&["--integrator", "path", "--samples", "0", "--out", out]),
        "--samples 0 is not usable",
    );
    assert_one_line_error(
        &render(&["--integrator", "paths", "--out", out]),
        "invalid value 'paths' for '--integrator",
    );
    assert_one_line_error(
        &render(&["--heatmap", "visits", "--integrator", "path", "--out", out]),
        "cannot be used with",
    );
    assert_one_line_error(
        &render(&[
            "--out",
            "/no/such/dir/x.png",
            "--width",
            "8",
            "--height",
            "8",
        ]),
        "/no/such/dir/x.png: cannot write PNG",
    );
    assert_one_line_error(
        &render(&["--out", dir.to_str().unwrap()]),
        "it is a directory",
    );
    assert_one_line_error(
        &render(&["--heatmap", "colours", "--out", out]),
        "invalid value 'colours' for '--heatmap",
    );
    assert_one_line_error(
        &render(&[
            "--heatmap",
            "visits",
            "--structures",
            "bvh,nope",
            "--out",
            out,
        ]),
        "unknown structure `nope`",
    );
    assert!(!Path::new(out).exists(), "nothing is written on bad input");
    if let Some(meshes) = shared_meshes_dir() {
        let malformed = meshes.join("bad").join("malformed.obj");
        assert_one_line_error(
            &render(&["--scene", malformed.to_str().unwrap(), "--out", out]),
            "malformed.obj:23:",
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

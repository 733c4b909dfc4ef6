//! The fuzz targets' bodies in the normal suite: over the seed corpora in `fuzz/seeds/` and over
//! every input a fuzzer found failing, kept in `fuzz/regressions/` (one folder per target).
//!
//! The seeds are generated here, so they stay in step with the formats and the kit's scenes:
//! `RT_BLESS=1 cargo test -p rt-shootout --test fuzz_corpus` rewrites them.

use rt_bvh::Bvh;
use rt_conformance::{SCENES, lattice_rays, lattice_triangles, scene};
use rt_core::glam::Vec3;
use rt_core::{Accel, Mesh, Ray, Triangle};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_persist::Persist;
use rt_scene::SceneFormat;
use rt_scene::save::{PlyEncoding, glb_bytes, gltf_embedded, ply_bytes};
use rt_shootout::fuzz;
use std::path::{Path, PathBuf};

const TARGETS: [&str; 10] = [
    "load_obj",
    "load_ply",
    "load_gltf",
    "trace",
    "bundle",
    "saved_bvh",
    "saved_kdtree",
    "saved_grid",
    "saved_hgrid",
    "saved_octree",
];

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
}

/// Runs target `target`'s body on `bytes`, with a message naming `what` on failure.
fn run(target: &str, what: &str, bytes: &[u8]) {
    match target {
        "load_obj" => fuzz::load(SceneFormat::Obj, bytes),
        "load_ply" => fuzz::load(SceneFormat::Ply, bytes),
        "load_gltf" => fuzz::load(SceneFormat::Gltf, bytes),
        "trace" => {
            if let Err(e) = fuzz::trace(bytes) {
                panic!("{what}: {e}");
            }
        }
        "bundle" => {
            if let Err(e) = fuzz::bundle(bytes) {
                panic!("{what}: {e}");
            }
        }
        saved if fuzz::SAVED_TARGETS.contains(&saved) => {
            if let Err(e) = fuzz::saved(saved, bytes) {
                panic!("{what}: {e}");
            }
        }
        _ => panic!("unknown target {target}"),
    }
}

fn cube() -> Mesh {
    Mesh::cuboid(Vec3::ZERO, Vec3::ONE)
}

/// Every seed: (target, file name, bytes).
fn seeds() -> Vec<(&'static str, String, Vec<u8>)> {
    let mut out = Vec::new();
    let obj = "# a cube with texture coordinates, normals, quads and negative indices\n\
        o cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 -1\nvn 0 0 1\n\
        f 1/1/1 4/3/1 3/2/1 2/1/1\nf 5/1/2 6/2/2 7/3/2 8/3/2\ng sides\nf -8 -7 -3 -4\n\
        f 2 3 7 6\nf 3 4 8\nf 3 8 7\nl 1 2\np 1\n";
    out.push(("load_obj", "cube.obj".into(), obj.as_bytes().to_vec()));
    out.push((
        "load_obj",
        "triangle.obj".into(),
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
    ));
    let cube = cube();
    for (name, enc) in [
        ("cube-ascii.ply", PlyEncoding::Ascii),
        ("cube-le.ply", PlyEncoding::BinaryLittleEndian),
        ("cube-be.ply", PlyEncoding::BinaryBigEndian),
    ] {
        out.push(("load_ply", name.into(), ply_bytes(&cube, enc)));
    }
    let ngon = "ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\n\
        property double z\nproperty uchar red\nelement face 1\nproperty list uchar uint vertex_index\n\
        end_header\n0 0 0 1\n2 0 0 2\n2 2 0 3\n1 1 0 4\n0 2 0 5\n5 0 1 2 3 4\n";
    out.push(("load_ply", "ngon.ply".into(), ngon.as_bytes().to_vec()));
    out.push((
        "load_gltf",
        "cube.gltf".into(),
        gltf_embedded(&cube).into_bytes(),
    ));
    out.push(("load_gltf", "cube.glb".into(), glb_bytes(&cube)));
    for name in SCENES {
        let s = scene(name);
        let bytes = fuzz::encode(&s.triangles, &s.rays);
        if !bytes.is_empty() {
            out.push(("trace", format!("{name}.bin"), bytes));
        }
    }
    out.push(("trace", "cube.bin".into(), cube_trace()));
    // The kit's lattice scenes, on the quarter lattice: the cases `trace` compares with brute
    // force.
    for seed in 1..=4 {
        let tris = lattice_triangles(seed, fuzz::MAX_TRIANGLES);
        let rays = lattice_rays(seed, fuzz::MAX_RAYS);
        let bytes =
            fuzz::encode_lattice(&tris, &rays).expect("the kit's lattice is a quarter lattice");
        assert_eq!(bytes[0] & 1, 0);
        out.push(("trace", format!("lattice-{seed}.bin"), bytes));
    }
    // The bundle target reads the trace target's cases.
    let bundle: Vec<_> = out
        .iter()
        .filter(|(target, ..)| *target == "trace")
        .map(|(_, name, bytes)| ("bundle", name.clone(), bytes.clone()))
        .collect();
    out.extend(bundle);
    // Each structure saved with each of its presets over the kit's smaller scenes: files the
    // loaders accept, for the `saved_*` targets to change.
    for name in SAVED_SCENES {
        let s = scene(name);
        saved_seeds::<Bvh<Triangle>>(&mut out, "saved_bvh", name, &s.triangles);
        saved_seeds::<KdTree<Triangle>>(&mut out, "saved_kdtree", name, &s.triangles);
        saved_seeds::<Grid<Triangle>>(&mut out, "saved_grid", name, &s.triangles);
        saved_seeds::<HGrid<Triangle>>(&mut out, "saved_hgrid", name, &s.triangles);
        saved_seeds::<Octree<Triangle>>(&mut out, "saved_octree", name, &s.triangles);
    }
    out
}

/// The kit's scenes whose saved files stay small (a few kilobytes), so a fuzzer runs fast.
const SAVED_SCENES: [&str; 5] = [
    "empty_scene",
    "one_triangle",
    "shared_edge",
    "far_origins",
    "lattice",
];

fn saved_seeds<A: Accel<Prim = Triangle> + Persist>(
    out: &mut Vec<(&'static str, String, Vec<u8>)>,
    target: &'static str,
    scene: &str,
    tris: &[Triangle],
) {
    for (preset, params) in A::presets() {
        out.push((
            target,
            format!("{scene}-{preset}.bin"),
            A::build(tris, &params).save(),
        ));
    }
}

/// The cube's triangles on the lattice (low bit of the first byte clear) and rays through its
/// edges and corners.
fn cube_trace() -> Vec<u8> {
    let c = cube();
    let q = |v: f32| (v * 4.0) as i8 as u8;
    let mut out = vec![0, (c.triangle_count() - 1) as u8];
    for t in c.triangles() {
        for v in [t.v0, t.v1, t.v2] {
            out.extend(v.to_array().map(q));
        }
    }
    for (o, d) in [
        (Vec3::new(-1.0, 0.5, 0.5), Vec3::X),
        (Vec3::new(-1.0, 0.0, 0.0), Vec3::X),
        (Vec3::new(-1.0, -1.0, -1.0), Vec3::ONE),
        (Vec3::new(0.5, 0.5, 0.5), Vec3::new(0.0, -1.0, 0.0)),
        (Vec3::new(1.0, 2.0, 1.0), Vec3::new(0.0, -1.0, 0.0)),
        (Vec3::new(2.0, 2.0, 2.0), Vec3::ZERO),
    ] {
        out.extend(o.to_array().map(q));
        out.extend(d.to_array().map(q));
    }
    out
}

#[test]
fn seeds_are_current() {
    let bless = std::env::var_os("RT_BLESS").is_some();
    let root = fuzz_dir().join("seeds");
    let mut stale = Vec::new();
    for (target, name, bytes) in seeds() {
        let path = root.join(target).join(&name);
        if bless {
            std::fs::create_dir_all(path.parent().expect("a folder")).expect("seed folder");
            std::fs::write(&path, &bytes).expect("seed written");
        } else if std::fs::read(&path).ok().as_deref() != Some(&bytes[..]) {
            stale.push(format!("{target}/{name}"));
        }
    }
    assert!(
        stale.is_empty(),
        "seeds missing or out of date: {stale:?}; rewrite them with RT_BLESS=1"
    );
}

#[test]
fn every_seed_and_regression_passes() {
    let mut ran = 0;
    for kind in ["seeds", "regressions"] {
        for target in TARGETS {
            let Ok(entries) = std::fs::read_dir(fuzz_dir().join(kind).join(target)) else {
                assert_ne!(kind, "seeds", "fuzz/seeds/{target} is missing");
                continue;
            };
            for entry in entries {
                let path = entry.expect("entry").path();
                let bytes = std::fs::read(&path).expect("readable");
                run(target, &path.display().to_string(), &bytes);
                ran += 1;
            }
        }
    }
    assert!(ran >= seeds().len(), "ran {ran} inputs");
}

#[test]
fn decode_gives_back_what_encode_wrote() {
    let tris = vec![
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
        Triangle::new(Vec3::splat(f32::NAN), Vec3::splat(1e30), Vec3::splat(-0.0)),
    ];
    let rays = vec![
        Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
    ];
    let case = fuzz::decode(&fuzz::encode(&tris, &rays));
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    assert_eq!(case.tris.len(), 2);
    for (a, b) in case.tris.iter().zip(&tris) {
        assert_eq!([a.v0, a.v1, a.v2].map(bits), [b.v0, b.v1, b.v2].map(bits));
    }
    assert_eq!(case.rays.len(), 2);
    for (a, b) in case.rays.iter().zip(&rays) {
        assert_eq!(
            (bits(a.origin), bits(a.dir())),
            (bits(b.origin), bits(b.dir()))
        );
    }
    // A planted bug is caught: a structure that lost a triangle would disagree; here, the
    // decoder's lattice mode reads signed quarters.
    let lattice = fuzz::decode(&[0, 0, 4, 0, 0, 0, 4, 0, 0, 0, 252]);
    assert_eq!(lattice.tris[0].v0, Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(lattice.tris[0].v2, Vec3::new(0.0, 0.0, -1.0));
}

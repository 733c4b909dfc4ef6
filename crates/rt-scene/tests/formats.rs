//! PLY and glTF loading: round trips through every encoding and layout, the features real files
//! use (n-gons, extra properties and elements, node transforms, strips and fans), and broken
//! files, each of which must give one clear error naming where it is.
#![cfg(all(feature = "ply", feature = "gltf"))]

use rt_core::Mesh;
use rt_core::glam::{Mat4, Quat, Vec3};
use rt_scene::save::{PlyEncoding, glb_bytes, gltf_embedded, gltf_external, ply_bytes};
use rt_scene::{LoadError, LoadErrorKind, SceneFormat, load_mesh, load_mesh_bytes, scenes};
use std::f32::consts::FRAC_1_SQRT_2;

fn ply(bytes: &[u8]) -> Result<Mesh, LoadError> {
    load_mesh_bytes("t.ply", SceneFormat::Ply, bytes)
}

fn gltf(bytes: &[u8]) -> Result<Mesh, LoadError> {
    load_mesh_bytes("t.gltf", SceneFormat::Gltf, bytes)
}

/// A scratch folder of this test's own under the target directory.
fn folder(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

#[test]
fn every_ply_encoding_round_trips_exactly() {
    let mesh = scenes::teapot_with_detail(0.0, 0.3);
    for encoding in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let back = ply(&ply_bytes(&mesh, encoding)).unwrap_or_else(|e| panic!("{encoding:?}: {e}"));
        assert_eq!(back.triangles(), mesh.triangles(), "{encoding:?}");
    }
}

#[test]
fn every_gltf_layout_round_trips_exactly() {
    let mesh = scenes::teapot_with_detail(0.0, 0.3);
    let dir = folder("gltf-layouts");
    std::fs::write(dir.join("embedded.gltf"), gltf_embedded(&mesh)).unwrap();
    let (json, bin) = gltf_external(&mesh, "teapot%20data.bin");
    std::fs::write(dir.join("external.gltf"), json).unwrap();
    std::fs::write(dir.join("teapot data.bin"), bin).unwrap();
    std::fs::write(dir.join("binary.glb"), glb_bytes(&mesh)).unwrap();
    for name in ["embedded.gltf", "external.gltf", "binary.glb"] {
        let back = load_mesh(dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back.triangles(), mesh.triangles(), "{name}");
    }
    // From memory, an external buffer cannot be found.
    let (json, _) = gltf_external(&mesh, "teapot.bin");
    let e = gltf(json.as_bytes()).unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::Unsupported(_)), "{e}");
    assert_eq!(e.element.as_deref(), Some("buffer 0"));
}

#[test]
fn ply_reads_ngons_extra_properties_and_elements() {
    // Doubles, an extra colour property, an element the loader skips between vertices and
    // faces, `vertex_index` with unsigned indices, a quad and a concave pentagon.
    let text = "ply\nformat ascii 1.0\ncomment scanned\nobj_info test\n\
        element vertex 6\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\n\
        element material 1\nproperty float shine\n\
        element face 2\nproperty list uchar uint vertex_index\nproperty uchar flags\n\
        end_header\n\
        0 0 0 255\n2 0 0 0\n2 2 0 0\n0 2 0 0\n1 1 0 0\n1 0.5 1 0\n\
        0.5\n\
        4 0 1 2 3 7\n5 0 1 2 4 3 0\n";
    let mesh = ply(text.as_bytes()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.triangle_count(), 2 + 3);
    // The quad's two triangles cover its area, the pentagon's three cover its area (the square
    // minus the notch down to (1, 1)): 4 + 3.
    let area: f32 = mesh
        .triangles()
        .iter()
        .map(|t| 0.5 * (t.v1 - t.v0).cross(t.v2 - t.v0).length())
        .sum();
    assert!((area - 7.0).abs() < 1e-5, "area {area}");
}

#[test]
fn gltf_applies_node_transforms_and_reads_strips_and_fans() {
    // One buffer: a unit right triangle's three corners and a fourth point, as positions;
    // primitives in triangle mode (indexed), strip and fan mode (not indexed), and points
    // (skipped). The mesh is placed twice: under a translated parent, rotated and scaled.
    let corners: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let mut bin: Vec<u8> = corners
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    bin.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()));
    use base64::Engine;
    let uri = base64::engine::general_purpose::STANDARD.encode(&bin);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"translation":[10,0,0],"children":[1,2]}},
                 {{"mesh":0}},
                 {{"mesh":0,"rotation":[0,0,0.7071068,0.7071068],"scale":[2,2,2]}}],
        "meshes":[{{"primitives":[
            {{"attributes":{{"POSITION":0}},"indices":1}},
            {{"attributes":{{"POSITION":0}},"mode":5}},
            {{"attributes":{{"POSITION":0}},"mode":6}},
            {{"attributes":{{"POSITION":0}},"mode":0}}]}}],
        "buffers":[{{"byteLength":{},"uri":"data:application/gltf-buffer;base64,{uri}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":6}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        bin.len()
    );
    let mesh = gltf(json.as_bytes()).unwrap_or_else(|e| panic!("{e}"));
    // Per placement: 1 indexed triangle, 2 strip triangles, 2 fan triangles; points skipped.
    assert_eq!(mesh.triangle_count(), 2 * 5);
    let p = |i: usize| Vec3::from(corners[i]);
    let first = Mat4::from_translation(Vec3::new(10.0, 0.0, 0.0));
    let second = first
        * Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            Quat::from_xyzw(0.0, 0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2),
            Vec3::ZERO,
        );
    let tris = mesh.triangles();
    for (placement, world) in [first, second].iter().enumerate() {
        let got: Vec<[Vec3; 3]> = tris[5 * placement..5 * placement + 5]
            .iter()
            .map(|t| [t.v0, t.v1, t.v2])
            .collect();
        // Nodes are visited depth first from the last child pushed, so the scaled copy (node 2)
        // comes first; find each placement's triangles by their first corner.
        let want: Vec<[Vec3; 3]> = [[0, 1, 2], [0, 1, 2], [2, 1, 3], [0, 1, 2], [0, 2, 3]]
            .iter()
            .map(|t| t.map(|i| world.transform_point3(p(i))))
            .collect();
        let other: Vec<[Vec3; 3]> = tris[5 * (1 - placement)..5 * (1 - placement) + 5]
            .iter()
            .map(|t| [t.v0, t.v1, t.v2])
            .collect();
        let close = |a: &[[Vec3; 3]], b: &[[Vec3; 3]]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| x.iter().zip(y).all(|(u, v)| u.distance(*v) < 1e-5))
        };
        assert!(
            close(&got, &want) || close(&other, &want),
            "placement {placement}: {got:?} or {other:?}, want {want:?}"
        );
    }
}

/// Which error a broken file gives: the line or element, and the kind's name.
fn check(
    name: &str,
    got: Result<Mesh, LoadError>,
    line: Option<usize>,
    element: Option<&str>,
    kind: &str,
) {
    let e = match got {
        Ok(m) => panic!("{name}: loaded {} triangles", m.triangle_count()),
        Err(e) => e,
    };
    let msg = e.to_string();
    assert!(!msg.contains('\n'), "{name}: one line: {msg}");
    assert_eq!(e.line, line, "{name}: {msg}");
    assert_eq!(e.element.as_deref(), element, "{name}: {msg}");
    assert!(format!("{:?}", e.kind).starts_with(kind), "{name}: {msg}");
}

/// A broken PLY file: its name, its text, and the line, element and kind of error it gives.
type PlyCase = (
    &'static str,
    String,
    Option<usize>,
    Option<&'static str>,
    &'static str,
);

const HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
    property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
    end_header\n";

#[test]
fn broken_ply_files_name_the_line_or_element() {
    let ok = format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    assert_eq!(ply(ok.as_bytes()).unwrap().triangle_count(), 1);
    // Lines 10-12 are the vertices, 13 the face.
    // (name, file, line, element, kind)
    let cases: Vec<PlyCase> = vec![
        (
            "index",
            format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
            Some(13),
            None,
            "NoSuchVertex",
        ),
        (
            "negative",
            format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"),
            Some(13),
            None,
            "NoSuchVertex",
        ),
        (
            "nan",
            format!("{HEADER}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"),
            Some(11),
            None,
            "Invalid",
        ),
        (
            "overflow",
            format!("{HEADER}0 0 0\n1 0 0\n0 1e39 0\n3 0 1 2\n"),
            Some(12),
            None,
            "NonFinite",
        ),
        (
            "two corners",
            format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
            Some(13),
            None,
            "Invalid",
        ),
        (
            "word",
            format!("{HEADER}0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"),
            Some(11),
            None,
            "Invalid",
        ),
        (
            "short",
            format!("{HEADER}0 0 0\n1 0 0\n"),
            Some(12),
            None,
            "Invalid",
        ),
        (
            "magic",
            "plx\nformat ascii 1.0\nend_header\n".into(),
            Some(1),
            None,
            "Invalid",
        ),
        (
            "no header end",
            "ply\nformat ascii 1.0\nelement vertex 1\n".into(),
            Some(4),
            None,
            "Invalid",
        ),
        (
            "no faces",
            HEADER.replace(
                "element face 1\nproperty list uchar int vertex_indices\n",
                "",
            ) + "0 0 0\n1 0 0\n0 1 0\n",
            None,
            None,
            "NoTriangles",
        ),
        (
            "no z",
            HEADER.replace("property float z\n", "") + "0 0\n1 0\n0 1\n3 0 1 2\n",
            None,
            None,
            "Unsupported",
        ),
        (
            "no list",
            HEADER.replace("property list uchar int vertex_indices", "property int a")
                + "0 0 0\n1 0 0\n0 1 0\n3\n",
            None,
            None,
            "Unsupported",
        ),
        (
            "huge count",
            HEADER.replace("vertex 3", "vertex 4000000000") + "0 0 0\n",
            Some(11),
            None,
            "Invalid",
        ),
    ];
    for (name, text, line, element, kind) in cases {
        check(name, ply(text.as_bytes()), line, element, kind);
    }
    // Binary files have no lines: the element is named instead.
    let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
    let good = ply_bytes(&mesh, PlyEncoding::BinaryLittleEndian);
    let mut bad_index = good.clone();
    let n = bad_index.len();
    bad_index[n - 4..].copy_from_slice(&9u32.to_le_bytes());
    check(
        "binary index",
        ply(&bad_index),
        None,
        Some("face 0"),
        "NoSuchVertex",
    );
    let mut nan = good.clone();
    let at = good.len() - 13 - 36 + 16;
    nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    check("binary nan", ply(&nan), None, Some("vertex 1"), "NonFinite");
    check(
        "truncated",
        ply(&good[..good.len() - 3]),
        None,
        Some("face element"),
        "Invalid",
    );
    let mut huge_list = good.clone();
    huge_list[n - 13] = 255;
    check(
        "long list",
        ply(&huge_list),
        None,
        Some("face element"),
        "Invalid",
    );
}

#[test]
fn broken_gltf_files_name_the_element() {
    let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
    let good = gltf_embedded(&mesh);
    assert_eq!(gltf(good.as_bytes()).unwrap().triangle_count(), 1);
    let (json, bin) = gltf_external(&mesh, "x.bin");
    let with = |bin: &[u8]| {
        use base64::Engine;
        json.replace(
            "\"uri\":\"x.bin\"",
            &format!(
                "\"uri\":\"data:application/octet-stream;base64,{}\"",
                base64::engine::general_purpose::STANDARD.encode(bin)
            ),
        )
    };
    let mut bad_index = bin.clone();
    let n = bin.len();
    bad_index[n - 4..].copy_from_slice(&3u32.to_le_bytes());
    let mut nan = bin.clone();
    nan[0..4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let cases: Vec<(&str, String, Option<&str>, &str)> = vec![
        ("not json", "{\"asset\":".into(), None, "Invalid"),
        ("no asset", "{}".into(), None, "Invalid"),
        (
            "short buffer",
            with(&bin[..20]),
            Some("buffer 0"),
            "Invalid",
        ),
        (
            "bad base64",
            good.replace("base64,", "base64,!!"),
            Some("buffer 0"),
            "Invalid",
        ),
        (
            "index",
            with(&bad_index),
            Some("mesh 0 primitive 0"),
            "NoSuchVertex",
        ),
        (
            "infinite",
            with(&nan),
            Some("mesh 0 primitive 0"),
            "NonFinite",
        ),
        (
            "count",
            good.replace(
                "\"count\":3,\"type\":\"VEC3\"",
                "\"count\":3000000000,\"type\":\"VEC3\"",
            ),
            Some("mesh 0 primitive 0"),
            "Invalid",
        ),
        (
            "type",
            good.replace("\"componentType\":5126", "\"componentType\":5123"),
            Some("mesh 0 primitive 0"),
            "Invalid",
        ),
        (
            "stride",
            good.replace(
                "\"byteOffset\":0,\"byteLength\":36}",
                "\"byteOffset\":0,\"byteLength\":36,\"byteStride\":4}",
            ),
            Some("mesh 0 primitive 0"),
            "Invalid",
        ),
        (
            "view",
            good.replace("\"byteOffset\":36", "\"byteOffset\":4000000000"),
            Some("mesh 0 primitive 0"),
            "Invalid",
        ),
        (
            "cycle",
            good.replace(
                "\"nodes\":[{\"mesh\":0}]",
                "\"nodes\":[{\"mesh\":0,\"children\":[0]}]",
            ),
            None,
            "Invalid",
        ),
        // gltf 1.4's validator panics on this one; the loader checks it first.
        (
            "no accessors",
            good.replace("\"accessors\"", "\"accessorz\""),
            Some("mesh 0 primitive 0"),
            "Invalid",
        ),
        (
            "lines only",
            good.replace("\"mode\":4", "\"mode\":1"),
            None,
            "NoTriangles",
        ),
        (
            "not three",
            good.replace(
                "\"count\":3,\"type\":\"SCALAR\"",
                "\"count\":2,\"type\":\"SCALAR\"",
            ),
            Some("mesh 0 primitive 0"),
            "Invalid",
        ),
    ];
    for (name, text, element, kind) in cases {
        assert_ne!(text, good, "{name}: the edit must change the file");
        check(name, gltf(text.as_bytes()), None, element, kind);
    }
    let glb = glb_bytes(&mesh);
    for cut in [4, 12, 20, glb.len() - 8, glb.len() - 1] {
        let got = load_mesh_bytes("t.glb", SceneFormat::Gltf, &glb[..cut]);
        assert!(got.is_err(), "a GLB cut at {cut} bytes loaded");
    }
}

#[test]
fn extensions_choose_the_loader() {
    let e = load_mesh("scene.stl").unwrap_err();
    assert_eq!(e.kind, LoadErrorKind::UnknownFormat);
    assert_eq!(e.to_string().lines().count(), 1);
    let e = load_mesh("missing.GLB").unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::Io(_)), "{e}");
}

/// Every broken OBJ file of `../shared/meshes/bad/` read as PLY and as glTF: an error, never a
/// panic.
#[test]
fn shared_bad_files_are_errors_for_the_other_loaders() {
    let Some(dir) = rt_conformance::shared_meshes_dir() else {
        return;
    };
    let mut read = 0;
    for entry in std::fs::read_dir(dir.join("bad")).expect("bad/ is readable") {
        let bytes = std::fs::read(entry.expect("entry").path()).expect("readable");
        for format in [SceneFormat::Ply, SceneFormat::Gltf] {
            let e = load_mesh_bytes("bad", format, &bytes).expect_err("not a PLY or glTF file");
            assert!(!e.to_string().contains('\n'), "{e}");
        }
        read += 1;
    }
    assert!(read >= 10, "only {read} files in bad/");
}

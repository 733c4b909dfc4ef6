//! Writing a [`Mesh`] as PLY or glTF, so that a scene can be converted and handed to any
//! program (or back to [`load_mesh`](crate::load_mesh)): positions and triangles only.
//!
//! ```
//! use rt_scene::save::{PlyEncoding, ply_bytes};
//! use rt_scene::{SceneFormat, load_mesh_bytes, scenes};
//!
//! let teapot = scenes::teapot(0.0);
//! let bytes = ply_bytes(&teapot, PlyEncoding::BinaryBigEndian);
//! // Reading PLY back needs the `ply` feature (writing does not).
//! #[cfg(feature = "ply")]
//! {
//!     let back = load_mesh_bytes("teapot.ply", SceneFormat::Ply, &bytes).unwrap();
//!     assert_eq!(back.triangles(), teapot.triangles());
//! }
//! ```

use rt_core::Mesh;

/// How a PLY file stores its numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlyEncoding {
    /// Text, one vertex or face per line.
    Ascii,
    /// Binary, least significant byte first.
    BinaryLittleEndian,
    /// Binary, most significant byte first.
    BinaryBigEndian,
}

/// The mesh as a PLY file: `float` x, y, z per vertex and a `uchar`-counted `int` index list per
/// face.
pub fn ply_bytes(mesh: &Mesh, encoding: PlyEncoding) -> Vec<u8> {
    let format = match encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment written by rt-core\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        mesh.positions().len(),
        mesh.indices().len()
    )
    .into_bytes();
    let word = |out: &mut Vec<u8>, bits: u32| match encoding {
        PlyEncoding::BinaryBigEndian => out.extend_from_slice(&bits.to_be_bytes()),
        _ => out.extend_from_slice(&bits.to_le_bytes()),
    };
    for p in mesh.positions() {
        if encoding == PlyEncoding::Ascii {
            // `{:?}` prints the shortest text that reads back as the same f32.
            out.extend_from_slice(format!("{:?} {:?} {:?}\n", p.x, p.y, p.z).as_bytes());
        } else {
            for c in p.to_array() {
                word(&mut out, c.to_bits());
            }
        }
    }
    for t in mesh.indices() {
        if encoding == PlyEncoding::Ascii {
            out.extend_from_slice(format!("3 {} {} {}\n", t[0], t[1], t[2]).as_bytes());
        } else {
            out.push(3);
            for &i in t {
                word(&mut out, i);
            }
        }
    }
    out
}

/// The mesh's geometry as one glTF buffer: positions (`VEC3` floats), then indices (`u32`).
fn gltf_buffer(mesh: &Mesh) -> Vec<u8> {
    let mut bin = Vec::with_capacity(12 * (mesh.positions().len() + mesh.indices().len()));
    for p in mesh.positions() {
        for c in p.to_array() {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in mesh.indices() {
        for &i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    bin
}

/// The glTF JSON for the mesh, its buffer given by `uri` (`None` for a GLB's binary chunk).
fn gltf_json(mesh: &Mesh, uri: Option<&str>, byte_length: usize) -> String {
    let b = mesh.bounds();
    let (vertices, triangles) = (mesh.positions().len(), mesh.indices().len());
    let uri = uri.map_or(String::new(), |u| format!(r#","uri":"{u}""#));
    format!(
        r#"{{"asset":{{"version":"2.0","generator":"rt-core"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],"buffers":[{{"byteLength":{byte_length}{uri}}}],"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pl}}},{{"buffer":0,"byteOffset":{pl},"byteLength":{il}}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":{vertices},"type":"VEC3","min":[{:?},{:?},{:?}],"max":[{:?},{:?},{:?}]}},{{"bufferView":1,"componentType":5125,"count":{ic},"type":"SCALAR"}}]}}"#,
        b.min.x,
        b.min.y,
        b.min.z,
        b.max.x,
        b.max.y,
        b.max.z,
        pl = 12 * vertices,
        il = 12 * triangles,
        ic = 3 * triangles,
    )
}

#[cfg(feature = "gltf")]
/// The mesh as a `.gltf` file with its buffer embedded as a base64 data URI.
pub fn gltf_embedded(mesh: &Mesh) -> String {
    use base64::Engine;
    let bin = gltf_buffer(mesh);
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    gltf_json(mesh, Some(&uri), bin.len())
}

/// The mesh as a `.gltf` file whose buffer is the external file `bin_name` (returned second,
/// to be written beside it).
pub fn gltf_external(mesh: &Mesh, bin_name: &str) -> (String, Vec<u8>) {
    let bin = gltf_buffer(mesh);
    (gltf_json(mesh, Some(bin_name), bin.len()), bin)
}

/// The mesh as a `.glb` file: the JSON chunk, then the binary chunk.
pub fn glb_bytes(mesh: &Mesh) -> Vec<u8> {
    let mut bin = gltf_buffer(mesh);
    let mut json = gltf_json(mesh, None, bin.len()).into_bytes();
    // Chunks are 4-byte aligned: JSON padded with spaces, binary with zeros.
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

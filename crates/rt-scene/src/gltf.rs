//! Loading glTF 2.0 files (`.gltf` and `.glb`) into a [`Mesh`].
//!
//! The `gltf` crate parses and validates the document (JSON or the binary container); the
//! buffers and accessors are read here, with every offset, stride and count checked against
//! the bytes that are really there, since a broken file may declare anything. A `.gltf` file's
//! buffers may be external files (beside it) or embedded as base64 data URIs; a `.glb` file's
//! first buffer may be its binary chunk.
//!
//! The mesh is every mesh primitive in triangle, triangle-strip or triangle-fan mode, reached
//! from the nodes of the default scene (or the first scene, or every root node if the file has
//! no scene), with the nodes' transforms applied. Points and lines are skipped. Positions must be
//! 32-bit floats, as the glTF specification requires; indices 8, 16 or 32-bit unsigned integers.
//! Sparse accessors (used for morph targets, not for base geometry) are not read.

use crate::error::{LoadErrorKind, LoadResult, Located};
use base64::Engine;
use glam::{Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::buffer::Source;
use gltf::mesh::Mode;
use rt_core::Mesh;
use std::borrow::Cow;
use std::path::Path;

/// The deepest node hierarchy read; deeper is taken for a broken file.
const MAX_NODE_DEPTH: usize = 1024;

/// Parses a glTF or GLB file's bytes; external buffers are read from `folder` (none when
/// loading from memory).
pub(crate) fn parse_gltf(bytes: &[u8], folder: Option<&Path>) -> LoadResult<Mesh> {
    let doc = document(bytes)?;
    let buffers = doc
        .buffers()
        .map(|b| {
            let at = |kind| Located::element(format!("buffer {}", b.index()), kind);
            let data: Cow<'_, [u8]> = match b.source() {
                Source::Bin => Cow::Borrowed(doc.blob.as_deref().ok_or_else(|| {
                    at(LoadErrorKind::Invalid(
                        "the GLB file has no binary chunk".into(),
                    ))
                })?),
                Source::Uri(uri) => Cow::Owned(fetch(uri, folder).map_err(at)?),
            };
            if data.len() < b.length() {
                return Err(at(LoadErrorKind::Invalid(format!(
                    "holds {} bytes but declares {}",
                    data.len(),
                    b.length()
                ))));
            }
            Ok(data)
        })
        .collect::<LoadResult<Vec<_>>>()?;

    // The nodes to start from, with their transforms from the root.
    let roots: Vec<gltf::Node<'_>> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !child[n.index()]).collect()
        }
    };
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let mut stack: Vec<(gltf::Node<'_>, Mat4, usize)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    // A valid file's nodes form trees, so no node is visited twice; a broken one may share
    // children or loop, which this bound turns into an error instead of endless work.
    let mut visits = 0;
    let hierarchy_error = || {
        Located::none(LoadErrorKind::Invalid(
            "the node hierarchy is not a tree (a node has two parents, or nodes form a cycle)"
                .into(),
        ))
    };
    while let Some((node, parent, depth)) = stack.pop() {
        visits += 1;
        if visits > doc.nodes().len() || depth > MAX_NODE_DEPTH {
            return Err(hierarchy_error());
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let element = || format!("mesh {} primitive {}", mesh.index(), prim.index());
                read_primitive(&prim, &buffers, world, &mut positions, &mut indices)
                    .map_err(|kind| Located::element(element(), kind))?;
            }
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    if indices.is_empty() {
        return Err(Located::none(LoadErrorKind::NoTriangles));
    }
    Mesh::new(positions, indices).map_err(|e| Located::none(LoadErrorKind::Invalid(e.to_string())))
}

/// The parsed and validated document.
///
/// `gltf` 1.4's validation indexes a primitive's POSITION accessor before checking that it
/// exists, and panics on a file that names a missing one (found by the `load_gltf` fuzz target),
/// so that reference is checked here first. The validation also runs under `catch_unwind`, as a
/// last safety net for any other check it makes out of order.
fn document(bytes: &[u8]) -> LoadResult<gltf::Gltf> {
    let invalid = |e: String| Located::none(LoadErrorKind::Invalid(format!("glTF: {e}")));
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| invalid(e.to_string()))?;
    let json = document.into_json();
    let accessors = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&position)
                && i.value() >= accessors
            {
                return Err(Located::element(
                    format!("mesh {m} primitive {p}"),
                    LoadErrorKind::Invalid(format!(
                        "POSITION names accessor {}, and there are {accessors}",
                        i.value()
                    )),
                ));
            }
        }
    }
    let document = std::panic::catch_unwind(move || gltf::Document::from_json(json))
        .map_err(|_| invalid("the glTF validator panicked".into()))?
        .map_err(|e| invalid(e.to_string()))?;
    Ok(gltf::Gltf { document, blob })
}

/// Appends one primitive's triangles (if it is in a triangle mode), transformed by `world`.
fn read_primitive(
    prim: &gltf::Primitive<'_>,
    buffers: &[Cow<'_, [u8]>],
    world: Mat4,
    positions: &mut Vec<Vec3>,
    indices: &mut Vec<[u32; 3]>,
) -> Result<(), LoadErrorKind> {
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(());
    }
    let Some(acc) = prim.get(&gltf::Semantic::Positions) else {
        return Err(LoadErrorKind::Invalid("no POSITION attribute".into()));
    };
    if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
        return Err(LoadErrorKind::Invalid(
            "POSITION is not a VEC3 of 32-bit floats".into(),
        ));
    }
    let base = positions.len();
    let vertices = acc.count();
    let view = elements(&acc, buffers, 12)?;
    positions.reserve(vertices);
    for e in view {
        let f = |k: usize| f32::from_le_bytes([e[k], e[k + 1], e[k + 2], e[k + 3]]);
        let p = world.transform_point3(Vec3::new(f(0), f(4), f(8)));
        if !p.is_finite() {
            return Err(LoadErrorKind::NonFinite);
        }
        positions.push(p);
    }
    let order: Vec<u32> = match prim.indices() {
        Some(acc) => {
            let size = match (acc.data_type(), acc.dimensions()) {
                (DataType::U8, Dimensions::Scalar) => 1,
                (DataType::U16, Dimensions::Scalar) => 2,
                (DataType::U32, Dimensions::Scalar) => 4,
                _ => {
                    return Err(LoadErrorKind::Invalid(
                        "indices are not unsigned integer scalars".into(),
                    ));
                }
            };
            let mut order = Vec::with_capacity(acc.count());
            for e in elements(&acc, buffers, size)? {
                let i = match size {
                    1 => u32::from(e[0]),
                    2 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                    _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                };
                if i as usize >= vertices {
                    return Err(LoadErrorKind::NoSuchVertex {
                        index: i.into(),
                        vertices,
                    });
                }
                order.push(i);
            }
            order
        }
        None => (0..u32::try_from(vertices).map_err(|_| too_many())?).collect(),
    };
    let base = u32::try_from(base).map_err(|_| too_many())?;
    u32::try_from(positions.len()).map_err(|_| too_many())?;
    let n = order.len();
    let tri = |a: usize, b: usize, c: usize| [order[a] + base, order[b] + base, order[c] + base];
    match mode {
        Mode::Triangles if !n.is_multiple_of(3) => {
            return Err(LoadErrorKind::Invalid(format!(
                "{n} indices in triangle mode, not a multiple of 3"
            )));
        }
        Mode::Triangles => indices.extend((0..n / 3).map(|t| tri(3 * t, 3 * t + 1, 3 * t + 2))),
        // Every other triangle of a strip is flipped back to the strip's winding.
        Mode::TriangleStrip => indices.extend((0..n.saturating_sub(2)).map(|t| {
            if t % 2 == 0 {
                tri(t, t + 1, t + 2)
            } else {
                tri(t + 1, t, t + 2)
            }
        })),
        _ => indices.extend((1..n.saturating_sub(1)).map(|t| tri(0, t, t + 1))),
    }
    Ok(())
}

fn too_many() -> LoadErrorKind {
    LoadErrorKind::Unsupported("more than 2^32 vertices".into())
}

/// The bytes of each of an accessor's elements (`size` bytes each), after checking that the
/// accessor lies inside its buffer view and the view inside its buffer.
fn elements<'a>(
    acc: &gltf::Accessor<'_>,
    buffers: &'a [Cow<'_, [u8]>],
    size: usize,
) -> Result<impl Iterator<Item = &'a [u8]>, LoadErrorKind> {
    let bad = |what: String| LoadErrorKind::Invalid(format!("accessor {}: {what}", acc.index()));
    if acc.sparse().is_some() {
        return Err(LoadErrorKind::Unsupported(format!(
            "accessor {} is sparse",
            acc.index()
        )));
    }
    let Some(view) = acc.view() else {
        return Err(LoadErrorKind::Unsupported(format!(
            "accessor {} has no buffer view",
            acc.index()
        )));
    };
    let buffer = &buffers[view.buffer().index()];
    let data = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| {
            bad(format!(
                "buffer view {} lies outside its buffer",
                view.index()
            ))
        })?;
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(bad(format!(
            "stride {stride} is less than the element size {size}"
        )));
    }
    let count = acc.count();
    let data = match count {
        0 => &data[..0],
        _ => stride
            .checked_mul(count - 1)
            .and_then(|s| s.checked_add(size))
            .and_then(|len| acc.offset().checked_add(len).map(|end| (acc.offset(), end)))
            .and_then(|(start, end)| data.get(start..end))
            .ok_or_else(|| bad(format!("{count} elements do not fit in its buffer view")))?,
    };
    Ok((0..count).map(move |i| &data[i * stride..i * stride + size]))
}

/// The bytes of an external buffer or a data URI.
fn fetch(uri: &str, folder: Option<&Path>) -> Result<Vec<u8>, LoadErrorKind> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((meta, payload)) = rest.split_once(',') else {
            return Err(LoadErrorKind::Invalid("a data URI without a comma".into()));
        };
        if !meta.ends_with(";base64") {
            return Err(LoadErrorKind::Unsupported(
                "a data URI that is not base64".into(),
            ));
        }
        let engine = base64::engine::GeneralPurpose::new(
            &base64::alphabet::STANDARD,
            base64::engine::GeneralPurposeConfig::new()
                .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
        );
        return engine
            .decode(payload)
            .map_err(|e| LoadErrorKind::Invalid(format!("a data URI's base64: {e}")));
    }
    let Some(folder) = folder else {
        return Err(LoadErrorKind::Unsupported(format!(
            "external buffer `{uri}` when loading from memory (there is no folder to read it from)"
        )));
    };
    let path = folder.join(percent_decode(uri));
    std::fs::read(&path).map_err(|e| LoadErrorKind::Io(format!("{}: {e}", path.display())))
}

/// A relative URI reference's path, with `%XX` escapes decoded (glTF writers escape spaces and
/// other characters in file names).
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (
            bytes[i],
            bytes.get(i + 1).and_then(|&b| hex(b)),
            bytes.get(i + 2).and_then(|&b| hex(b)),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

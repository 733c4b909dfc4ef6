//! Loading PLY files (Stanford's polygon format) into a [`Mesh`].
//!
//! The file is parsed by `ply-rs-bw`: ASCII and binary, little and big endian, any property
//! types. Only the `vertex` element's `x`, `y` and `z` and the `face` element's `vertex_indices`
//! (or `vertex_index`) list are kept; other properties (normals, colours, confidence) and
//! other elements are read past. Faces with more than three vertices are triangulated by ear
//! clipping in their plane, as OBJ polygons are.
//!
//! Errors name the file and, for ASCII files, the line; for binary files the element (such as
//! `face 12`), since a binary file has no lines.

use crate::error::{LoadErrorKind, LoadResult, Located};
use crate::polygon::triangulate;
use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Encoding, Property, PropertyAccess, PropertyAccessResult, PropertyType};
use rt_core::Mesh;
use std::io::BufReader;

/// A vertex's position as read; `seen` has bit `a` set once coordinate `a` was read.
#[derive(Default)]
struct Vertex {
    p: [f64; 3],
    seen: u8,
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return PropertyAccessResult::Ignored,
        };
        let Some(v) = scalar(&property) else {
            return PropertyAccessResult::UnsupportedType;
        };
        self.p[axis] = v;
        self.seen |= 1 << axis;
        PropertyAccessResult::Set
    }
}

/// A face's vertex indices as read (signed, so that negative ones can be reported).
#[derive(Default)]
struct Face {
    indices: Vec<i64>,
    seen: bool,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if !is_index_list(name) {
            return PropertyAccessResult::Ignored;
        }
        let list: Option<Vec<i64>> = match property {
            Property::ListChar(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUChar(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListInt(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUInt(v) => Some(v.into_iter().map(i64::from).collect()),
            _ => None,
        };
        match list {
            Some(list) => {
                self.indices = list;
                self.seen = true;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

/// An element the mesh does not need, read past.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

/// Parses a PLY file's bytes.
pub(crate) fn parse_ply(bytes: &[u8]) -> LoadResult<Mesh> {
    let mut reader = Reader::new(BufReader::new(bytes));
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| Located::line(e.line(), LoadErrorKind::Invalid(first_line(&e.to_string()))))?;
    let ascii = header.encoding == Encoding::Ascii;
    let mut vertices: Option<(Vec<Vertex>, usize)> = None;
    let mut faces: Option<(Vec<Face>, usize)> = None;
    for def in header.elements.values() {
        // The line of the element's first entry in an ASCII file (one entry per line): the
        // reader has counted the line it will read next.
        let first = reader.line();
        let err = |e: ply_rs_bw::parser::ParseError| {
            let what = LoadErrorKind::Invalid(first_line(&e.to_string()));
            if ascii {
                Located::line(e.line(), what)
            } else {
                Located::element(format!("{} element", def.name), what)
            }
        };
        match def.name.as_str() {
            "vertex" if vertices.is_none() => {
                for axis in ["x", "y", "z"] {
                    match def.properties.get(axis).map(|p| &p.data_type) {
                        Some(PropertyType::Scalar(_)) => {}
                        _ => {
                            return Err(Located::none(LoadErrorKind::Unsupported(format!(
                                "the vertex element has no scalar `{axis}` property"
                            ))));
                        }
                    }
                }
                let read = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(err)?;
                vertices = Some((read, first));
            }
            "face" if faces.is_none() => {
                let list = def.properties.values().find(|p| {
                    is_index_list(&p.name) && matches!(p.data_type, PropertyType::List(..))
                });
                if list.is_none() {
                    return Err(Located::none(LoadErrorKind::Unsupported(
                        "the face element has no `vertex_indices` list".into(),
                    )));
                }
                let read = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(err)?;
                faces = Some((read, first));
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(err)?;
            }
        }
    }
    let (vertices, first_vertex_line) = vertices.unwrap_or_default();
    let (faces, first_face_line) = faces.unwrap_or_default();
    let at = |element: &str, i: usize, first_line: usize, kind| {
        if ascii {
            Located::line(Some(first_line + i), kind)
        } else {
            Located::element(format!("{element} {i}"), kind)
        }
    };
    let mut positions = Vec::with_capacity(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        let p = Vec3::new(v.p[0] as f32, v.p[1] as f32, v.p[2] as f32);
        if v.seen != 7 || !p.is_finite() {
            return Err(at("vertex", i, first_vertex_line, LoadErrorKind::NonFinite));
        }
        positions.push(p);
    }
    drop(vertices);
    let mut indices = Vec::new();
    let mut face = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        if !f.seen || f.indices.len() < 3 {
            return Err(at(
                "face",
                i,
                first_face_line,
                LoadErrorKind::Invalid("a face needs at least three vertices".into()),
            ));
        }
        face.clear();
        for &index in &f.indices {
            match u32::try_from(index) {
                Ok(k) if (k as usize) < positions.len() => face.push(k),
                _ => {
                    return Err(at(
                        "face",
                        i,
                        first_face_line,
                        LoadErrorKind::NoSuchVertex {
                            index,
                            vertices: positions.len(),
                        },
                    ));
                }
            }
        }
        triangulate(&face, &positions, |[a, b, c]| {
            indices.push([face[a], face[b], face[c]]);
        });
    }
    if indices.is_empty() {
        return Err(Located::none(LoadErrorKind::NoTriangles));
    }
    Mesh::new(positions, indices).map_err(|e| Located::none(LoadErrorKind::Invalid(e.to_string())))
}

/// The first line of a parser's message (ply-rs adds the offending text and a debug dump on
/// further lines), without its `Line N: ` prefix, since [`LoadError`](crate::LoadError) shows
/// the line itself.
fn first_line(message: &str) -> String {
    let first = message.lines().next().unwrap_or(message).trim();
    let rest = first
        .strip_prefix("Line ")
        .and_then(|r| r.split_once(": "))
        .filter(|(n, _)| n.bytes().all(|b| b.is_ascii_digit()))
        .map_or(first, |(_, r)| r);
    rest.to_owned()
}

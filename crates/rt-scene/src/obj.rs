//! Loading Wavefront OBJ files into a [`Mesh`].
//!
//! The geometry is parsed by `tobj`. Before `tobj` sees the text, one pass over the lines checks
//! everything `tobj` would trip on or report without a line number: numbers that do not parse,
//! non-finite coordinates, faces with fewer than three vertices, and vertex, texture and normal
//! indices that are zero or out of range (`tobj` 4.0.5 can panic in debug builds on some of
//! those). Errors therefore name the file and the line. As a last safety net the `tobj` call also
//! runs under `catch_unwind`, so even an unforeseen panic inside it becomes a [`LoadError`].
//!
//! Polygons with more than three vertices are triangulated by ear clipping in the polygon's
//! plane, so concave polygons come out right (a fan would not).

use crate::error::{LoadError, LoadErrorKind, Located};
use crate::polygon::triangulate;
use glam::{Vec2, Vec3};
use rt_core::Mesh;
use std::io::Cursor;
use std::path::Path;

/// Loads the triangles of an OBJ file (all objects and groups merged into one mesh).
///
/// # Errors
/// A [`LoadError`] naming the file, and the line where one is to blame, for a missing or
/// unreadable file, text that is neither UTF-8 nor UTF-16, a malformed line, an index out of
/// range, a non-finite coordinate, or a file without triangles. Never panics.
///
/// ```
/// let err = rt_scene::load_obj("no/such/file.obj").unwrap_err();
/// assert!(err.to_string().starts_with("no/such/file.obj: cannot read file"));
/// ```
pub fn load_obj(path: impl AsRef<Path>) -> Result<Mesh, LoadError> {
    let path = path.as_ref();
    let bytes = crate::error::read(path)?;
    parse_obj(&bytes).map_err(|(line, kind)| Located::line(line, kind).at(path))
}

/// Loads OBJ text from memory; `name` is used in errors in place of a path.
///
/// # Errors
/// As [`load_obj`], except that nothing is read from disk.
pub fn load_obj_bytes(name: &str, bytes: &[u8]) -> Result<Mesh, LoadError> {
    parse_obj(bytes).map_err(|(line, kind)| Located::line(line, kind).at(name))
}

type ParseResult<T> = Result<T, (Option<usize>, LoadErrorKind)>;

pub(crate) fn parse_obj(bytes: &[u8]) -> ParseResult<Mesh> {
    let text = decode(bytes)?;
    let corners_have = validate(&text)?;
    // tobj parses `l` (polyline) elements like faces, so a polyline of three or more points
    // would become a polygon. Lines are not surfaces: blank them (keeping line numbers).
    let text: String = text
        .lines()
        .map(|l| {
            if l.split_whitespace().next() == Some("l") {
                "#"
            } else {
                l
            }
        })
        .flat_map(|l| [l, "\n"])
        .collect();
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let loaded = std::panic::catch_unwind(|| {
        tobj::load_obj_buf(&mut Cursor::new(text.as_bytes()), &options, |_| {
            // Materials are irrelevant to geometry; a missing .mtl file is not an error here.
            Ok(Default::default())
        })
    });
    let models = match loaded {
        Ok(Ok((models, _))) => models,
        Ok(Err(e)) => return Err((None, LoadErrorKind::Parser(e.to_string()))),
        Err(_) => {
            return Err((
                None,
                LoadErrorKind::Parser("the OBJ parser panicked".into()),
            ));
        }
    };

    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let (mut normals, mut normal_indices) = (Vec::new(), Vec::new());
    let (mut uvs, mut uv_indices) = (Vec::new(), Vec::new());
    for model in &models {
        let m = &model.mesh;
        let base = positions.len() as u32;
        positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        // Normals and texture coordinates count only when every face corner of the file names
        // one: where some corners do not, tobj fills in index 0 for them, which would shade
        // those faces with an unrelated normal. Without, shading falls back to the geometric
        // normal and the barycentrics.
        let normal_base = normals.len() as u32;
        let has_normals = corners_have.normals
            && !m.normal_indices.is_empty()
            && m.normal_indices.len() == m.indices.len();
        if has_normals {
            normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        }
        let uv_base = uvs.len() as u32;
        let has_uvs = corners_have.uvs
            && !m.texcoord_indices.is_empty()
            && m.texcoord_indices.len() == m.indices.len();
        if has_uvs {
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        }
        let (local, local_normals, local_uvs) = (
            &positions[base as usize..],
            normals.len() - normal_base as usize,
            uvs.len() - uv_base as usize,
        );
        let arities: Vec<u32> = if m.face_arities.is_empty() {
            vec![3; m.indices.len() / 3]
        } else {
            m.face_arities.clone()
        };
        let mut start = 0usize;
        for arity in arities {
            let range = start..start + arity as usize;
            let Some(face) = m.indices.get(range.clone()) else {
                return Err((
                    None,
                    LoadErrorKind::Parser("face list shorter than its arities".into()),
                ));
            };
            start += arity as usize;
            let out_of = |ids: &[u32], len: usize| ids.iter().any(|&i| i as usize >= len);
            if out_of(face, local.len())
                || (has_normals && out_of(&m.normal_indices[range.clone()], local_normals))
                || (has_uvs && out_of(&m.texcoord_indices[range.clone()], local_uvs))
            {
                return Err((
                    None,
                    LoadErrorKind::Parser("face index outside its object".into()),
                ));
            }
            let corners =
                |list: &[u32], base: u32, c: [usize; 3]| c.map(|k| list[range.start + k] + base);
            triangulate(face, local, |c| {
                indices.push(corners(&m.indices, base, c));
                normal_indices.push(if has_normals {
                    corners(&m.normal_indices, normal_base, c)
                } else {
                    [Mesh::NONE; 3]
                });
                uv_indices.push(if has_uvs {
                    corners(&m.texcoord_indices, uv_base, c)
                } else {
                    [Mesh::NONE; 3]
                });
            });
        }
    }
    if indices.is_empty() {
        return Err((None, LoadErrorKind::NoTriangles));
    }
    let parser = |e: rt_core::MeshError| (None, LoadErrorKind::Parser(e.to_string()));
    let mut mesh = Mesh::new(positions, indices).map_err(parser)?;
    if !normals.is_empty() {
        mesh = mesh.with_normals(normals, normal_indices).map_err(parser)?;
    }
    if !uvs.is_empty() {
        mesh = mesh.with_uvs(uvs, uv_indices).map_err(parser)?;
    }
    Ok(mesh)
}

/// UTF-8 (with or without a byte-order mark), or UTF-16 of either byte order with a mark.
fn decode(bytes: &[u8]) -> ParseResult<String> {
    let utf16 = |be: bool| {
        let units = bytes[2..]
            .chunks(2)
            .map(|c| {
                if c.len() == 2 {
                    Ok([c[0], c[1]])
                } else {
                    Err((None, LoadErrorKind::Encoding))
                }
            })
            .map(|c| {
                c.map(|c| {
                    if be {
                        u16::from_be_bytes(c)
                    } else {
                        u16::from_le_bytes(c)
                    }
                })
            })
            .collect::<Result<Vec<u16>, _>>()?;
        String::from_utf16(&units).map_err(|_| (None, LoadErrorKind::Encoding))
    };
    match bytes {
        [0xFE, 0xFF, ..] => utf16(true),
        [0xFF, 0xFE, ..] => utf16(false),
        [0xEF, 0xBB, 0xBF, rest @ ..] => utf8(rest),
        _ => utf8(bytes),
    }
}

fn utf8(bytes: &[u8]) -> ParseResult<String> {
    String::from_utf8(bytes.to_vec()).map_err(|e| {
        let line = 1 + bytes[..e.utf8_error().valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        (Some(line), LoadErrorKind::Encoding)
    })
}

/// Whether every face corner of a file names a texture coordinate, and a normal.
#[derive(Clone, Copy, Debug)]
struct Corners {
    uvs: bool,
    normals: bool,
}

/// The validation pass: finds, with its line number, everything the parser would reject or
/// mishandle. Mirrors the OBJ rules `tobj` applies: `v` needs three numbers, `vt` two, `vn`
/// three; face indices are 1-based or negative (relative to the elements defined so far).
fn validate(text: &str) -> ParseResult<Corners> {
    let mut counts = [0usize; 3]; // vertices, texture coordinates, normals
    let mut corners_have = Corners {
        uvs: true,
        normals: true,
    };
    for (n, line) in text.lines().enumerate() {
        let line_no = Some(n + 1);
        let err = |kind| Err((line_no, kind));
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let numbers = |need: usize, what: &str| -> ParseResult<Vec<f32>> {
            let vals = words
                .clone()
                .take(need)
                .map(|w| w.parse::<f32>().map_err(|_| w))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|w| {
                    (
                        line_no,
                        LoadErrorKind::Malformed(format!("`{w}` is not a number")),
                    )
                })?;
            if vals.len() < need {
                return Err((
                    line_no,
                    LoadErrorKind::Malformed(format!(
                        "{what} needs {need} numbers, found {}",
                        vals.len()
                    )),
                ));
            }
            Ok(vals)
        };
        match keyword {
            "v" => {
                if numbers(3, "a vertex")?.iter().any(|x| !x.is_finite()) {
                    return err(LoadErrorKind::NonFinite);
                }
                counts[0] += 1;
            }
            "vt" => {
                numbers(2, "a texture coordinate")?;
                counts[1] += 1;
            }
            "vn" => {
                numbers(3, "a normal")?;
                counts[2] += 1;
            }
            "f" => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return err(LoadErrorKind::Malformed(format!(
                        "a face needs at least 3 vertices, found {}",
                        corners.len()
                    )));
                }
                for corner in corners {
                    let parts: Vec<&str> = corner.split('/').collect();
                    corners_have.uvs &= parts.get(1).is_some_and(|p| !p.is_empty());
                    corners_have.normals &= parts.get(2).is_some_and(|p| !p.is_empty());
                    if parts.len() > 3 || parts[0].is_empty() {
                        return err(LoadErrorKind::Malformed(format!(
                            "bad face vertex `{corner}`"
                        )));
                    }
                    const ELEMENTS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
                    for (k, part) in parts.iter().enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let Ok(index) = part.parse::<i64>() else {
                            return err(LoadErrorKind::Malformed(format!(
                                "bad face vertex `{corner}`"
                            )));
                        };
                        let defined = counts[k];
                        let ok = if index > 0 {
                            index as u64 <= defined as u64
                        } else {
                            index < 0 && index.unsigned_abs() <= defined as u64
                        };
                        if !ok {
                            return err(LoadErrorKind::IndexOutOfRange {
                                element: ELEMENTS[k],
                                index,
                                defined,
                            });
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(corners_have)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::Triangle;

    fn load(text: &str) -> Result<Mesh, LoadError> {
        load_obj_bytes("test.obj", text.as_bytes())
    }

    #[test]
    fn loads_triangles_and_quads() {
        let m = load("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 2 3 4\n").unwrap();
        assert_eq!(m.triangle_count(), 3);
        assert_eq!(m.positions().len(), 4);
    }

    #[test]
    fn negative_indices_and_slashes() {
        let m =
            load("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf -3/1/1 -2//1 -1/-1/-1\n").unwrap();
        assert_eq!(m.triangle(0), Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y));
    }

    #[test]
    fn keeps_normals_and_texture_coordinates() {
        // A quad with its own normal and texture-coordinate numbering, in two objects.
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 2\nvn 0 1 0\n\
                    f 1/1/1 2/2/1 3/3/2 4/4/2\no other\nv 5 0 0\nv 6 0 0\nv 5 1 0\n\
                    f 5/1/1 6/2/1 7/4/1\n";
        let m = load(text).unwrap();
        assert_eq!(m.triangle_count(), 3);
        assert_eq!(m.uvs().len(), 4 + 3);
        assert_eq!(m.shading(2, 0.5, 0.25).normal, Vec3::Z);
        assert_eq!(m.shading(2, 0.0, 1.0).uv, Vec2::new(0.0, 1.0));
        // One face without normals or texture coordinates: the file has none (tobj would give
        // that face an unrelated one), and shading uses the geometric normal.
        let m = load(&format!("{text}f 5 6 7\n")).unwrap();
        assert!(m.normal_indices().is_none() && m.uv_indices().is_none());
        assert_eq!(m.shading(0, 0.25, 0.25).normal, Vec3::Z);
        let m = load(text).unwrap();
        for i in 0..2 {
            // Texture coordinates follow the positions here, so they interpolate to the point.
            let s = m.shading(i, 0.25, 0.25);
            assert!(s.uv.distance(s.surface.point.truncate()) < 1e-6, "{s:?}");
            assert!(s.normal.is_normalized());
        }
        // At the corner where vertex 3 (normal 2, +y) sits, the shading normal is +y.
        let corner = (0..2)
            .flat_map(|i| [(i, 1.0, 0.0), (i, 0.0, 1.0), (i, 0.0, 0.0)])
            .map(|(i, u, v)| m.shading(i, u, v))
            .find(|s| s.surface.point == Vec3::new(1.0, 1.0, 0.0))
            .unwrap();
        assert_eq!(corner.normal, Vec3::Y);
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err();
        assert_eq!(e.line, Some(4));
        assert_eq!(
            e.kind,
            LoadErrorKind::IndexOutOfRange {
                element: "vertex",
                index: 4,
                defined: 3
            }
        );
        assert_eq!(
            e.to_string(),
            "test.obj:4: vertex index 4 out of range (3 defined before this line)"
        );

        let e = load("v 0 0 0\nv 1 0 zero\n").unwrap_err();
        assert_eq!(
            (e.line, e.to_string().contains("`zero` is not a number")),
            (Some(2), true)
        );

        let e = load("v 0 0 0\nv 1 0 NaN\n").unwrap_err();
        assert_eq!((e.line, e.kind), (Some(2), LoadErrorKind::NonFinite));

        let e = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap_err();
        assert_eq!(e.line, Some(4));

        let e = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1\n").unwrap_err();
        assert!(matches!(
            e.kind,
            LoadErrorKind::IndexOutOfRange {
                element: "texture coordinate",
                ..
            }
        ));

        let e = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -3/1/-7\n").unwrap_err();
        assert_eq!(e.line, Some(4));

        let e = load("v 0 0 0\nf\n").unwrap_err();
        assert_eq!(e.line, Some(2));

        let e =
            load("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nl 1 2\nl 1 2 3 4\np 1 2 3\n").unwrap_err();
        assert_eq!((e.line, e.kind), (None, LoadErrorKind::NoTriangles));

        let e = load("").unwrap_err();
        assert_eq!(e.kind, LoadErrorKind::NoTriangles);

        let e = load_obj_bytes("x.obj", b"v 0 0 0\n\xff\xfe\xfd\n").unwrap_err();
        assert_eq!((e.line, e.kind), (Some(2), LoadErrorKind::Encoding));
    }

    #[test]
    fn utf16_with_bom_is_decoded() {
        let text = "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n";
        let mut be = vec![0xFE, 0xFF];
        let mut le = vec![0xFF, 0xFE];
        for u in text.encode_utf16() {
            be.extend(u.to_be_bytes());
            le.extend(u.to_le_bytes());
        }
        assert_eq!(load_obj_bytes("be", &be).unwrap().triangle_count(), 1);
        assert_eq!(load_obj_bytes("le", &le).unwrap().triangle_count(), 1);
    }

    #[test]
    fn concave_polygon_is_ear_clipped() {
        // An L-shaped hexagon: a fan from corner 0 would put a triangle outside the L.
        let text = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n";
        let m = load(text).unwrap();
        assert_eq!(m.triangle_count(), 4);
        let area: f32 = m
            .triangles()
            .iter()
            .map(|t| t.normal().length() * 0.5)
            .sum();
        assert!((area - 3.0).abs() < 1e-6, "area {area}");
        // Every triangle's centroid lies inside the L (not in the missing square [1,2]x[1,2]).
        for t in m.triangles() {
            let c = (t.v0 + t.v1 + t.v2) / 3.0;
            assert!(
                !(c.x > 1.0 && c.y > 1.0),
                "triangle outside the polygon: {t:?}"
            );
        }
    }

    #[test]
    fn degenerate_polygon_does_not_loop() {
        let mut text = String::from("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf");
        for _ in 0..300 {
            text.push_str(" 1 2 3 4");
        }
        text.push('\n');
        assert_eq!(load(&text).unwrap().triangle_count(), 1198);
    }
}

#[cfg(test)]
mod fuzz {
    use super::*;
    use proptest::prelude::*;

    /// OBJ-ish lines: valid and broken vertices and faces, other keywords, junk.
    fn line() -> impl Strategy<Value = String> {
        let num = prop_oneof![
            (-1000i32..1000).prop_map(|i| (i as f32 / 7.0).to_string()),
            Just("nan".to_string()),
            Just("inf".to_string()),
            Just("1e40".to_string()),
            Just("3.1+e2".to_string()),
            "[a-z0-9.+-]{0,4}",
        ];
        let index = prop_oneof![(-12i64..12).prop_map(|i| i.to_string()), "[0-9/-]{0,6}"];
        prop_oneof![
            prop::collection::vec(num, 0..5).prop_map(|v| format!("v {}", v.join(" "))),
            prop::collection::vec(index.clone(), 0..8).prop_map(|v| format!("f {}", v.join(" "))),
            prop::collection::vec(index, 0..5).prop_map(|v| format!("l {}", v.join(" "))),
            Just("vt 0 0".to_string()),
            Just("vn 0 0 1".to_string()),
            Just("o thing".to_string()),
            Just("usemtl missing".to_string()),
            "\\PC{0,20}",
        ]
    }

    proptest! {
        /// Whatever the text, loading returns a mesh whose indices are all in range, or an
        /// error; it never panics.
        #[test]
        fn never_panics(lines in prop::collection::vec(line(), 0..30)) {
            match load_obj_bytes("fuzz.obj", lines.join("\n").as_bytes()) {
                Ok(mesh) => {
                    prop_assert!(mesh.triangle_count() > 0);
                    let n = mesh.positions().len() as u32;
                    prop_assert!(mesh.indices().iter().flatten().all(|&i| i < n));
                }
                Err(e) => prop_assert!(!e.to_string().is_empty()),
            }
        }

        /// Arbitrary bytes, too.
        #[test]
        fn never_panics_on_bytes(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
            let _ = load_obj_bytes("bytes.obj", &bytes);
        }
    }
}

//! Indexed triangle meshes.

use crate::{Aabb, SurfacePoint, Triangle};
use glam::{Vec2, Vec3};
use std::fmt;

/// A triangle mesh with shared vertices: a position buffer and a buffer of index triples, and
/// optionally per-vertex normals and texture coordinates with their own index triples (as OBJ
/// files give them, where a corner's position, normal and texture coordinate are numbered apart).
///
/// The buffers are plain `Pod` data (`bytemuck::cast_slice` views them as bytes or `f32`s). Every
/// index is checked on construction, so turning the mesh into triangles, or asking for the
/// [`Shading`] of a hit, never fails for a triangle of the mesh.
///
/// ```
/// use rt_core::{Accel, BruteForce, Mesh, Ray, glam::{Vec2, Vec3}};
/// let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])
///     .unwrap()
///     .with_normals(vec![Vec3::Z, Vec3::new(0.0, 0.6, 0.8)], vec![[0, 0, 1]])
///     .unwrap()
///     .with_uvs(vec![Vec2::ZERO, Vec2::X, Vec2::Y], vec![[0, 1, 2]])
///     .unwrap();
/// let accel = BruteForce::build(&mesh.triangles(), &Default::default());
/// let hit = accel.intersect(&Ray::new(Vec3::new(0.25, 0.5, 1.0), -Vec3::Z)).unwrap();
/// let shading = mesh.shading(hit.prim as usize, hit.u, hit.v);
/// assert_eq!(shading.surface.point, Vec3::new(0.25, 0.5, 0.0));
/// assert_eq!(shading.surface.normal, Vec3::Z); // geometric, from the winding
/// assert!(shading.normal.y > 0.0); // interpolated towards the third vertex's normal
/// assert_eq!(shading.uv, Vec2::new(0.25, 0.5));
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
    normals: Vec<Vec3>,
    /// Empty, or one triple per triangle ([`Mesh::NONE`] where a triangle has no normals).
    normal_indices: Vec<[u32; 3]>,
    uvs: Vec<Vec2>,
    /// Empty, or one triple per triangle ([`Mesh::NONE`] where a triangle has no coordinates).
    uv_indices: Vec<[u32; 3]>,
}

/// An inconsistent mesh: an index past the end of its buffer, or a per-triangle attribute list
/// of the wrong length.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MeshError {
    /// A triangle refers to an element that does not exist.
    IndexOutOfRange {
        /// `"vertex"`, `"normal"` or `"texture coordinate"`.
        attribute: &'static str,
        /// Which triangle.
        triangle: usize,
        /// The offending index.
        index: u32,
        /// How many such elements there are.
        len: usize,
    },
    /// A flat buffer ([`IndexedTriangles::from_flat`](crate::IndexedTriangles::from_flat))
    /// whose length is not a multiple of three.
    Ragged {
        /// `"position"` or `"index"`.
        buffer: &'static str,
        /// Its length.
        len: usize,
    },
    /// Normal or texture-coordinate index triples do not number one per triangle.
    CountMismatch {
        /// `"normal"` or `"texture coordinate"`.
        attribute: &'static str,
        /// Triangles in the mesh.
        triangles: usize,
        /// Index triples given.
        found: usize,
    },
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let plural = |a: &str| match a {
            "vertex" => "vertices".to_string(),
            a => format!("{a}s"),
        };
        match self {
            MeshError::IndexOutOfRange {
                attribute,
                triangle,
                index,
                len,
            } => write!(
                f,
                "triangle {triangle} uses {attribute} index {index} but the mesh has {len} {}",
                plural(attribute)
            ),
            MeshError::Ragged { buffer, len } => write!(
                f,
                "the flat {buffer} buffer holds {len} numbers, not a multiple of three"
            ),
            MeshError::CountMismatch {
                attribute,
                triangles,
                found,
            } => write!(
                f,
                "{found} {attribute} index triples for {triangles} triangles (need one per triangle)"
            ),
        }
    }
}

impl std::error::Error for MeshError {}

/// What a renderer needs to shade a hit on a mesh triangle: the surface point (with the
/// geometric normal and the error bound that [`SurfacePoint::spawn_ray`] uses), the shading
/// normal and the texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// The point, the unit geometric normal (by the triangle's winding) and its error bound.
    pub surface: SurfacePoint,
    /// The unit shading normal: the vertex normals interpolated with the hit's barycentrics
    /// where the triangle has them, the geometric normal otherwise (and where the interpolated
    /// normal is zero or not finite).
    pub normal: Vec3,
    /// The texture coordinates interpolated with the barycentrics where the triangle has them,
    /// the barycentrics `(u, v)` themselves otherwise.
    pub uv: Vec2,
}

fn check(
    attribute: &'static str,
    len: usize,
    indices: &[[u32; 3]],
    triangles: Option<usize>,
    allow_none: bool,
) -> Result<(), MeshError> {
    if let Some(triangles) = triangles
        && indices.len() != triangles
    {
        return Err(MeshError::CountMismatch {
            attribute,
            triangles,
            found: indices.len(),
        });
    }
    for (triangle, tri) in indices.iter().enumerate() {
        if allow_none && *tri == [Mesh::NONE; 3] {
            continue;
        }
        for &index in tri {
            if index as usize >= len {
                return Err(MeshError::IndexOutOfRange {
                    attribute,
                    triangle,
                    index,
                    len,
                });
            }
        }
    }
    Ok(())
}

/// Checks position index triples against `len` vertices.
pub(crate) fn check_indices(len: usize, indices: &[[u32; 3]]) -> Result<(), MeshError> {
    check("vertex", len, indices, None, false)
}

impl Mesh {
    /// The index triple of a triangle without normals or texture coordinates, in
    /// [`Mesh::with_normals`] and [`Mesh::with_uvs`].
    pub const NONE: u32 = u32::MAX;

    /// A mesh from positions and index triples.
    ///
    /// # Errors
    /// [`MeshError::IndexOutOfRange`] if any index is not below `positions.len()`.
    pub fn new(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        check("vertex", positions.len(), &indices, None, false)?;
        Ok(Self {
            positions,
            indices,
            ..Self::default()
        })
    }

    /// The mesh with per-vertex normals: `normals` and one index triple into them per triangle
    /// (`[Mesh::NONE; 3]` for a triangle without normals). They need not be unit length.
    ///
    /// # Errors
    /// [`MeshError`] if the triples are not one per triangle or an index is out of range.
    pub fn with_normals(
        mut self,
        normals: Vec<Vec3>,
        indices: Vec<[u32; 3]>,
    ) -> Result<Self, MeshError> {
        check(
            "normal",
            normals.len(),
            &indices,
            Some(self.indices.len()),
            true,
        )?;
        self.normals = normals;
        self.normal_indices = indices;
        Ok(self)
    }

    /// The mesh with texture coordinates: `uvs` and one index triple into them per triangle
    /// (`[Mesh::NONE; 3]` for a triangle without).
    ///
    /// # Errors
    /// [`MeshError`] if the triples are not one per triangle or an index is out of range.
    pub fn with_uvs(mut self, uvs: Vec<Vec2>, indices: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        check(
            "texture coordinate",
            uvs.len(),
            &indices,
            Some(self.indices.len()),
            true,
        )?;
        self.uvs = uvs;
        self.uv_indices = indices;
        Ok(self)
    }

    /// The box `[lo, hi]` as a closed mesh of eight corners and twelve triangles facing
    /// outwards, each face split along the diagonal from its lowest corner.
    ///
    /// ```
    /// use rt_core::{Mesh, glam::Vec3};
    /// let cube = Mesh::cuboid(Vec3::ZERO, Vec3::ONE);
    /// assert_eq!((cube.positions().len(), cube.triangle_count()), (8, 12));
    /// // Facing outwards: the bottom face's normal points down.
    /// assert!(cube.triangle(0).normal().z < 0.0);
    /// ```
    pub fn cuboid(lo: Vec3, hi: Vec3) -> Self {
        let positions = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        // Each face as its four corners, counter-clockwise seen from outside.
        let faces: [[u32; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let indices = faces
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        Self {
            positions,
            indices,
            ..Self::default()
        }
    }

    /// A mesh that shares no vertices: three positions per triangle.
    pub fn from_triangles(tris: &[Triangle]) -> Self {
        let positions = tris.iter().flat_map(|t| [t.v0, t.v1, t.v2]).collect();
        let indices = (0..tris.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        Self {
            positions,
            indices,
            ..Self::default()
        }
    }

    /// The vertex positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The index triples, one per triangle.
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// The per-vertex normals (empty if the mesh has none).
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    /// One index triple into [`normals`](Mesh::normals) per triangle, `[Mesh::NONE; 3]` for a
    /// triangle without; `None` if no triangle has normals.
    pub fn normal_indices(&self) -> Option<&[[u32; 3]]> {
        (!self.normal_indices.is_empty()).then_some(&self.normal_indices[..])
    }

    /// The texture coordinates (empty if the mesh has none).
    pub fn uvs(&self) -> &[Vec2] {
        &self.uvs
    }

    /// One index triple into [`uvs`](Mesh::uvs) per triangle, `[Mesh::NONE; 3]` for a triangle
    /// without; `None` if no triangle has texture coordinates.
    pub fn uv_indices(&self) -> Option<&[[u32; 3]]> {
        (!self.uv_indices.is_empty()).then_some(&self.uv_indices[..])
    }

    /// The shading data of a hit on triangle `i` at barycentrics `u` (weight of the second
    /// vertex) and `v` (of the third), as a [`Hit`](crate::Hit) from a structure built over
    /// [`Mesh::triangles`] reports them.
    ///
    /// # Panics
    /// If `i >= self.triangle_count()`.
    pub fn shading(&self, i: usize, u: f32, v: f32) -> Shading {
        let surface = self.triangle(i).surface_at(u, v);
        let w = 1.0 - u - v;
        let normal = match self.normal_indices.get(i) {
            Some(&[a, b, c]) if a != Self::NONE => {
                let n = &self.normals;
                (w * n[a as usize] + u * n[b as usize] + v * n[c as usize])
                    .try_normalize()
                    .unwrap_or(surface.normal)
            }
            _ => surface.normal,
        };
        let uv = match self.uv_indices.get(i) {
            Some(&[a, b, c]) if a != Self::NONE => {
                let t = &self.uvs;
                w * t[a as usize] + u * t[b as usize] + v * t[c as usize]
            }
            _ => Vec2::new(u, v),
        };
        Shading {
            surface,
            normal,
            uv,
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The triangle at index `i`.
    ///
    /// # Panics
    /// If `i >= self.triangle_count()`.
    pub fn triangle(&self, i: usize) -> Triangle {
        let [a, b, c] = self.indices[i];
        Triangle::new(
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        )
    }

    /// Every triangle, in index order (triangle `i` of the mesh is primitive `i` of a structure
    /// built from this vector).
    pub fn triangles(&self) -> Vec<Triangle> {
        (0..self.indices.len()).map(|i| self.triangle(i)).collect()
    }

    /// The box around every referenced vertex with finite coordinates.
    pub fn bounds(&self) -> Aabb {
        self.indices
            .iter()
            .flatten()
            .map(|&i| self.positions[i as usize])
            .filter(|p| p.is_finite())
            .fold(Aabb::EMPTY, Aabb::grow)
    }

    /// Appends another mesh (its normals and texture coordinates too; triangles of the mesh
    /// that has none get [`Mesh::NONE`]).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        let (own, theirs) = (self.indices.len(), other.indices.len());
        self.positions.extend_from_slice(&other.positions);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|i| i + base)));
        fn merge<T: Copy>(
            items: &mut Vec<T>,
            indices: &mut Vec<[u32; 3]>,
            own: usize,
            other_items: &[T],
            other_indices: &[[u32; 3]],
            theirs: usize,
        ) {
            if indices.is_empty() && other_indices.is_empty() {
                return;
            }
            indices.resize(own, [Mesh::NONE; 3]);
            let base = items.len() as u32;
            items.extend_from_slice(other_items);
            if other_indices.is_empty() {
                indices.resize(own + theirs, [Mesh::NONE; 3]);
            } else {
                indices.extend(other_indices.iter().map(|t| {
                    if *t == [Mesh::NONE; 3] {
                        *t
                    } else {
                        t.map(|i| i + base)
                    }
                }));
            }
        }
        merge(
            &mut self.normals,
            &mut self.normal_indices,
            own,
            &other.normals,
            &other.normal_indices,
            theirs,
        );
        merge(
            &mut self.uvs,
            &mut self.uv_indices,
            own,
            &other.uvs,
            &other.uv_indices,
            theirs,
        );
    }

    /// The mesh with smooth per-vertex normals computed from its geometry, replacing any it
    /// had: each vertex gets the sum of the normals of the triangles around it, weighted by
    /// their area (the unnormalized cross product), so that shading varies smoothly across a
    /// tessellated curved surface. Vertices only on degenerate triangles get no usable normal,
    /// and shading falls back to the geometric one there.
    pub fn with_smooth_normals(mut self) -> Self {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for i in 0..self.indices.len() {
            let n = self.triangle(i).normal();
            if n.is_finite() {
                for &v in &self.indices[i] {
                    normals[v as usize] += n;
                }
            }
        }
        self.normal_indices = self.indices.clone();
        self.normals = normals;
        self
    }

    /// The mesh scaled about the origin: every position multiplied by `factor` (normals,
    /// directions only, are unchanged for a positive factor).
    pub fn scaled(mut self, factor: f32) -> Self {
        for p in &mut self.positions {
            *p *= factor;
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_out_of_range_indices() {
        let err = Mesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 3]]).unwrap_err();
        assert!(matches!(err, MeshError::IndexOutOfRange { index: 3, .. }));
        assert!(err.to_string().contains("has 3 vertices"));
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        let err = mesh
            .clone()
            .with_normals(vec![Vec3::Z], vec![[0, 0, 1]])
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "triangle 0 uses normal index 1 but the mesh has 1 normals"
        );
        let err = mesh.with_uvs(vec![Vec2::ZERO], vec![]).unwrap_err();
        assert!(matches!(
            err,
            MeshError::CountMismatch {
                found: 0,
                triangles: 1,
                ..
            }
        ));
    }

    #[test]
    fn round_trips_triangles() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let mut m = Mesh::from_triangles(&[t]);
        m.append(&Mesh::from_triangles(&[t]));
        assert_eq!(m.triangles(), vec![t, t]);
        assert_eq!(m.bounds(), Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
    }

    #[test]
    fn smooth_normals_average_the_faces_around_a_vertex() {
        // Two triangles folded along the x axis at a right angle: the shared edge's vertices get
        // the diagonal, the others their own face's normal.
        let m = Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Z, -Vec3::Y],
            vec![[0, 1, 2], [0, 1, 3]],
        )
        .unwrap()
        .with_smooth_normals();
        let diagonal = Vec3::new(0.0, -1.0, -1.0).normalize();
        assert!(m.shading(0, 0.0, 0.0).normal.distance(diagonal) < 1e-6);
        assert!(m.shading(0, 0.0, 1.0).normal.distance(-Vec3::Y) < 1e-6);
        assert!(m.shading(1, 0.0, 0.999).normal.distance(-Vec3::Z) < 1e-2);
    }

    #[test]
    fn append_keeps_attributes_aligned() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let plain = Mesh::from_triangles(&[t]);
        let smooth = Mesh::from_triangles(&[t])
            .with_normals(vec![Vec3::Z, -Vec3::Z], vec![[1, 1, 1]])
            .unwrap();
        let mut m = plain.clone();
        m.append(&smooth);
        m.append(&plain);
        assert_eq!(
            m.normal_indices().unwrap(),
            &[[Mesh::NONE; 3], [1, 1, 1], [Mesh::NONE; 3]]
        );
        assert_eq!(m.shading(0, 0.2, 0.2).normal, Vec3::Z); // geometric
        assert_eq!(m.shading(1, 0.2, 0.2).normal, -Vec3::Z); // its own normals
        assert_eq!(m.shading(2, 0.3, 0.1).uv, Vec2::new(0.3, 0.1));
        assert!(m.uv_indices().is_none());
    }
}

//! Indexed triangle meshes.

use crate::{Aabb, Triangle};
use glam::Vec3;
use std::fmt;

/// A triangle mesh with shared vertices: a position buffer and a buffer of index triples.
///
/// Both buffers are plain `Pod` data (`bytemuck::cast_slice` views them as bytes or `f32`s). Every
/// index is checked against the position buffer on construction, so turning the mesh into
/// triangles can never fail.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
}

/// A triangle index that points past the end of the position buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IndexOutOfRange {
    /// Which triangle.
    pub triangle: usize,
    /// The offending index.
    pub index: u32,
    /// How many positions there are.
    pub positions: usize,
}

impl fmt::Display for IndexOutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "triangle {} uses vertex index {} but the mesh has {} vertices",
            self.triangle, self.index, self.positions
        )
    }
}

impl std::error::Error for IndexOutOfRange {}

impl Mesh {
    /// A mesh from positions and index triples.
    ///
    /// # Errors
    /// [`IndexOutOfRange`] if any index is not below `positions.len()`.
    pub fn new(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Result<Self, IndexOutOfRange> {
        for (triangle, tri) in indices.iter().enumerate() {
            for &index in tri {
                if index as usize >= positions.len() {
                    return Err(IndexOutOfRange {
                        triangle,
                        index,
                        positions: positions.len(),
                    });
                }
            }
        }
        Ok(Self { positions, indices })
    }

    /// A mesh that shares no vertices: three positions per triangle.
    pub fn from_triangles(tris: &[Triangle]) -> Self {
        let positions = tris.iter().flat_map(|t| [t.v0, t.v1, t.v2]).collect();
        let indices = (0..tris.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        Self { positions, indices }
    }

    /// The vertex positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The index triples, one per triangle.
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
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

    /// Appends another mesh.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|i| i + base)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_out_of_range_indices() {
        let err = Mesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 3]]).unwrap_err();
        assert_eq!(err.index, 3);
        assert!(err.to_string().contains("has 3 vertices"));
    }

    #[test]
    fn round_trips_triangles() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let mut m = Mesh::from_triangles(&[t]);
        m.append(&Mesh::from_triangles(&[t]));
        assert_eq!(m.triangles(), vec![t, t]);
        assert_eq!(m.bounds(), Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
    }
}

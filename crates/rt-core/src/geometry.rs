//! Where a structure's primitives come from: anything that hands them out by index.
//!
//! [`Accel::build`](crate::Accel::build) takes a slice of primitives, so a mesh loaded with
//! shared vertices had to be expanded into a `Vec<Triangle>` first (36 bytes per triangle),
//! which the structure then copied again into its own layout.
//! [`Accel::build_from`](crate::Accel::build_from) takes any [`Geometry`] instead: a slice, a
//! [`Mesh`], or an [`IndexedTriangles`] view of buffers the caller already has. Each structure
//! reads the triangles straight from the indices into the layout it keeps (rt-bvh's wide tree
//! into its SIMD packs, never a triangle list), so no intermediate copy exists.

use crate::mesh::check_indices;
use crate::{Mesh, MeshError, Primitive, Triangle};
use glam::Vec3;

/// A source of primitives, numbered `0..len()`: what a structure is built from.
///
/// Hits and closest points report these numbers. `prim` is called many times per primitive
/// while a structure is built (for its box, its centroid, its clipped parts), so it should be
/// cheap: a clone of a slice element, or a triangle gathered through three indices.
pub trait Geometry: Sync {
    /// The primitive type handed out.
    type Prim: Primitive;

    /// How many primitives there are.
    fn len(&self) -> usize;

    /// Whether there are none.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Primitive `index`.
    ///
    /// # Panics
    /// If `index >= self.len()`.
    fn prim(&self, index: usize) -> Self::Prim;

    /// Every primitive, in order: the copy a structure that keeps its primitives by index
    /// stores.
    fn to_vec(&self) -> Vec<Self::Prim> {
        (0..self.len()).map(|i| self.prim(i)).collect()
    }
}

impl<P: Primitive> Geometry for [P] {
    type Prim = P;

    #[inline]
    fn len(&self) -> usize {
        <[P]>::len(self)
    }

    #[inline]
    fn prim(&self, index: usize) -> P {
        self[index].clone()
    }

    fn to_vec(&self) -> Vec<P> {
        <[P]>::to_vec(self)
    }
}

impl<P: Primitive, const N: usize> Geometry for [P; N] {
    type Prim = P;

    #[inline]
    fn len(&self) -> usize {
        N
    }

    #[inline]
    fn prim(&self, index: usize) -> P {
        self[index].clone()
    }
}

impl<P: Primitive> Geometry for Vec<P> {
    type Prim = P;

    #[inline]
    fn len(&self) -> usize {
        self.as_slice().len()
    }

    #[inline]
    fn prim(&self, index: usize) -> P {
        self[index].clone()
    }

    fn to_vec(&self) -> Vec<P> {
        self.clone()
    }
}

/// Triangle `i` of a mesh is primitive `i`, as in [`Mesh::triangles`].
impl Geometry for Mesh {
    type Prim = Triangle;

    #[inline]
    fn len(&self) -> usize {
        self.triangle_count()
    }

    #[inline]
    fn prim(&self, index: usize) -> Triangle {
        self.triangle(index)
    }
}

/// Borrowed triangle buffers with shared vertices: positions and one index triple per
/// triangle, checked once, so a structure can be built from a renderer's or an engine's own
/// buffers without copying them into a [`Mesh`] or a triangle list.
///
/// ```
/// use rt_core::{Accel, BruteForce, IndexedTriangles, Ray, glam::Vec3};
/// // Two triangles sharing an edge, as flat buffers (x, y, z per vertex; three indices each).
/// let positions = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0];
/// let indices = [0, 1, 2, 2, 1, 3];
/// let view = IndexedTriangles::from_flat(&positions, &indices).unwrap();
/// let accel = BruteForce::build_from(&view, &());
/// let hit = accel.intersect(&Ray::new(Vec3::new(0.9, 0.9, 1.0), -Vec3::Z)).unwrap();
/// assert_eq!((hit.prim, hit.t), (1, 1.0));
/// assert!(IndexedTriangles::from_flat(&positions, &[0, 1, 4]).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndexedTriangles<'a> {
    positions: &'a [Vec3],
    indices: &'a [[u32; 3]],
}

impl<'a> IndexedTriangles<'a> {
    /// A view of `positions` and `indices`.
    ///
    /// # Errors
    /// [`MeshError::IndexOutOfRange`] if an index is not below `positions.len()`.
    pub fn new(positions: &'a [Vec3], indices: &'a [[u32; 3]]) -> Result<Self, MeshError> {
        check_indices(positions.len(), indices)?;
        Ok(Self { positions, indices })
    }

    /// A view of flat buffers: three floats per vertex, three indices per triangle (as glTF
    /// and most engines store them).
    ///
    /// # Errors
    /// [`MeshError::Ragged`] if a buffer's length is not a multiple of three;
    /// [`MeshError::IndexOutOfRange`] if an index names no vertex.
    pub fn from_flat(positions: &'a [f32], indices: &'a [u32]) -> Result<Self, MeshError> {
        let ragged = |buffer, len: usize| {
            (!len.is_multiple_of(3)).then_some(MeshError::Ragged { buffer, len })
        };
        if let Some(e) = ragged("position", positions.len()).or(ragged("index", indices.len())) {
            return Err(e);
        }
        // Both views are of runs of three 4-byte scalars, so alignment always holds, and the
        // lengths were checked above: neither can fail or drop an element.
        let positions: &[Vec3] = rt_pod::vec3s(positions);
        let indices: &[[u32; 3]] = bytemuck::cast_slice(indices);
        Self::new(positions, indices)
    }

    /// The vertex positions.
    pub fn positions(&self) -> &'a [Vec3] {
        self.positions
    }

    /// The index triples, one per triangle.
    pub fn indices(&self) -> &'a [[u32; 3]] {
        self.indices
    }
}

impl Geometry for IndexedTriangles<'_> {
    type Prim = Triangle;

    #[inline]
    fn len(&self) -> usize {
        self.indices.len()
    }

    #[inline]
    fn prim(&self, index: usize) -> Triangle {
        let [a, b, c] = self.indices[index];
        Triangle::new(
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        )
    }
}

impl Mesh {
    /// The mesh's positions and indices as an [`IndexedTriangles`] view.
    pub fn view(&self) -> IndexedTriangles<'_> {
        IndexedTriangles {
            positions: self.positions(),
            indices: self.indices(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_source_hands_out_the_same_triangles() {
        // A bumpy 5 × 5 grid of shared vertices: 32 triangles, each vertex used up to six times.
        let positions: Vec<Vec3> = (0..25)
            .map(|i| Vec3::new((i % 5) as f32, (i / 5) as f32, ((i * 7) % 3) as f32 * 0.25))
            .collect();
        let indices: Vec<[u32; 3]> = (0..16u32)
            .flat_map(|q| {
                let v = q / 4 * 5 + q % 4;
                [[v, v + 1, v + 6], [v, v + 6, v + 5]]
            })
            .collect();
        let mesh = Mesh::new(positions, indices).unwrap();
        let tris = mesh.triangles();
        assert_eq!(tris.len(), 32);
        let view = mesh.view();
        assert_eq!(Geometry::len(&mesh), tris.len());
        assert!(tris.iter().all(|t| t.is_valid()));
        assert_eq!(Geometry::len(&view), tris.len());
        assert_eq!(Geometry::to_vec(&mesh), tris);
        assert_eq!(view.to_vec(), tris);
        assert_eq!(Geometry::to_vec(tris.as_slice()), tris);
        assert_eq!(Geometry::prim(&tris, 7), tris[7]);
    }

    #[test]
    fn ragged_or_dangling_buffers_are_refused() {
        let p = [0.0; 9];
        assert_eq!(
            IndexedTriangles::from_flat(&p[..8], &[0, 1, 2]),
            Err(MeshError::Ragged {
                buffer: "position",
                len: 8
            })
        );
        assert_eq!(
            IndexedTriangles::from_flat(&p, &[0, 1]),
            Err(MeshError::Ragged {
                buffer: "index",
                len: 2
            })
        );
        assert!(matches!(
            IndexedTriangles::from_flat(&p, &[0, 1, 3]),
            Err(MeshError::IndexOutOfRange {
                index: 3,
                len: 3,
                ..
            })
        ));
        assert_eq!(
            IndexedTriangles::from_flat(&p, &[0, 1, 2]).unwrap().len(),
            1
        );
    }
}

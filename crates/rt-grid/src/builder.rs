//! The build: resolution, then a counting sort of (cell, primitive) pairs.
//!
//! Each primitive is tested against the cells of its bounding box and listed in those it
//! overlaps ([`Primitive::clip_bounds`]: exact for triangles). The pairs are then counted per
//! cell, the counts turned into offsets, and the pairs written in primitive order, so a cell's
//! references are sorted and the layout does not depend on threading. O(N + cells) besides the
//! overlap tests.

use crate::GridParams;
use crate::cell::GridShape;
use rt_core::{Aabb, Primitive};

/// Primitives handed to one rayon task when the build runs in parallel.
const CHUNK: usize = 2048;

/// What the builder hands to [`Grid`](crate::Grid).
#[derive(Debug)]
pub(crate) struct Built {
    pub shape: GridShape,
    /// `cells[i]..cells[i + 1]` indexes `refs` for cell `i`.
    pub cells: Vec<u32>,
    pub refs: Vec<u32>,
    pub valid_prims: usize,
}

/// How far a cell is widened, per axis, for the overlap test: a few units in the last place of
/// the grid's coordinates. Traversal finds its first cell from a rounded entry point, which can
/// land a cell away from the planes right next to a boundary; a primitive within rounding of a
/// plane is therefore listed on both sides.
pub(crate) fn margin(shape: &GridShape) -> [f32; 3] {
    let b = shape.bounds();
    std::array::from_fn(|a| (b.min[a].abs() + b.max[a].abs()) * f32::EPSILON * 8.0)
}

/// The cell's box widened by `margin`.
pub(crate) fn test_box(shape: &GridShape, c: [u32; 3], margin: [f32; 3]) -> Aabb {
    let b = shape.cell_box(c);
    let m = rt_core::glam::Vec3::from_array(margin);
    Aabb::new(b.min - m, b.max + m)
}

/// The cells of `shape` that primitive `prim` (index `id`) is listed in: those of its bounding
/// box whose box, widened by a few units in the last place of the grid's coordinates, it
/// overlaps ([`Primitive::clip_bounds`]: exact for triangles). Appends `(cell index, id)` pairs
/// to `out`. Hierarchical grids insert into their nested grids with the same rule.
pub fn cells_overlapping<P: Primitive>(
    shape: &GridShape,
    prim: &P,
    id: u32,
    out: &mut Vec<(u32, u32)>,
) {
    cells_of(shape, margin(shape), prim, id, true, out);
}

/// [`cells_overlapping`] with the margin computed once by the caller.
pub(crate) fn cells_of<P: Primitive>(
    shape: &GridShape,
    margin: [f32; 3],
    prim: &P,
    id: u32,
    exact: bool,
    out: &mut Vec<(u32, u32)>,
) {
    let b = prim.bounds();
    let lo: [u32; 3] = std::array::from_fn(|a| shape.cell_of(a, b.min[a] - margin[a]));
    let hi: [u32; 3] = std::array::from_fn(|a| shape.cell_of(a, b.max[a] + margin[a]));
    // A primitive whose box lies in one cell overlaps that cell: no test needed. Without
    // `exact`, every cell of the box gets the primitive.
    let single = lo == hi || !exact;
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let c = [x, y, z];
                if single || prim.clip_bounds(&test_box(shape, c, margin)).is_some() {
                    out.push((shape.index(c) as u32, id));
                }
            }
        }
    }
}

pub(crate) fn build<P: Primitive>(prims: &[P], params: &GridParams) -> Built {
    let (ids, bounds) = rt_core::valid_primitives(prims);
    if ids.is_empty() {
        let zero = rt_core::glam::Vec3::ZERO;
        let shape = GridShape::new(Aabb::new(zero, zero), [1; 3]);
        return Built {
            shape,
            cells: vec![0, 0],
            refs: Vec::new(),
            valid_prims: 0,
        };
    }
    let res = GridShape::resolution(&bounds, ids.len(), params.density, params.max_cells);
    let shape = GridShape::new(bounds, res);
    let margin = margin(&shape);
    let exact = params.exact_insertion;
    let pairs_of = |chunk: &[u32]| {
        let mut out = Vec::with_capacity(chunk.len() * 2);
        for &id in chunk {
            cells_of(&shape, margin, &prims[id as usize], id, exact, &mut out);
        }
        out
    };
    let chunks: Vec<Vec<(u32, u32)>> = if params.parallel && ids.len() > CHUNK {
        rt_core::par::map_chunks(&ids, CHUNK, pairs_of)
    } else {
        vec![pairs_of(&ids)]
    };
    let total: usize = chunks.iter().map(Vec::len).sum();
    assert!(
        total <= u32::MAX as usize,
        "a grid holds at most 2^32 - 1 primitive references"
    );
    // Counting sort by cell; chunks are in primitive order, so each cell's list is too.
    let n_cells = shape.cell_count();
    let mut cells = vec![0u32; n_cells + 1];
    for &(c, _) in chunks.iter().flatten() {
        cells[c as usize + 1] += 1;
    }
    for i in 0..n_cells {
        cells[i + 1] += cells[i];
    }
    let mut cursor = cells.clone();
    let mut refs = vec![0u32; total];
    for &(c, id) in chunks.iter().flatten() {
        let slot = &mut cursor[c as usize];
        refs[*slot as usize] = id;
        *slot += 1;
    }
    Built {
        shape,
        cells,
        refs,
        valid_prims: ids.len(),
    }
}

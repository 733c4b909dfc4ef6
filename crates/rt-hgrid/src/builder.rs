//! The build: a uniform top grid, then a nested grid in every crowded cell, recursively.
//!
//! A grid lists each primitive in the cells it overlaps (`rt_grid::cells_overlapping`, the
//! exact test with the uniform grid's margin) and counting-sorts the pairs by cell. A cell with
//! at least `split_min` primitives, above the last level, becomes the box of a nested grid whose
//! resolution follows its own count (`density` cells per primitive, as Kalojanov et al. 2011 size
//! each top cell's grid); the others keep their list. Termination and bounded memory: the level
//! count is bounded, all grids together stay within `max_cells`, and a cell keeps its list when
//! its nested grid would have one cell, more than eight references per primitive, or a nested
//! cell with more than three quarters of its primitives (large, identical or overlapping
//! primitives, which no grid separates).

use crate::HGridParams;
use crate::node::{Cell, Level};
use rt_core::{Aabb, Primitive};
use rt_grid::{GridShape, cells_overlapping};

/// The most levels, the top grid included: the size of the walk's fixed stack.
pub const MAX_LEVELS: usize = 4;

/// Primitives handed to one rayon task when the top grid's overlap tests run in parallel.
const CHUNK: usize = 2048;

#[derive(Debug, Default)]
pub(crate) struct Built {
    pub levels: Vec<Level>,
    pub cells: Vec<Cell>,
    pub refs: Vec<u32>,
    pub valid_prims: usize,
    pub depth: u32,
}

struct Ctx<'a, P> {
    prims: &'a [P],
    /// Cells the nested grids may still take: all grids together stay within `max_cells`.
    budget: std::cell::Cell<usize>,
    density: f32,
    split_min: usize,
    max_levels: u32,
    max_cells: usize,
}

pub(crate) fn build<P: Primitive>(prims: &[P], params: &HGridParams) -> Built {
    let (ids, bounds) = rt_core::valid_primitives(prims);
    let mut out = Built {
        valid_prims: ids.len(),
        ..Built::default()
    };
    if ids.is_empty() {
        let zero = rt_core::glam::Vec3::ZERO;
        out.levels.push(Level {
            shape: GridShape::new(Aabb::new(zero, zero), [1; 3]),
            first_cell: 0,
            all: (0, 0),
            depth: 0,
        });
        out.cells.push(Cell::leaf(0, 0));
        return out;
    }
    let ctx = Ctx {
        prims,
        budget: std::cell::Cell::new(params.max_cells),
        density: params.density,
        split_min: (params.split_min as usize).max(2),
        max_levels: params.max_levels.clamp(1, MAX_LEVELS as u32),
        max_cells: params.max_cells,
    };
    let res = GridShape::resolution(&bounds, ids.len(), params.top_density, params.max_cells);
    let shape = GridShape::new(bounds, res);
    ctx.budget
        .set(params.max_cells.saturating_sub(shape.cell_count()));
    let pairs_of = |chunk: &[u32]| {
        let mut pairs = Vec::with_capacity(chunk.len() * 2);
        for &id in chunk {
            cells_overlapping(&shape, &prims[id as usize], id, &mut pairs);
        }
        pairs
    };
    // Chunks are in primitive order, so the concatenation is too.
    let pairs: Vec<(u32, u32)> = if params.parallel && ids.len() > CHUNK {
        rt_core::par::map_chunks(&ids, CHUNK, pairs_of).concat()
    } else {
        pairs_of(&ids)
    };
    build_level(&ctx, &mut out, shape, &pairs, 0, (0, 0));
    out
}

/// How many cells of `shape` box `b` spans.
fn box_cells(shape: &GridShape, b: &Aabb) -> usize {
    (0..3)
        .map(|a| (shape.cell_of(a, b.max[a]) - shape.cell_of(a, b.min[a]) + 1) as usize)
        .product()
}

/// Whether a nested grid with these `(cell, primitive)` pairs, over a cell of `n` primitives,
/// is worth having: no nested cell may keep more than three quarters of them. Identical or
/// heavily overlapping primitives land in the same nested cells however fine the grid, and
/// refining them again and again would multiply cells without ever separating them.
fn separates(nested: &GridShape, pairs: &[(u32, u32)], n: usize) -> bool {
    if pairs.is_empty() {
        return false;
    }
    let mut counts = vec![0u32; nested.cell_count()];
    for &(c, _) in pairs {
        counts[c as usize] += 1;
    }
    let most = counts.iter().copied().max().unwrap_or(0) as usize;
    4 * most <= 3 * n
}

/// Counting-sorts `(cell, primitive)` pairs (in primitive order) by cell: per-cell offsets into
/// the returned list, each cell's primitives in increasing order.
fn by_cell(n_cells: usize, pairs: &[(u32, u32)]) -> (Vec<usize>, Vec<u32>) {
    let mut offsets = vec![0usize; n_cells + 1];
    for &(c, _) in pairs {
        offsets[c as usize + 1] += 1;
    }
    for i in 0..n_cells {
        offsets[i + 1] += offsets[i];
    }
    let mut cursor = offsets.clone();
    let mut list = vec![0u32; pairs.len()];
    for &(c, id) in pairs {
        list[cursor[c as usize]] = id;
        cursor[c as usize] += 1;
    }
    (offsets, list)
}

/// Appends the grid `shape` holding `pairs` at `depth`, and its nested grids after it; returns
/// its index. `all` is the parent cell's reference range.
fn build_level<P: Primitive>(
    ctx: &Ctx<'_, P>,
    out: &mut Built,
    shape: GridShape,
    pairs: &[(u32, u32)],
    depth: u32,
    all: (usize, usize),
) -> usize {
    let index = out.levels.len();
    let first_cell = out.cells.len();
    let n = shape.cell_count();
    out.levels.push(Level {
        shape,
        first_cell,
        all,
        depth,
    });
    out.depth = out.depth.max(depth);
    out.cells.resize(first_cell + n, Cell::leaf(0, 0));
    let (offsets, list) = by_cell(n, pairs);
    let mut nested_pairs = Vec::new();
    for c in 0..n {
        let ids = &list[offsets[c]..offsets[c + 1]];
        if ids.len() >= ctx.split_min && depth + 1 < ctx.max_levels {
            let cell_box = shape.cell_box(shape.coords(c));
            let res = GridShape::resolution(&cell_box, ids.len(), ctx.density, ctx.max_cells);
            let nested = GridShape::new(cell_box, res);
            nested_pairs.clear();
            // Primitives whose boxes span many nested cells would be listed in many of them; past
            // eight references per primitive a nested grid cannot pay. The boxes bound the count
            // before any overlap test, and the tests stop as soon as the references pass it.
            let cap = 8 * ids.len();
            let spans: usize = ids
                .iter()
                .map(|&id| box_cells(&nested, &ctx.prims[id as usize].bounds()))
                .sum();
            let mut worth_it = res.iter().any(|&r| r > 1)
                && nested.cell_count() <= ctx.budget.get()
                && spans <= 4 * cap;
            for &id in ids {
                if !worth_it {
                    break;
                }
                cells_overlapping(&nested, &ctx.prims[id as usize], id, &mut nested_pairs);
                worth_it = nested_pairs.len() <= cap;
            }
            if worth_it && separates(&nested, &nested_pairs, ids.len()) {
                ctx.budget.set(ctx.budget.get() - nested.cell_count());
                let all_first = out.refs.len();
                out.refs.extend_from_slice(ids);
                let pairs = std::mem::take(&mut nested_pairs);
                let child = build_level(
                    ctx,
                    out,
                    nested,
                    &pairs,
                    depth + 1,
                    (all_first, all_first + ids.len()),
                );
                nested_pairs = pairs;
                out.cells[first_cell + c] = Cell::parent(child);
                continue;
            }
        }
        out.cells[first_cell + c] = Cell::leaf(out.refs.len(), ids.len());
        out.refs.extend_from_slice(ids);
    }
    index
}

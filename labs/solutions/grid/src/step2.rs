//! Step 2: how many cells, and which triangles go in each.
//!
//! Resolution: Cleary & Wyvill's rule, as in pbrt-v1 and Wald's grid papers: about
//! `density × N` cells, as close to cubes as the box allows. With `V` the box's volume, a cube
//! cell has side `s = ∛(V / (density · N))`, and axis `a` gets `⌈extent_a / s⌉` cells (at least
//! 1, and at most [`MAX_RES`]). A flat axis (extent 0) gets one cell; then compute the side from
//! the area (or length) of the other axes instead.
//!
//! Build: each valid triangle goes into every cell its bounding box overlaps (conservative: a
//! cell may list a triangle that only its box touches; that costs tests, never answers). Pad
//! the triangle's box by a small fraction of the scene's size so that a triangle lying on a
//! cell boundary is listed on both sides: rays are walked through one side or the other by
//! rounding. Store the lists as one array: count per cell, prefix sums into `cells`, then fill
//! `refs` (a counting sort).

use crate::LabGrid;
use rt_core::{Aabb, Primitive};

/// The most cells along one axis.
pub const MAX_RES: u32 = 128;

/// Cells per axis for `n` triangles in `bounds` with `density` cells per triangle; each entry
/// in `1..=MAX_RES`. An empty or invalid box gets `[1, 1, 1]`.
pub fn resolution(bounds: &Aabb, n: usize, density: f32) -> [u32; 3] {
    // BEGIN SOLUTION step 2: the resolution
    let extent = bounds.max - bounds.min;
    if n == 0
        || !extent.is_finite()
        || extent.min_element() < 0.0
        || density.is_nan()
        || density <= 0.0
    {
        return [1, 1, 1];
    }
    let cells = (density as f64 * n as f64).max(1.0);
    let axes: Vec<f64> = (0..3)
        .map(|a| extent[a] as f64)
        .filter(|&e| e > 0.0)
        .collect();
    if axes.is_empty() {
        return [1, 1, 1];
    }
    // The side of a cube (or square, or segment) cell: the measure of the non-flat axes shared
    // out among the cells.
    let measure: f64 = axes.iter().product();
    let side = (measure / cells).powf(1.0 / axes.len() as f64);
    std::array::from_fn(|a| {
        let e = extent[a] as f64;
        if e > 0.0 {
            ((e / side).ceil() as u32).clamp(1, MAX_RES)
        } else {
            1
        }
    })
    // END SOLUTION
}

/// The cell lists of `grid` (whose `bounds`, `res`, `inv_cell` and `tris` are set): the
/// offsets `cells` (one per cell, plus one) and the triangle indices `refs`.
pub fn fill_cells(grid: &LabGrid) -> (Vec<u32>, Vec<u32>) {
    // BEGIN SOLUTION step 2: the build
    let n = grid.res.iter().map(|&r| r as usize).product::<usize>();
    let pad = (grid.bounds.max - grid.bounds.min).max_element() * 1e-5 + 1e-30;
    let range = |b: Aabb| -> [(u32, u32); 3] {
        std::array::from_fn(|a| {
            let cell = |x: f32| {
                let f = ((x - grid.bounds.min[a]) * grid.inv_cell[a]).floor();
                (f.max(0.0) as u32).min(grid.res[a] - 1)
            };
            (cell(b.min[a] - pad), cell(b.max[a] + pad))
        })
    };
    let mut count = vec![0u32; n + 1];
    let each = |f: &mut dyn FnMut(usize, u32)| {
        for (id, t) in grid.tris.iter().enumerate() {
            if !t.is_valid() {
                continue;
            }
            let r = range(t.bounds());
            for z in r[2].0..=r[2].1 {
                for y in r[1].0..=r[1].1 {
                    for x in r[0].0..=r[0].1 {
                        f(grid.index([x, y, z]), id as u32);
                    }
                }
            }
        }
    };
    each(&mut |c, _| count[c + 1] += 1);
    for i in 0..n {
        count[i + 1] += count[i];
    }
    let mut next = count.clone();
    let mut refs = vec![0u32; count[n] as usize];
    each(&mut |c, id| {
        refs[next[c] as usize] = id;
        next[c] += 1;
    });
    (count, refs)
    // END SOLUTION
}

//! Step 3: the walk through the cells a ray crosses, in order (a 3D-DDA).
//!
//! Find the cell where the ray enters the grid (at `t0`, from step 1). Per axis, the ray moves
//! to the next cell when it crosses the next cell boundary in its direction (`plane(a, c + 1)`
//! going up, `plane(a, c)` going down, never for a zero direction component). The current
//! cell ends at the first of the three crossings, `t_exit`; step along that axis, and stop when
//! the walk leaves the grid or passes `t1`. Compute each crossing from the plane's coordinate
//! ([`LabGrid::plane`]), not by adding up step lengths, so rounding does not pile up.
//!
//! Rounding still bites when the origin is far away: from 10¹², the parameter's rounding step
//! (131,072) is larger than a small grid, so every plane is crossed at the same rounded `t`,
//! and the rounded entry point may lie cells away from the truth. Start in the first cell
//! along the ray that the ray leaves at or after `t0`, and do not stop at a crossing equal to
//! `t1`, or the walk skips cells (the kit's `far_origins` scene).

use crate::LabGrid;
use rt_core::Ray;

/// Calls `visit(cell, t_enter, t_exit)` for each cell the ray crosses between `t0` and `t1`
/// (where it is inside the grid's box), in order along the ray, until `visit` returns `true`
/// or the ray leaves the grid. `t_exit` is where the ray leaves the cell (at most `t1`).
pub fn walk(
    grid: &LabGrid,
    ray: &Ray,
    t0: f32,
    t1: f32,
    visit: impl FnMut([u32; 3], f32, f32) -> bool,
) {
    // BEGIN SOLUTION step 3: the walk
    let mut visit = visit;
    let p = ray.at(t0);
    let cross = |a: usize, k: u32| (grid.plane(a, k) - ray.origin[a]) * ray.inv_dir()[a];
    let mut cell: [u32; 3] = std::array::from_fn(|a| {
        let f = ((p[a] - grid.bounds.min[a]) * grid.inv_cell[a]).floor();
        let mut k = (f.max(0.0) as u32).min(grid.res[a] - 1);
        // The rounded entry point can be cells away from the truth when the origin is far (at
        // 10¹² the parameter's rounding step is larger than a small grid, and every plane's
        // crossing rounds to `t0`): move to the first cell along the ray that the ray leaves
        // at or after `t0`.
        if ray.dir()[a] > 0.0 {
            while k > 0 && cross(a, k) >= t0 {
                k -= 1;
            }
            while k + 1 < grid.res[a] && cross(a, k + 1) < t0 {
                k += 1;
            }
        } else if ray.dir()[a] < 0.0 {
            while k + 1 < grid.res[a] && cross(a, k + 1) >= t0 {
                k += 1;
            }
            while k > 0 && cross(a, k) < t0 {
                k -= 1;
            }
        }
        k
    });
    let mut t_enter = t0;
    loop {
        // Where the ray crosses the next boundary along each axis.
        let next: [f32; 3] = std::array::from_fn(|a| {
            let d = ray.dir()[a];
            if d > 0.0 {
                cross(a, cell[a] + 1)
            } else if d < 0.0 {
                cross(a, cell[a])
            } else {
                f32::INFINITY
            }
        });
        let a = (0..3)
            .min_by(|&i, &j| next[i].total_cmp(&next[j]))
            .unwrap_or(0);
        let t_exit = next[a].max(t_enter);
        // Strictly beyond `t1`: cells whose crossings all rounded to `t1` are still walked.
        if visit(cell, t_enter, t_exit.min(t1)) || t_exit > t1 {
            return;
        }
        if ray.dir()[a] > 0.0 {
            if cell[a] + 1 >= grid.res[a] {
                return;
            }
            cell[a] += 1;
        } else {
            if cell[a] == 0 {
                return;
            }
            cell[a] -= 1;
        }
        t_enter = t_exit;
    }
    // END SOLUTION
}

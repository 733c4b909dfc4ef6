//! The 3D-DDA stepper (Amanatides & Woo 1987), shared by the uniform and the hierarchical grid.
//!
//! Per axis it keeps the ray parameter `t` at which the ray reaches the next cell boundary; a
//! step moves one cell along the axis whose boundary comes first and costs a comparison chain,
//! an increment and one multiplication (the new boundary's `t`). Every boundary `t`, including
//! those that choose the first cell, comes from the same planes ([`GridShape::plane`]) and the
//! same formula, so the cells visited follow one consistent path.

use crate::cell::GridShape;
use rt_core::Ray;

/// Two boundaries crossed within this factor of each other count as crossed together, and the
/// cells beside the path there are tested too (shared with the octree; see its definition).
pub use rt_core::NEAR_TIE;

/// The ray's components as arrays, so an axis index does not branch.
#[derive(Clone, Copy, Debug)]
pub struct RayAxes {
    o: [f32; 3],
    d: [f32; 3],
    inv: [f32; 3],
}

impl RayAxes {
    /// The components of `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        Self {
            o: ray.origin.to_array(),
            d: ray.dir().to_array(),
            inv: ray.inv_dir().to_array(),
        }
    }

    /// The ray's parameter at the `k`-th plane of `axis` of `shape`.
    #[inline(always)]
    fn t_at(&self, shape: &GridShape, axis: usize, k: u32) -> f32 {
        (shape.plane(axis, k) - self.o[axis]) * self.inv[axis]
    }
}

/// Where a walk through one grid is: the current cell and each axis' next boundary.
#[derive(Clone, Copy, Debug)]
pub struct Dda {
    /// The current cell.
    pub cell: [u32; 3],
    t_next: [f32; 3],
}

impl Dda {
    /// The walk through `shape` of a ray that is inside its box at parameter `t0`: the first cell
    /// is the first along the ray whose exit parameter is at or after `t0`, found from the
    /// rounded entry point's cell and corrected against the planes so that it agrees with the
    /// steps that follow.
    #[inline(always)]
    pub fn start(shape: &GridShape, r: &RayAxes, t0: f32) -> Self {
        let mut cell = [0u32; 3];
        let mut t_next = [f32::INFINITY; 3];
        for a in 0..3 {
            cell[a] = first_cell(shape, r, a, t0);
            if r.d[a] > 0.0 {
                t_next[a] = r.t_at(shape, a, cell[a] + 1);
            } else if r.d[a] < 0.0 {
                t_next[a] = r.t_at(shape, a, cell[a]);
            }
        }
        Self { cell, t_next }
    }

    /// The axis whose boundary comes first (the lowest on ties) and the ray parameter there,
    /// where the ray leaves the current cell.
    #[inline(always)]
    pub fn exit(&self) -> (usize, f32) {
        let t = &self.t_next;
        let a = if t[0] <= t[1] && t[0] <= t[2] {
            0
        } else if t[1] <= t[2] {
            1
        } else {
            2
        };
        (a, t[a])
    }

    /// The cells beside the path at the exit through `axis`: each combination of the other axes
    /// whose boundaries are crossed within [`NEAR_TIE`] of it, stepped once, if in the grid.
    /// Empty almost always; up to three cells next to a corner.
    #[inline(always)]
    pub fn side_cells(
        &self,
        shape: &GridShape,
        r: &RayAxes,
        axis: usize,
    ) -> impl Iterator<Item = [u32; 3]> {
        let t_exit = self.t_next[axis];
        let near: [bool; 3] =
            std::array::from_fn(|b| b != axis && self.t_next[b] <= t_exit * NEAR_TIE);
        let any = near.iter().any(|&n| n);
        let (cell, res, d) = (self.cell, shape.resolution_per_axis(), r.d);
        (1u32..8)
            .filter(move |&mask| any && (0..3).all(|b| mask >> b & 1 == 0 || near[b]))
            .filter_map(move |mask| {
                let mut out = cell;
                for b in 0..3 {
                    if mask >> b & 1 == 1 {
                        out[b] = if d[b] > 0.0 {
                            (cell[b] + 1 < res[b]).then_some(cell[b] + 1)?
                        } else {
                            cell[b].checked_sub(1)?
                        };
                    }
                }
                Some(out)
            })
    }

    /// Steps to the next cell through `axis`; false if that leaves the grid.
    #[inline(always)]
    pub fn step(&mut self, shape: &GridShape, r: &RayAxes, axis: usize) -> bool {
        let res = shape.resolution_per_axis();
        if r.d[axis] > 0.0 {
            if self.cell[axis] + 1 >= res[axis] {
                return false;
            }
            self.cell[axis] += 1;
            self.t_next[axis] = r.t_at(shape, axis, self.cell[axis] + 1);
        } else {
            if self.cell[axis] == 0 {
                return false;
            }
            self.cell[axis] -= 1;
            self.t_next[axis] = r.t_at(shape, axis, self.cell[axis]);
        }
        true
    }
}

/// The cell on `axis` where the ray is at parameter `t0`: the coordinate `axis` of
/// [`Dda::start`]'s first cell, without the other two.
#[inline(always)]
pub fn first_cell(shape: &GridShape, r: &RayAxes, axis: usize, t0: f32) -> u32 {
    let n = shape.resolution_per_axis()[axis];
    let mut k = shape.cell_of(axis, r.o[axis] + r.d[axis] * t0);
    let t = |k| r.t_at(shape, axis, k);
    // The first cell along the ray that it leaves at or after `t0`, so that cells the ray
    // crosses in no time at all (their planes' parameters all round to `t0`) are walked, not
    // skipped. That happens when the origin is so far away that the parameter's rounding step
    // exceeds the cells: a ray from 10¹² towards a grid a few thousand units wide reaches every
    // plane "at once", and the walk must still go through the cells in order, from the near end.
    if r.d[axis] > 0.0 {
        while k > 0 && t(k) >= t0 {
            k -= 1;
        }
        while k + 1 < n && t(k + 1) < t0 {
            k += 1;
        }
    } else if r.d[axis] < 0.0 {
        while k + 1 < n && t(k + 1) >= t0 {
            k += 1;
        }
        while k > 0 && t(k) < t0 {
            k -= 1;
        }
    } else {
        // Parallel to the axis' planes: the coordinate is exact, compare it with the planes.
        while k > 0 && r.o[axis] < shape.plane(axis, k) {
            k -= 1;
        }
        while k + 1 < n && r.o[axis] >= shape.plane(axis, k + 1) {
            k += 1;
        }
    }
    k
}

//! 3D-DDA traversal (Amanatides & Woo 1987): walk the cells the ray crosses, in order.
//!
//! Per axis the walk keeps the ray parameter `t` at which it reaches the next cell boundary; a
//! step moves one cell along the axis whose boundary comes first, and costs one comparison
//! chain, an add and one multiplication (the new boundary's `t`). Every boundary `t`, including
//! those that choose the first cell, comes from the same planes ([`GridShape::plane`]) and the
//! same formula, so the cells visited follow one consistent path.
//!
//! The walk keeps the best hit found so far and stops once the next cell starts beyond it: a
//! primitive spanning several cells may be hit beyond the current cell while a closer one waits
//! in the next. Where two boundaries are crossed within rounding of each other (the ray passes
//! next to a cell edge or corner), the cells beside the path are tested too, as the kd-tree
//! visits both children of a plane it meets at an interval's end.

use crate::Grid;
use crate::cell::GridShape;
use rt_core::{Hit, Mailbox, Primitive, Ray, SLAB_FAR_SCALE, Stats, leaf};

/// Mailbox slots per ray: the last this many primitives tested are not tested again.
pub(crate) const MAILBOX: usize = 8;

/// The ray's parameter at the `k`-th plane of `axis`.
#[inline(always)]
fn t_at(shape: &GridShape, o: &[f32; 3], inv: &[f32; 3], axis: usize, k: u32) -> f32 {
    (shape.plane(axis, k) - o[axis]) * inv[axis]
}

/// The cell on `axis` where a ray with direction component `d` is at parameter `t0`: the one
/// whose boundary parameters enclose `t0`, found from the rounded entry point's cell and then
/// corrected against the planes, so it agrees with the steps that follow.
#[inline(always)]
fn first_cell(
    shape: &GridShape,
    o: &[f32; 3],
    d: &[f32; 3],
    inv: &[f32; 3],
    axis: usize,
    t0: f32,
) -> u32 {
    let n = shape.resolution_per_axis()[axis];
    let mut k = shape.cell_of(axis, o[axis] + d[axis] * t0);
    let t = |k| t_at(shape, o, inv, axis, k);
    if d[axis] > 0.0 {
        while k > 0 && t(k) > t0 {
            k -= 1;
        }
        while k + 1 < n && t(k + 1) <= t0 {
            k += 1;
        }
    } else if d[axis] < 0.0 {
        while k + 1 < n && t(k + 1) > t0 {
            k += 1;
        }
        while k > 0 && t(k) <= t0 {
            k -= 1;
        }
    } else {
        // Parallel to the axis' planes: the coordinate is exact, compare it with the planes.
        while k > 0 && o[axis] < shape.plane(axis, k) {
            k -= 1;
        }
        while k + 1 < n && o[axis] >= shape.plane(axis, k + 1) {
            k += 1;
        }
    }
    k
}

impl<P: Primitive> Grid<P> {
    /// Tests the primitives of cell `c` against `[ray.t_min, best.t]`. Returns true if `ANY` and
    /// one hit.
    #[inline(always)]
    fn test_cell<S: Stats, const ANY: bool>(
        &self,
        c: [u32; 3],
        ray: &Ray,
        best: &mut Hit,
        mailbox: &mut Mailbox<MAILBOX>,
        stats: &mut S,
    ) -> bool {
        let i = self.shape.index(c);
        let ids = &self.refs[self.cells[i] as usize..self.cells[i + 1] as usize];
        leaf::test_primitives::<P, S, ANY, MAILBOX>(
            &self.prims,
            ids,
            ray,
            best,
            mailbox,
            self.mailbox,
            stats,
        )
    }

    /// The DDA walk. `ANY = false` finds the closest hit; `ANY = true` returns at the first.
    #[inline(always)]
    pub(crate) fn walk<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        if self.refs.is_empty() {
            return None;
        }
        let shape = &self.shape;
        let (t0, t1) = shape.bounds().intersect(ray, ray.t_max)?;
        let (o, d, inv) = (
            ray.origin.to_array(),
            ray.dir.to_array(),
            ray.inv_dir.to_array(),
        );
        let res = shape.resolution_per_axis();
        let mut cell = [0u32; 3];
        let mut t_next = [f32::INFINITY; 3];
        for a in 0..3 {
            cell[a] = first_cell(shape, &o, &d, &inv, a, t0);
            if d[a] > 0.0 {
                t_next[a] = t_at(shape, &o, &inv, a, cell[a] + 1);
            } else if d[a] < 0.0 {
                t_next[a] = t_at(shape, &o, &inv, a, cell[a]);
            }
        }
        let mut best = leaf::no_hit(ray.t_max);
        let mut mailbox = Mailbox::new();
        loop {
            stats.node_visit();
            if self.test_cell::<S, ANY>(cell, ray, &mut best, &mut mailbox, stats) {
                break;
            }
            // The axis whose boundary comes first, lowest axis on ties.
            let a = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                0
            } else if t_next[1] <= t_next[2] {
                1
            } else {
                2
            };
            let t_exit = t_next[a];
            if t_exit > best.t * SLAB_FAR_SCALE || t_exit > t1 {
                break;
            }
            // Boundaries crossed within rounding of this one: the path may graze the cells
            // beside it, so test those too (a cell with both axes stepped for a corner).
            let near = |b: usize| b != a && t_next[b] <= t_exit * SLAB_FAR_SCALE;
            let side = [near(0), near(1), near(2)];
            if side.iter().any(|&s| s) {
                for mask in 1u32..8 {
                    let stepped: [bool; 3] = std::array::from_fn(|b| mask >> b & 1 == 1);
                    if (0..3).any(|b| stepped[b] && !side[b]) {
                        continue;
                    }
                    if let Some(c) = neighbour(cell, stepped, &d, res) {
                        stats.node_visit();
                        if self.test_cell::<S, ANY>(c, ray, &mut best, &mut mailbox, stats) {
                            return leaf::answer::<ANY>(best);
                        }
                    }
                }
            }
            if d[a] > 0.0 {
                if cell[a] + 1 >= res[a] {
                    break;
                }
                cell[a] += 1;
                t_next[a] = t_at(shape, &o, &inv, a, cell[a] + 1);
            } else {
                if cell[a] == 0 {
                    break;
                }
                cell[a] -= 1;
                t_next[a] = t_at(shape, &o, &inv, a, cell[a]);
            }
        }
        leaf::answer::<ANY>(best)
    }
}

/// Cell `c` stepped one cell in the ray's direction on each axis of `stepped`, if in the grid.
#[inline]
fn neighbour(c: [u32; 3], stepped: [bool; 3], d: &[f32; 3], res: [u32; 3]) -> Option<[u32; 3]> {
    let mut out = c;
    for b in 0..3 {
        if stepped[b] {
            out[b] = if d[b] > 0.0 {
                (c[b] + 1 < res[b]).then_some(c[b] + 1)?
            } else {
                c[b].checked_sub(1)?
            };
        }
    }
    Some(out)
}

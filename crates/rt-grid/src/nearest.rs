//! Ball queries (closest point) over a grid: cells in growing shells around the centre.

use crate::{Grid, GridShape};
use rt_core::glam::Vec3;
use rt_core::{Aabb, BallQuery, Mailbox, Primitive, Stats};

/// Mailbox slots per query: a primitive listed in several cells is offered once.
const MAILBOX: usize = 8;

/// Calls `visit` for the cells of `shape` that meet the ball of `q`, in shells of growing
/// Chebyshev distance around the cell of the point of the grid's box nearest the centre: first
/// that cell, then the 26 around it, and so on. A cell is passed (with its box) only if its box
/// lies within the ball as the radius stands when the shell reaches it, and the walk ends at the
/// first shell that lies wholly outside the ball, or when the shells cover the grid.
///
/// The stop rule: a point `x` of the grid and the centre `c` (projected onto the grid's box at
/// `p`) satisfy `|c - x|² ≥ |c - p|² + |p - x|²` (projection onto a convex set), and every cell
/// of shell `k` lies beyond the planes `k` cells away from `p`'s cell on at least one side.
///
/// The hierarchical grid runs it on each nested grid too.
pub fn shells<P, Q: BallQuery<P>>(
    shape: &GridShape,
    q: &mut Q,
    mut visit: impl FnMut(&mut Q, [u32; 3], &Aabb),
) {
    let c = q.center();
    let b = shape.bounds();
    let outside = b.distance_squared(c);
    if outside > q.radius_sq() {
        return;
    }
    let p = c.clamp(b.min, b.max);
    let res = shape.resolution_per_axis();
    let home: [u32; 3] = std::array::from_fn(|a| shape.cell_of(a, p[a]));
    let last = (0..3)
        .map(|a| home[a].max(res[a] - 1 - home[a]))
        .max()
        .unwrap_or(0);
    let mut cell = |q: &mut Q, x: u32, y: u32, z: u32| {
        let cb = shape.cell_box([x, y, z]);
        if cb.distance_squared(c) <= q.radius_sq() {
            visit(q, [x, y, z], &cb);
        }
    };
    for k in 0..=last {
        if k > 0 && outside + gap(shape, home, res, k, p).powi(2) > q.radius_sq() {
            return;
        }
        let lo: [u32; 3] = std::array::from_fn(|a| home[a].saturating_sub(k));
        let hi: [u32; 3] = std::array::from_fn(|a| (home[a] + k).min(res[a] - 1));
        for z in lo[2]..=hi[2] {
            let on_z = z.abs_diff(home[2]) == k;
            for y in lo[1]..=hi[1] {
                if on_z || y.abs_diff(home[1]) == k {
                    for x in lo[0]..=hi[0] {
                        cell(q, x, y, z);
                    }
                } else {
                    // Inside the shell's square on this row: only its two ends.
                    if home[0] >= k {
                        cell(q, home[0] - k, y, z);
                    }
                    if home[0] + k < res[0] {
                        cell(q, home[0] + k, y, z);
                    }
                }
            }
        }
    }
}

/// A lower bound on the distance from `p` (in cell `home`) to any cell of shell `k >= 1`: the
/// nearest of the planes `k` cells away on the sides where the shell has cells, shrunk by a
/// relative `2⁻²⁰` against rounding.
fn gap(shape: &GridShape, home: [u32; 3], res: [u32; 3], k: u32, p: Vec3) -> f32 {
    let mut gap = f32::INFINITY;
    for a in 0..3 {
        if home[a] + k < res[a] {
            gap = gap.min((shape.plane(a, home[a] + k) - p[a]).max(0.0));
        }
        if home[a] >= k {
            gap = gap.min((p[a] - shape.plane(a, home[a] - k + 1)).max(0.0));
        }
    }
    gap * (1.0 - 1.0 / 1_048_576.0)
}

impl<P: Primitive> Grid<P> {
    /// The ball query: [`shells`], offering each cell's primitives once (mailboxed when the
    /// grid's `mailbox` parameter is on).
    pub(crate) fn ball<Q: BallQuery<P>, S: Stats>(&self, q: &mut Q, stats: &mut S) {
        if self.refs.is_empty() {
            return;
        }
        let mut mailbox = Mailbox::<MAILBOX>::new();
        shells(&self.shape, q, |q, c, _| {
            stats.node_visit();
            let i = self.shape.index(c);
            for &id in &self.refs[self.cells[i] as usize..self.cells[i + 1] as usize] {
                if self.mailbox && mailbox.check_and_insert(id) {
                    stats.mailbox_skip();
                    continue;
                }
                stats.prim_test();
                q.test(&self.prims[id as usize], id);
            }
        });
    }
}

//! The nested walk: a 3D-DDA through the top grid that, at a cell holding a nested grid, walks
//! that grid along the ray's stretch in the cell, then resumes.
//!
//! The walks in progress sit on a fixed stack, one per level. A cell is visited once (a leaf's
//! primitives tested, or its nested grid entered at the ray's entry into the cell); a walk that
//! leaves its grid pops, and the walk below steps on. Everything else is the uniform grid's:
//! the best hit is kept across cells and the walk ends at the first cell starting beyond it, and
//! where two boundaries are crossed within rounding of each other the cells beside the path are
//! tested too (a parent cell there by its whole list of primitives).

use crate::HGrid;
use crate::builder::MAX_LEVELS;
use rt_core::trace::{self, Event, Place};
use rt_core::{Hit, Mailbox, Primitive, Ray, SLAB_FAR_SCALE, Stats, leaf};
use rt_grid::dda::{Dda, RayAxes};

/// Mailbox slots per ray.
pub(crate) const MAILBOX: usize = 8;

/// A walk through one grid of the hierarchy.
#[derive(Clone, Copy, Debug)]
struct Walk {
    level: u32,
    dda: Dda,
    /// Where the ray enters the current cell.
    t_enter: f32,
    /// Whether the current cell was tested or entered.
    visited: bool,
}

impl<P: Primitive> HGrid<P> {
    /// The nested walk. `ANY = false` finds the closest hit; `ANY = true` returns at the first.
    #[inline(always)]
    pub(crate) fn walk<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        // Outside the precondition (NaN, huge origins, ...): answer at once, walk nothing.
        if self.refs.is_empty() || !ray.is_valid() {
            return None;
        }
        let top = &self.levels[0];
        let (t0, t1) = top.shape.bounds().intersect(ray, ray.t_max)?;
        let r = RayAxes::new(ray);
        let start = Walk {
            level: 0,
            dda: Dda::start(&top.shape, &r, t0),
            t_enter: t0,
            visited: false,
        };
        let mut stack = [start; MAX_LEVELS];
        let mut sp = 1;
        let mut best = leaf::no_hit(ray.t_max);
        let mut mailbox = Mailbox::<MAILBOX>::new();
        let mut test = |ids: &[u32], best: &mut Hit, stats: &mut S| {
            leaf::test_primitives::<P, S, ANY, MAILBOX>(
                &self.prims,
                ids,
                ray,
                best,
                &mut mailbox,
                self.mailbox,
                stats,
            )
        };
        loop {
            let w = stack[sp - 1];
            let level = &self.levels[w.level as usize];
            let enter = |cell: [u32; 3], t0: f32, t1: f32| Event::Enter {
                place: Place::Cell {
                    grid: w.level,
                    cell,
                },
                t0,
                t1,
                bounds: Some(level.shape.cell_box(cell)),
            };
            if !w.visited {
                stack[sp - 1].visited = true;
                stats.node_visit();
                trace::report(stats, || {
                    enter(w.dda.cell, w.t_enter, w.dda.exit().1.min(t1))
                });
                let cell = self.cells[level.first_cell + level.shape.index(w.dda.cell)];
                if let Some(nested) = cell.nested() {
                    trace::report(stats, || Event::Note("refined by a nested grid: walk it"));
                    let shape = &self.levels[nested].shape;
                    stack[sp] = Walk {
                        level: nested as u32,
                        dda: Dda::start(shape, &r, w.t_enter),
                        t_enter: w.t_enter,
                        visited: false,
                    };
                    sp += 1;
                    continue;
                }
                if test(&self.refs[cell.references()], &mut best, stats) {
                    trace::report(stats, || Event::Note("a primitive blocks the ray: done"));
                    break;
                }
            }
            let (a, t_exit) = w.dda.exit();
            if t_exit > best.t * SLAB_FAR_SCALE || t_exit > t1 {
                trace::report(stats, || {
                    Event::Note(if t_exit > t1 {
                        "the ray leaves the top grid: done"
                    } else {
                        "the next cell starts beyond the best hit: done"
                    })
                });
                break;
            }
            for c in w.dda.side_cells(&level.shape, &r, a) {
                stats.node_visit();
                trace::report(stats, || {
                    Event::Note("two planes crossed within rounding: the cell beside the path too")
                });
                trace::report(stats, || enter(c, t_exit, t_exit));
                let cell = self.cells[level.first_cell + level.shape.index(c)];
                let ids = match cell.nested() {
                    Some(nested) => {
                        let (lo, hi) = self.levels[nested].all;
                        &self.refs[lo..hi]
                    }
                    None => &self.refs[cell.references()],
                };
                if test(ids, &mut best, stats) {
                    return leaf::answer::<ANY>(best);
                }
            }
            let w = &mut stack[sp - 1];
            if w.dda.step(&level.shape, &r, a) {
                w.t_enter = t_exit;
                w.visited = false;
            } else {
                sp -= 1;
                trace::report(stats, || {
                    Event::Note(if sp == 0 {
                        "the ray leaves the top grid: done"
                    } else {
                        "the ray leaves the nested grid: back to the grid above"
                    })
                });
                if sp == 0 {
                    break;
                }
            }
        }
        leaf::answer::<ANY>(best)
    }
}

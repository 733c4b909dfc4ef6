//! The nested walk: a 3D-DDA through the top grid that, at a cell holding a nested grid, walks
//! that grid along the ray's stretch in the cell, then resumes.
//!
//! The walks in progress sit on a fixed stack, one per level. A cell is visited once (a leaf's
//! primitives tested, or its nested grid entered at the ray's entry into the cell); a walk that
//! leaves its grid pops, and the walk below steps on. Everything else is the uniform grid's:
//! hits are offered to the query across cells and the walk ends at the first cell starting beyond
//! the query's far end (for a closest hit, the best hit so far), and
//! where two boundaries are crossed within rounding of each other the cells beside the path are
//! tested too (a parent cell there by its whole list of primitives).

use crate::HGrid;
use crate::builder::MAX_LEVELS;
use rt_core::leaf::{self, Seen};
use rt_core::trace::{self, Event, Place};
use rt_core::{Primitive, Ray, RayQuery, SLAB_FAR_SCALE, Stats};
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
    /// The walk for query `q`, with the record of tested primitives its query needs
    /// ([`leaf::walk_once`]: a mailbox of the last [`MAILBOX`], or every one).
    #[inline(always)]
    pub(crate) fn query<S: Stats, Q: RayQuery>(&self, ray: &Ray, q: &mut Q, stats: &mut S) {
        leaf::walk_once::<_, MAILBOX, Q, S>(self, ray, q, stats);
    }
}

impl<P: Primitive> leaf::CellWalk for HGrid<P> {
    #[inline(always)]
    fn prim_count(&self) -> usize {
        self.prims.len()
    }

    /// The nested walk.
    #[inline(always)]
    fn walk<Q: RayQuery, S: Stats, M: Seen>(
        &self,
        ray: &Ray,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) {
        // An empty structure walks nothing (`walk_once` has already turned away invalid rays).
        if self.refs.is_empty() {
            return;
        }
        let top = &self.levels[0];
        let Some((t0, t1)) = top.shape.bounds().intersect(ray, q.t_far()) else {
            return;
        };
        let r = RayAxes::new(ray);
        let start = Walk {
            level: 0,
            dda: Dda::start(&top.shape, &r, t0),
            t_enter: t0,
            visited: false,
        };
        let mut stack = [start; MAX_LEVELS];
        let mut sp = 1;
        // A query that wants each hit once is remembered exactly, whatever the ablation says.
        let dedupe = self.mailbox || !Q::REPEATABLE;
        let mut test = |ids: &[u32], q: &mut Q, stats: &mut S| {
            leaf::test_primitives(&self.prims, ids, ray, q, seen, dedupe, stats).is_break()
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
                if test(&self.refs[cell.references()], q, stats) {
                    trace::report(stats, || Event::Note("the query ends the walk: done"));
                    break;
                }
            }
            let (a, t_exit) = w.dda.exit();
            if t_exit > q.t_far() * SLAB_FAR_SCALE || t_exit > t1 {
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
                if test(ids, q, stats) {
                    return;
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
    }
}

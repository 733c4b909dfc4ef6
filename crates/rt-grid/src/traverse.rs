//! The uniform grid's walk: [`Dda`] through the cells, testing each cell's primitives.
//!
//! The walk offers its query each hit and stops once the next cell starts beyond the query's
//! far end (for a closest hit, the best hit so far): a
//! primitive spanning several cells may be hit beyond the current cell while a closer one waits
//! in the next. Where two boundaries are crossed within rounding of each other (the ray passes
//! next to a cell edge or corner), the cells beside the path are tested too, as the kd-tree
//! visits both children of a plane it meets at an interval's end.

use crate::Grid;
use crate::dda::{Dda, RayAxes};
use rt_core::leaf::{self, Seen};
use rt_core::trace::{self, Event, Place};
use rt_core::{Primitive, Ray, RayQuery, SLAB_FAR_SCALE, Stats};
use std::ops::ControlFlow;

/// Mailbox slots per ray: the last this many primitives tested are not tested again.
pub(crate) const MAILBOX: usize = 8;

impl<P: Primitive> Grid<P> {
    /// Tests the primitives of cell `c` against `[ray.t_min, q.t_far()]`, offering `q` the
    /// hits; `Break` when the query ends the walk.
    #[inline(always)]
    fn test_cell<S: Stats, Q: RayQuery, M: Seen>(
        &self,
        c: [u32; 3],
        ray: &Ray,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) -> ControlFlow<()> {
        let i = self.shape.index(c);
        let ids = &self.refs[self.cells[i] as usize..self.cells[i + 1] as usize];
        // A query that wants each hit once is remembered exactly, whatever the ablation says.
        let dedupe = self.mailbox || !Q::REPEATABLE;
        leaf::test_primitives(&self.prims, ids, ray, q, seen, dedupe, stats)
    }

    /// The walk for query `q`, with the record of tested primitives its query needs
    /// ([`leaf::walk_once`]: a mailbox of the last [`MAILBOX`], or every one).
    #[inline(always)]
    pub(crate) fn query<S: Stats, Q: RayQuery>(&self, ray: &Ray, q: &mut Q, stats: &mut S) {
        leaf::walk_once::<_, MAILBOX, Q, S>(self, ray, q, stats);
    }
}

impl<P: Primitive> leaf::CellWalk for Grid<P> {
    #[inline(always)]
    fn prim_count(&self) -> usize {
        self.prims.len()
    }

    /// The DDA walk.
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
        let shape = &self.shape;
        let Some((t0, t1)) = shape.bounds().intersect(ray, q.t_far()) else {
            return;
        };
        let r = RayAxes::new(ray);
        let mut dda = Dda::start(shape, &r, t0);
        // Only the trace reads where the ray enters the current cell.
        let mut t_enter = t0;
        let enter = |cell: [u32; 3], t0: f32, t1: f32| Event::Enter {
            place: Place::Cell { grid: 0, cell },
            t0,
            t1,
            bounds: Some(shape.cell_box(cell)),
        };
        loop {
            stats.node_visit();
            trace::report(stats, || enter(dda.cell, t_enter, dda.exit().1.min(t1)));
            if self.test_cell(dda.cell, ray, q, seen, stats).is_break() {
                trace::report(stats, || Event::Note("the query ends the walk: done"));
                break;
            }
            let (a, t_exit) = dda.exit();
            if t_exit > q.t_far() * SLAB_FAR_SCALE || t_exit > t1 {
                trace::report(stats, || {
                    Event::Note(if t_exit > t1 {
                        "the ray leaves the grid: done"
                    } else {
                        "the next cell starts beyond the best hit: done"
                    })
                });
                break;
            }
            for c in dda.side_cells(shape, &r, a) {
                stats.node_visit();
                trace::report(stats, || {
                    Event::Note("two planes crossed within rounding: the cell beside the path too")
                });
                trace::report(stats, || enter(c, t_exit, t_exit));
                if self.test_cell(c, ray, q, seen, stats).is_break() {
                    return;
                }
            }
            if !dda.step(shape, &r, a) {
                trace::report(stats, || Event::Note("the ray leaves the grid: done"));
                break;
            }
            t_enter = t_exit;
        }
    }
}

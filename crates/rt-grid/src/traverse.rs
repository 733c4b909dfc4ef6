//! The uniform grid's walk: [`Dda`] through the cells, testing each cell's primitives.
//!
//! The walk keeps the best hit found so far and stops once the next cell starts beyond it: a
//! primitive spanning several cells may be hit beyond the current cell while a closer one waits
//! in the next. Where two boundaries are crossed within rounding of each other (the ray passes
//! next to a cell edge or corner), the cells beside the path are tested too, as the kd-tree
//! visits both children of a plane it meets at an interval's end.

use crate::Grid;
use crate::dda::{Dda, RayAxes};
use rt_core::trace::{self, Event, Place};
use rt_core::{Hit, Mailbox, Primitive, Ray, SLAB_FAR_SCALE, Stats, leaf};

/// Mailbox slots per ray: the last this many primitives tested are not tested again.
pub(crate) const MAILBOX: usize = 8;

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
        // Outside the precondition (NaN, huge origins, ...): answer at once, walk nothing.
        if self.refs.is_empty() || !ray.is_valid() {
            return None;
        }
        let shape = &self.shape;
        let (t0, t1) = shape.bounds().intersect(ray, ray.t_max)?;
        let r = RayAxes::new(ray);
        let mut dda = Dda::start(shape, &r, t0);
        let mut best = leaf::no_hit(ray.t_max);
        let mut mailbox = Mailbox::new();
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
            if self.test_cell::<S, ANY>(dda.cell, ray, &mut best, &mut mailbox, stats) {
                trace::report(stats, || Event::Note("a primitive blocks the ray: done"));
                break;
            }
            let (a, t_exit) = dda.exit();
            if t_exit > best.t * SLAB_FAR_SCALE || t_exit > t1 {
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
                if self.test_cell::<S, ANY>(c, ray, &mut best, &mut mailbox, stats) {
                    return leaf::answer::<ANY>(best);
                }
            }
            if !dda.step(shape, &r, a) {
                trace::report(stats, || Event::Note("the ray leaves the grid: done"));
                break;
            }
            t_enter = t_exit;
        }
        leaf::answer::<ANY>(best)
    }
}

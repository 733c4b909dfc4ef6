//! Bundles through the hierarchy: `rt-grid`'s coherent grid traversal
//! ([`rt_grid::bundle::walk_slices`]) on the top grid and, at a cell that holds a nested grid,
//! on that grid, with the lanes that cross the cell's slice, recursively.
//!
//! Exact as the uniform grid's walk is, level by level: a nested walk covers every cell its
//! lanes' lines meet inside the nested grid, from one slice before each lane's first cell. A
//! lane whose slab test misses the nested grid's box (it grazes the parent cell) is tested
//! against the parent cell's whole list instead, as the single walk tests a parent cell it
//! passes beside. One mailbox serves the whole bundle, over all levels.

use crate::HGrid;
use rt_core::{Hit, Primitive, Ray, Stats};
use rt_grid::bundle::{coherent, walk_slices};
use rt_simd::bundle::{Bundle, LaneMailbox, Lanes, test_primitives};

impl<P: Primitive> HGrid<P> {
    /// The bundle queries, as the uniform grid's ([`walk_groups`](rt_simd::bundle::walk_groups)):
    /// each coherent bundle walked level by level, every other ray walked alone. Calls
    /// `answer(slot, hit)` for each of the first `slots` rays (for `ANY`, `Some` when the ray is
    /// blocked).
    pub(crate) fn bundle_query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        order: Option<&[u32]>,
        stats: &mut S,
        answer: impl FnMut(usize, Option<Hit>),
    ) {
        let top = &self.levels[0].shape;
        rt_simd::bundle::walk_groups_ordered::<S, ANY>(
            rays,
            slots,
            order,
            stats,
            |ray, stats| rt_simd::bundle::single::<_, S, ANY>(self, ray, stats),
            |b| b.route(&top.bounds(), |b| !self.refs.is_empty() && coherent(top, b)),
            // Inlined, so that the walk is compiled with the vector instructions `walk_groups` runs
            // with (`Isa::run`).
            #[inline(always)]
            |b, lanes, stats| {
                let mut mailbox = LaneMailbox::new();
                let mut alone = 0;
                let walking = b.all_lanes();
                let walked =
                    self.level::<S, ANY>(0, (b, walking), lanes, &mut mailbox, &mut alone, stats);
                alone | walked.alone
            },
            answer,
        );
    }

    /// Walks the lanes `walking` of bundle `b` through grid `level`, recursing into nested
    /// grids; lanes a nested walk leaves to single rays are added to `alone` (and leave the
    /// walks above).
    fn level<S: Stats, const ANY: bool>(
        &self,
        level: usize,
        (b, walking): (&Bundle, u64),
        lanes: &mut Lanes,
        mailbox: &mut LaneMailbox,
        alone: &mut u64,
        stats: &mut S,
    ) -> rt_grid::bundle::Walked {
        let l = &self.levels[level];
        walk_slices(&l.shape, b, lanes, walking, |lanes, c, lanes_in, t_hi| {
            stats.node_visit();
            stats.bundle_lanes(b.len() as u32, lanes_in.count_ones());
            let cell = self.cells[l.first_cell + l.shape.index(c)];
            let Some(nested) = cell.nested() else {
                let ids = &self.refs[cell.references()];
                return test_primitives::<P, S, ANY>(
                    &self.prims,
                    ids,
                    (b, t_hi),
                    lanes,
                    lanes_in,
                    mailbox,
                    stats,
                );
            };
            let walked = self.level::<S, ANY>(nested, (b, lanes_in), lanes, mailbox, alone, stats);
            *alone |= walked.alone;
            let mut leave = walked.alone;
            let grazing = match walked.missed {
                0 => 0,
                missed => passing_by(b, &l.shape.cell_box(c), missed),
            };
            if grazing != 0 {
                // Lanes that graze the cell: its whole list, as the single walk tests a parent
                // cell beside its path.
                let (lo, hi) = self.levels[nested].all;
                let ids = &self.refs[lo..hi];
                leave |= test_primitives::<P, S, ANY>(
                    &self.prims,
                    ids,
                    (b, t_hi),
                    lanes,
                    grazing,
                    mailbox,
                    stats,
                );
            }
            if ANY {
                // Blocked lanes in the nested walk hold a primitive now.
                let mut m = lanes_in;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if lanes.hit(i).is_some() {
                        leave |= 1 << i;
                    }
                }
            }
            leave
        })
    }
}

/// The lanes of `mask` whose lines pass within rounding of `cell`: those a single walk may
/// test the cell for (as a cell of its path, or one beside it).
///
/// The walk above hands a nested grid every lane that crosses the slice, and most of those
/// that miss the nested grid's box pass nowhere near its cell; testing them against its whole
/// list cost shadow rays on the sphereflake seven times the single rays' tests. A single walk
/// tests a cell beside its path only where it crosses two of the cell's planes within
/// [`NEAR_TIE`](rt_core::NEAR_TIE) (a relative `2⁻²⁰`) of each other, so the line's slab
/// interval through the cell, computed with the walk's own arithmetic (`(plane - o) · inv`), is
/// empty by at most that much. This keeps every lane whose interval is empty by less than
/// `2⁻⁸` of its ends' size, thousands of times that, and every lane whose arithmetic gives NaN.
fn passing_by(b: &Bundle, cell: &rt_core::Aabb, mask: u64) -> u64 {
    let mut near = 0;
    let mut m = mask;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let (mut t0, mut t1, mut nan) = (f32::NEG_INFINITY, f32::INFINITY, false);
        for a in 0..3 {
            let (lo, hi) = (cell.min[a], cell.max[a]);
            let (o, inv) = (b.origin[a][i], b.inv_dir[a][i]);
            let (ta, tb) = ((lo - o) * inv, (hi - o) * inv);
            nan |= ta.is_nan() || tb.is_nan();
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        let margin = (t0.abs() + t1.abs()) * (1.0 / 256.0);
        if nan || t0 <= t1 + margin {
            near |= 1 << i;
        }
    }
    near
}

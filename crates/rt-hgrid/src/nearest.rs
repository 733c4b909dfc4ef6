//! Ball queries (closest point): shells of cells around the centre, level by level.

use crate::HGrid;
use crate::traverse::MAILBOX;
use rt_core::{BallQuery, Mailbox, Primitive, Stats};
use rt_grid::nearest::shells;

impl<P: Primitive> HGrid<P> {
    /// The ball query: the top grid's cells in growing shells around the centre
    /// ([`shells`]); a cell with a nested grid is searched the same way, from the point of its
    /// box nearest the centre, before the shell goes on. The recursion is as deep as the
    /// hierarchy (at most [`MAX_LEVELS`](crate::MAX_LEVELS)).
    pub(crate) fn ball<Q: BallQuery<P>, S: Stats>(&self, q: &mut Q, stats: &mut S) {
        if self.refs.is_empty() {
            return;
        }
        let mut mailbox = Mailbox::<MAILBOX>::new();
        self.ball_level(0, q, stats, &mut mailbox);
    }

    fn ball_level<Q: BallQuery<P>, S: Stats>(
        &self,
        level: usize,
        q: &mut Q,
        stats: &mut S,
        mailbox: &mut Mailbox<MAILBOX>,
    ) {
        let grid = &self.levels[level];
        shells(&grid.shape, q, |q, c, _| {
            stats.node_visit();
            let cell = self.cells[grid.first_cell + grid.shape.index(c)];
            if let Some(nested) = cell.nested() {
                self.ball_level(nested, q, stats, mailbox);
                return;
            }
            for &id in &self.refs[cell.references()] {
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

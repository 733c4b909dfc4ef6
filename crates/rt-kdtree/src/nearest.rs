//! Ball queries (closest point): near side first, the far side only while the ball reaches it.

use crate::{KdTree, MAX_DEPTH};
use rt_core::{Aabb, BallQuery, Mailbox, Primitive, Stack, Stats};

/// Mailbox slots per query: a primitive listed in several leaves is offered once.
const MAILBOX: usize = 8;

impl<P: Primitive> KdTree<P> {
    /// The ball query. Each stack entry carries its node's cell (cut from the scene box by the
    /// splits above it) and that cell's distance from the centre; at an interior node the half
    /// nearer the centre is visited next and the other pushed if the ball reaches it, and a
    /// popped cell is skipped when the ball has shrunk below it. One entry per level.
    pub(crate) fn ball<Q: BallQuery<P>, S: Stats>(&self, q: &mut Q, stats: &mut S) {
        let c = q.center();
        if self.refs.is_empty() || self.bounds.distance_squared(c) > q.radius_sq() {
            return;
        }
        let mut mailbox = Mailbox::<MAILBOX>::new();
        let mut stack = Stack::<(u32, Aabb, f32), MAX_DEPTH>::new();
        let (mut current, mut cell) = (0usize, self.bounds);
        loop {
            stats.node_visit();
            let node = &self.nodes[current];
            if node.is_leaf() {
                let first = node.index();
                for &id in &self.refs[first..first + node.count()] {
                    if mailbox.check_and_insert(id) {
                        stats.mailbox_skip();
                        continue;
                    }
                    stats.prim_test();
                    q.test(&self.prims[id as usize], id);
                }
            } else {
                let (a, split, first) = (node.axis(), node.split(), node.index());
                let (mut lower, mut upper) = (cell, cell);
                lower.max[a] = split;
                upper.min[a] = split;
                let (dl, du) = (lower.distance_squared(c), upper.distance_squared(c));
                let ((near, near_cell, dn), (far, far_cell, df)) = if dl <= du {
                    ((first, lower, dl), (first + 1, upper, du))
                } else {
                    ((first + 1, upper, du), (first, lower, dl))
                };
                let r = q.radius_sq();
                if dn <= r {
                    if df <= r {
                        stack.push((far as u32, far_cell, df));
                    }
                    (current, cell) = (near, near_cell);
                    continue;
                }
            }
            loop {
                let Some((index, popped, d)) = stack.pop() else {
                    return;
                };
                if d <= q.radius_sq() {
                    (current, cell) = (index as usize, popped);
                    break;
                }
            }
        }
    }
}

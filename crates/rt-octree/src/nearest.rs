//! Ball queries (closest point): nearest child first, pruned by the shrinking radius.

use crate::Octree;
use crate::builder::MAX_DEPTH;
use crate::node::{Node, child_box, midpoint};
use crate::traverse::MAILBOX;
use rt_core::{Aabb, BallQuery, Mailbox, Primitive, Stats};

/// Stack entries: each level pushes at most seven siblings.
const STACK: usize = 7 * (MAX_DEPTH as usize + 1);

impl<P: Primitive> Octree<P> {
    /// The ball query. At an interior node the children whose boxes (cut at the same midpoints
    /// the builder used) meet the ball are sorted by distance from the centre; the nearest is
    /// visited next and the others pushed farthest first, each skipped when popped if the ball
    /// has shrunk below it.
    pub(crate) fn ball<Q: BallQuery<P>, S: Stats>(&self, q: &mut Q, stats: &mut S) {
        let c = q.center();
        if self.refs.is_empty() || self.bounds.distance_squared(c) > q.radius_sq() {
            return;
        }
        let mut mailbox = Mailbox::<MAILBOX>::new();
        let mut stack = [(Node::leaf(0, 0), Aabb::EMPTY, 0.0f32); STACK];
        let mut sp = 0;
        let (mut node, mut cell) = (self.root, self.bounds);
        loop {
            stats.node_visit();
            if let Some(block) = node.children() {
                let mid = midpoint(&cell);
                let r = q.radius_sq();
                // The children in the ball, nearest first (insertion sort of at most eight).
                let mut order = [(Node::leaf(0, 0), Aabb::EMPTY, 0.0f32); 8];
                let mut n = 0;
                for (i, &child) in self.blocks[block].0.iter().enumerate() {
                    if child.is_empty_leaf() {
                        continue;
                    }
                    let b = child_box(&cell, mid, i);
                    let d = b.distance_squared(c);
                    if d <= r {
                        let mut k = n;
                        while k > 0 && order[k - 1].2 > d {
                            order[k] = order[k - 1];
                            k -= 1;
                        }
                        order[k] = (child, b, d);
                        n += 1;
                    }
                }
                if n > 0 {
                    for &entry in order[1..n].iter().rev() {
                        stack[sp] = entry;
                        sp += 1;
                    }
                    (node, cell) = (order[0].0, order[0].1);
                    continue;
                }
            } else {
                for &id in &self.refs[node.references()] {
                    if self.mailbox && mailbox.check_and_insert(id) {
                        stats.mailbox_skip();
                        continue;
                    }
                    stats.prim_test();
                    q.test(&self.prims[id as usize], id);
                }
            }
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let (popped, b, d) = stack[sp];
                if d <= q.radius_sq() {
                    (node, cell) = (popped, b);
                    break;
                }
            }
        }
    }
}

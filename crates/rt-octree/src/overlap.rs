//! Box queries (box overlap): every octant that meets the query box.

use crate::Octree;
use crate::builder::MAX_DEPTH;
use crate::node::{Node, child_box, midpoint};
use rt_core::{Aabb, BoxQuery, Primitive, Stats, Visited, leaf};
use std::ops::ControlFlow;

/// Stack entries: each level pushes at most seven siblings.
const STACK: usize = 7 * (MAX_DEPTH as usize + 1);

impl<P: Primitive> Octree<P> {
    /// The box query. At an interior node the children whose boxes (cut at the same midpoints
    /// the builder used) meet the query box are visited in octant order: the first next, the
    /// others pushed. Each primitive is offered once, however many leaves list it ([`Visited`]).
    pub(crate) fn box_cells<Q: BoxQuery<P>, S: Stats>(
        &self,
        q: &mut Q,
        stats: &mut S,
    ) -> ControlFlow<()> {
        let b = q.bounds();
        if self.refs.is_empty() || b.is_empty() || !self.bounds.overlaps(&b) {
            return ControlFlow::Continue(());
        }
        Visited::with(self.prims.len(), |seen| {
            let mut stack = [(Node::leaf(0, 0), Aabb::EMPTY); STACK];
            let mut sp = 0;
            let (mut node, mut cell) = (self.root, self.bounds);
            loop {
                stats.node_visit();
                if let Some(block) = node.children() {
                    let mid = midpoint(&cell);
                    let mut next = None;
                    for (i, &child) in self.blocks[block].0.iter().enumerate().rev() {
                        let cb = child_box(&cell, mid, i);
                        if child.is_empty_leaf() || !cb.overlaps(&b) {
                            continue;
                        }
                        // Pushed highest octant first; the lowest that meets the box is kept.
                        if let Some(pending) = next.replace((child, cb)) {
                            stack[sp] = pending;
                            sp += 1;
                        }
                    }
                    if let Some(first) = next {
                        (node, cell) = first;
                        continue;
                    }
                } else {
                    leaf::offer_once(&self.prims, &self.refs[node.references()], seen, q, stats)?;
                }
                if sp == 0 {
                    return ControlFlow::Continue(());
                }
                sp -= 1;
                (node, cell) = stack[sp];
            }
        })
    }
}

//! Box queries (box overlap): every cell that meets the query box.

use crate::{KdTree, MAX_DEPTH};
use rt_core::{BoxQuery, Primitive, Stack, Stats, Visited, leaf};
use std::ops::ControlFlow;

impl<P: Primitive> KdTree<P> {
    /// The box query. At an interior node the lower half is visited when the query box reaches
    /// below the split plane and the upper half when it reaches above it (both when the box
    /// touches the plane: cells are closed); the upper is pushed when both are. One stack entry
    /// per level. Each primitive is offered once, however many leaves list it ([`Visited`]).
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
            let mut stack = Stack::<u32, MAX_DEPTH>::new();
            let mut current = 0usize;
            loop {
                stats.node_visit();
                let node = &self.nodes[current];
                if node.is_leaf() {
                    let ids = &self.refs[node.index()..node.index() + node.count()];
                    leaf::offer_once(&self.prims, ids, seen, q, stats)?;
                } else {
                    let (a, split, first) = (node.axis(), node.split(), node.index());
                    match (b.min[a] <= split, b.max[a] >= split) {
                        (true, upper) => {
                            if upper {
                                stack.push(first as u32 + 1);
                            }
                            current = first;
                            continue;
                        }
                        (false, true) => {
                            current = first + 1;
                            continue;
                        }
                        (false, false) => {}
                    }
                }
                let Some(next) = stack.pop() else {
                    return ControlFlow::Continue(());
                };
                current = next as usize;
            }
        })
    }
}

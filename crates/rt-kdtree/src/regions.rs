//! The tree's cells and split planes as [`Region`]s, for drawings of the structure.

use crate::KdTree;
use rt_core::{Primitive, Region};

impl<P: Primitive> KdTree<P> {
    /// Every node, root first, depth first (see [`rt_core::Accel::regions`]): an interior node
    /// with its split plane, a leaf with its reference count; each with the box the splits
    /// above it cut out of the root's.
    pub(crate) fn walk_regions(&self, visit: &mut dyn FnMut(Region)) {
        if self.nodes.is_empty() || self.bounds.is_empty() {
            return;
        }
        let mut stack = vec![(0usize, self.bounds, 0u32)];
        while let Some((i, bounds, depth)) = stack.pop() {
            let node = self.nodes[i];
            if node.is_leaf() {
                visit(Region {
                    bounds,
                    depth,
                    prims: Some(node.count() as u32),
                    split: None,
                });
                continue;
            }
            let (axis, pos) = (node.axis(), node.split());
            visit(Region {
                bounds,
                depth,
                prims: None,
                split: Some((axis, pos)),
            });
            let (mut below, mut above) = (bounds, bounds);
            below.max[axis] = pos;
            above.min[axis] = pos;
            stack.push((node.index() + 1, above, depth + 1));
            stack.push((node.index(), below, depth + 1));
        }
    }
}

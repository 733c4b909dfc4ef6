//! The octree's nodes as [`Region`]s, for drawings of the structure.

use crate::{Octree, node};
use rt_core::Region;

impl<P> Octree<P> {
    /// Every node, root first, depth first (see [`rt_core::Accel::regions`]): a leaf with its
    /// reference count, an interior node without.
    pub(crate) fn walk_regions(&self, visit: &mut dyn FnMut(Region)) {
        if self.bounds.is_empty() {
            return;
        }
        let mut todo = vec![(self.root, self.bounds, 0u32)];
        while let Some((n, b, depth)) = todo.pop() {
            let children = n.children();
            visit(Region {
                bounds: b,
                depth,
                prims: children.is_none().then(|| n.references().len() as u32),
                split: None,
            });
            if let Some(block) = children {
                let mid = node::midpoint(&b);
                for (i, &c) in self.blocks[block].0.iter().enumerate().rev() {
                    todo.push((c, node::child_box(&b, mid, i), depth + 1));
                }
            }
        }
    }
}

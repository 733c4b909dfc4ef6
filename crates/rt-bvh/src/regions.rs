//! The tree's boxes as [`Region`]s, for drawings of the structure.

use crate::{Bvh, Layout, MAX_DEPTH};
use rt_core::{Aabb, Primitive, Region};

impl<P: Primitive> Bvh<P> {
    /// Every node's box, root first, depth first (see [`rt_core::Accel::regions`]). In the
    /// wide layout the regions are the child boxes a wide node tests (a wide node itself has no
    /// box; the root's region is the union of its children's), each leaf a region of its own at
    /// its parent's depth plus one. So the SAH prediction (`rt_core::predicted_cost`) counts box
    /// entries, while the measured visits of the wide layout count 8-wide nodes and leaves.
    pub(crate) fn walk_regions(&self, visit: &mut dyn FnMut(Region)) {
        match self.layout() {
            Layout::Binary => {
                if self.valid == 0 {
                    return;
                }
                let mut stack = vec![(0usize, 0u32)];
                while let Some((i, depth)) = stack.pop() {
                    let node = &self.nodes()[i];
                    let leaf = node.is_leaf();
                    visit(Region {
                        bounds: node.bounds,
                        depth,
                        prims: leaf.then_some(node.count as u32),
                        split: None,
                    });
                    if !leaf && (depth as usize) < MAX_DEPTH {
                        stack.push((node.index as usize, depth + 1));
                        stack.push((i + 1, depth + 1));
                    }
                }
            }
            Layout::Wide => {
                let Some(root) = self.wide_nodes().first() else {
                    return;
                };
                let bounds = (0..8).fold(Aabb::EMPTY, |b, k| {
                    if root.child(k).0 == crate::ChildRef::EMPTY.0 {
                        b
                    } else {
                        b.union(root.child_bounds(k))
                    }
                });
                visit(Region {
                    bounds,
                    depth: 0,
                    prims: None,
                    split: None,
                });
                let mut stack = vec![(0usize, 1u32)];
                while let Some((i, depth)) = stack.pop() {
                    let node = &self.wide_nodes()[i];
                    for k in 0..8 {
                        let child = node.child(k);
                        if child.0 == crate::ChildRef::EMPTY.0 {
                            continue;
                        }
                        let prims = child.is_leaf().then(|| {
                            let items = child.items();
                            if self.packs().is_empty() {
                                items.len() as u32
                            } else {
                                self.packs()[items].iter().map(|p| p.len() as u32).sum()
                            }
                        });
                        visit(Region {
                            bounds: node.child_bounds(k),
                            depth,
                            prims,
                            split: None,
                        });
                        if !child.is_leaf() && (depth as usize) < MAX_DEPTH {
                            stack.push((child.index(), depth + 1));
                        }
                    }
                }
            }
        }
    }
}

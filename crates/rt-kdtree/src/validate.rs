//! Structural checks of a built tree.

use crate::{KdTree, MAX_DEPTH};
use rt_core::{Aabb, Primitive};
use std::fmt;

/// What [`KdTree::validate`] found wrong, and at which node.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ValidationError {
    /// The offending node's index.
    pub node: usize,
    /// What is wrong with it.
    pub message: String,
}

impl fmt::Display for ValidationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "kd-tree node {}: {}", self.node, self.message)
    }
}

impl std::error::Error for ValidationError {}

impl<P: Primitive> KdTree<P> {
    /// Checks the tree's invariants, for tests and for students' builders:
    /// - every node is reached exactly once from the root (a tree, no cycles, no orphans), and
    ///   the depth is at most [`MAX_DEPTH`];
    /// - every split plane lies strictly inside its node's cell;
    /// - every leaf's references are in bounds and name valid primitives that overlap the leaf's
    ///   cell;
    /// - every valid primitive is referenced by at least one leaf;
    /// - the counts reported by `build_stats` match the tree.
    pub fn validate(&self) -> Result<(), ValidationError> {
        let err = |node: usize, message: String| Err(ValidationError { node, message });
        let n = self.nodes.len();
        if n == 0 {
            return err(0, "no root".into());
        }
        let mut seen = vec![false; n];
        let mut referenced = vec![false; self.prims.len()];
        let (mut leaves, mut empty, mut depth_max) = (0, 0, 0);
        let mut stack = vec![(0usize, self.bounds, 0usize)];
        while let Some((i, cell, depth)) = stack.pop() {
            if std::mem::replace(&mut seen[i], true) {
                return err(i, "reached twice".into());
            }
            if depth > MAX_DEPTH {
                return err(i, format!("depth {depth} exceeds {MAX_DEPTH}"));
            }
            depth_max = depth_max.max(depth);
            let node = &self.nodes[i];
            if node.is_leaf() {
                leaves += 1;
                let range = node.index()..node.index() + node.count();
                let Some(refs) = self.refs.get(range.clone()) else {
                    return err(i, format!("references {range:?} out of bounds"));
                };
                empty += usize::from(refs.is_empty());
                for &id in refs {
                    let Some(p) = self.prims.get(id as usize).filter(|p| p.is_valid()) else {
                        return err(i, format!("reference to missing or invalid primitive {id}"));
                    };
                    if !p.bounds().overlaps(&cell) {
                        return err(
                            i,
                            format!("primitive {id} does not overlap the cell {cell:?}"),
                        );
                    }
                    referenced[id as usize] = true;
                }
                continue;
            }
            let (a, s, c) = (node.axis(), node.split(), node.index());
            if !(cell.min[a] < s && s < cell.max[a]) {
                return err(
                    i,
                    format!("split {s} on axis {a} not inside the cell {cell:?}"),
                );
            }
            if c + 1 >= n || c <= i {
                return err(i, format!("children {c}, {} out of order or bounds", c + 1));
            }
            let (mut l, mut r): (Aabb, Aabb) = (cell, cell);
            l.max[a] = s;
            r.min[a] = s;
            stack.push((c + 1, r, depth + 1));
            stack.push((c, l, depth + 1));
        }
        if let Some(orphan) = seen.iter().position(|&s| !s) {
            return err(orphan, "not reachable from the root".into());
        }
        if let Some(id) =
            (0..self.prims.len()).find(|&id| self.prims[id].is_valid() && !referenced[id])
        {
            return err(0, format!("valid primitive {id} is in no leaf"));
        }
        if (leaves, empty, depth_max) != (self.leaves, self.empty_leaves, self.max_depth) {
            return err(
                0,
                format!(
                    "stats say {} leaves, {} empty, depth {}; the tree has {leaves}, {empty}, {depth_max}",
                    self.leaves, self.empty_leaves, self.max_depth
                ),
            );
        }
        Ok(())
    }
}

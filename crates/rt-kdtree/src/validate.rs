//! Structural checks of a built tree.

use crate::{KdTree, MAX_DEPTH};
use rt_core::{Aabb, Primitive, ValidationError};

impl<P: Primitive> KdTree<P> {
    /// Checks the tree's invariants, for tests and for students' builders:
    /// - every node is reached exactly once from the root (a tree, no cycles, no orphans), and
    ///   the depth is at most [`MAX_DEPTH`];
    /// - every split plane lies strictly inside its node's cell;
    /// - every leaf's references are in bounds and name valid primitives that overlap the leaf's
    ///   cell;
    /// - every valid primitive is referenced by at least one leaf;
    /// - the counts reported by `build_stats` match the tree and the primitives.
    pub fn validate(&self) -> Result<(), ValidationError> {
        let err = |node: usize, message: String| Err(ValidationError::at(node, message));
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
        let valid = self.prims.iter().filter(|p| p.is_valid()).count();
        if valid != self.valid_prims {
            return err(
                0,
                format!(
                    "stats say {} valid primitives; there are {valid}",
                    self.valid_prims
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::{KdParams, KdTree, Node};
    use rt_core::{Accel, Triangle};
    use rt_scene::scenes;

    fn tree() -> KdTree<Triangle> {
        KdTree::build(&scenes::random_soup(500, 1).triangles(), &KdParams::sah())
    }

    fn message(t: &KdTree<Triangle>) -> String {
        t.validate()
            .expect_err("the corruption must be caught")
            .message
    }

    /// `validate` accepts a built tree and rejects each kind of corruption it claims to detect.
    #[test]
    fn detects_each_broken_invariant() {
        assert_eq!(tree().validate(), Ok(()));
        let interior = |t: &KdTree<Triangle>| t.nodes.iter().position(|n| !n.is_leaf()).unwrap();
        let full_leaf = |t: &KdTree<Triangle>| {
            t.nodes
                .iter()
                .position(|n| n.is_leaf() && n.count() > 0)
                .unwrap()
        };

        // A split plane outside its cell.
        let mut t = tree();
        let i = interior(&t);
        let n = t.nodes[i];
        t.nodes[i] = Node::interior(n.axis(), t.bounds.max[n.axis()] + 1.0, n.index());
        assert!(message(&t).contains("not inside the cell"));

        // A child pointing back at the root: a cycle.
        let mut t = tree();
        t.nodes[0] = Node::interior(t.nodes[0].axis(), t.nodes[0].split(), 0);
        assert!(message(&t).contains("out of order or bounds"));

        // A leaf whose references run past the list.
        let mut t = tree();
        let i = full_leaf(&t);
        t.nodes[i] = Node::leaf(t.refs.len(), 1);
        assert!(message(&t).contains("out of bounds"));

        // A reference to a primitive that does not exist.
        let mut t = tree();
        let i = full_leaf(&t);
        t.refs[t.nodes[i].index()] = 100_000;
        assert!(message(&t).contains("missing or invalid"));

        // A reference to a primitive far from the leaf's cell.
        let mut t = tree();
        t.prims[t.refs[0] as usize] = Triangle::new(
            rt_core::glam::Vec3::splat(1e6),
            rt_core::glam::Vec3::new(1e6 + 1.0, 1e6, 1e6),
            rt_core::glam::Vec3::new(1e6, 1e6 + 1.0, 1e6),
        );
        assert!(message(&t).contains("does not overlap"));

        // A primitive no leaf references: empty every leaf that holds primitive 0.
        let mut t = tree();
        for n in t.nodes.iter_mut() {
            if n.is_leaf() && t.refs[n.index()..n.index() + n.count()].contains(&0) {
                *n = Node::leaf(0, 0);
            }
        }
        assert!(message(&t).contains("is in no leaf"));

        // Statistics that do not match the tree.
        let mut t = tree();
        t.leaves += 1;
        assert!(message(&t).contains("stats say"));
    }
}

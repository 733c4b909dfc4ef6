//! Structural checks of a built tree.

use crate::{Bvh, MAX_DEPTH};
use rt_core::Primitive;
use std::fmt;

/// A broken invariant found by [`Bvh::validate`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ValidationError {
    /// The node where the invariant fails (`None` for whole-tree invariants).
    pub node: Option<usize>,
    /// Which invariant.
    pub message: String,
}

impl fmt::Display for ValidationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.node {
            Some(n) => write!(f, "node {n}: {}", self.message),
            None => write!(f, "{}", self.message),
        }
    }
}

impl std::error::Error for ValidationError {}

impl<P: Primitive> Bvh<P> {
    /// Checks the tree's invariants:
    /// - the nodes form one depth-first tree (first child right after its parent, second child
    ///   after the first child's subtree) no deeper than the traversal stack;
    /// - every kept primitive is in exactly one leaf, and the primitive ids are a permutation of
    ///   the valid input primitives;
    /// - every child box lies inside its parent's box, and every primitive's box inside its
    ///   leaf's box.
    ///
    /// # Errors
    /// The first broken invariant.
    pub fn validate(&self) -> Result<(), ValidationError> {
        let err = |node: Option<usize>, message: String| Err(ValidationError { node, message });
        let n = self.prims.len();
        if self.ids.len() != n {
            return err(None, format!("{} primitives but {} ids", n, self.ids.len()));
        }
        if n == 0 {
            return if self.nodes.len() == 1 {
                Ok(())
            } else {
                err(None, "empty tree with more than one node".into())
            };
        }
        let mut covered = vec![false; n];
        // (node, depth, expected end of its subtree is checked by the walk order)
        let mut stack = vec![(0usize, 0usize)];
        let mut next_expected = 0usize;
        while let Some((i, depth)) = stack.pop() {
            if i != next_expected {
                return err(
                    Some(i),
                    format!("not in depth-first order (expected node {next_expected})"),
                );
            }
            next_expected += 1;
            if depth >= MAX_DEPTH {
                return err(
                    Some(i),
                    format!("depth {depth} exceeds the traversal stack ({MAX_DEPTH})"),
                );
            }
            let node = self.nodes.get(i).ok_or(ValidationError {
                node: Some(i),
                message: "index out of range".into(),
            })?;
            if node.is_leaf() {
                let range = node.prim_range();
                if range.end > n {
                    return err(Some(i), format!("leaf range {range:?} past {n} primitives"));
                }
                for k in range {
                    if std::mem::replace(&mut covered[k], true) {
                        return err(Some(i), format!("primitive slot {k} is in two leaves"));
                    }
                    if !node.bounds.contains(&self.prims[k].bounds()) {
                        return err(
                            Some(i),
                            format!("primitive slot {k} sticks out of its leaf box"),
                        );
                    }
                }
            } else {
                let (a, b) = (i + 1, node.index as usize);
                if b <= a || b >= self.nodes.len() {
                    return err(Some(i), format!("second child {b} out of order or range"));
                }
                for c in [a, b] {
                    if !node.bounds.contains(&self.nodes[c].bounds) {
                        return err(
                            Some(i),
                            format!("child {c}'s box is not inside its parent's"),
                        );
                    }
                }
                stack.push((b, depth + 1));
                stack.push((a, depth + 1));
            }
        }
        if next_expected != self.nodes.len() {
            return err(
                None,
                format!("{} nodes reachable of {}", next_expected, self.nodes.len()),
            );
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return err(None, format!("primitive slot {k} is in no leaf"));
        }
        let mut ids = self.ids.clone();
        ids.sort_unstable();
        if ids.windows(2).any(|w| w[0] == w[1]) {
            return err(None, "a primitive id appears twice".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::{Bvh, BvhParams};
    use rt_core::{Accel, Triangle, scenes};

    fn tree() -> Bvh<Triangle> {
        Bvh::build(&scenes::random_soup(500, 1).triangles(), &BvhParams::sah())
    }

    /// `validate` accepts a built tree and rejects each kind of corruption it claims to detect.
    #[test]
    fn detects_each_broken_invariant() {
        assert_eq!(tree().validate(), Ok(()));

        let first_leaf = |b: &Bvh<Triangle>| b.nodes.iter().position(|n| n.is_leaf()).unwrap();
        let first_interior = |b: &Bvh<Triangle>| b.nodes.iter().position(|n| !n.is_leaf()).unwrap();

        let mut b = tree();
        let i = first_interior(&b);
        b.nodes[i].bounds.max.x -= 0.5;
        assert!(
            b.validate()
                .unwrap_err()
                .message
                .contains("not inside its parent")
        );

        let mut b = tree();
        let i = first_leaf(&b);
        b.nodes[i].bounds.min.y += 0.5;
        assert!(b.validate().is_err());

        let mut b = tree();
        let i = first_leaf(&b);
        b.nodes[i].index += 1; // overlaps the next leaf's first slot and drops its own
        assert!(b.validate().is_err());

        let mut b = tree();
        b.nodes[0].index = 0; // second child pointing backwards
        assert!(
            b.validate()
                .unwrap_err()
                .message
                .contains("out of order or range")
        );

        let mut b = tree();
        b.ids[3] = b.ids[4];
        assert!(b.validate().unwrap_err().message.contains("appears twice"));

        let mut b = tree();
        b.ids.pop();
        assert!(b.validate().is_err());
    }
}

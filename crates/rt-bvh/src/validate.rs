//! Structural checks of a built tree.

use crate::node::{ChildRef, TriPack, WIDTH};
use crate::{Bvh, Layout, MAX_DEPTH};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Primitive, TriangleTest, ValidationError};

impl<P: Primitive> Bvh<P> {
    /// Checks the tree's invariants.
    ///
    /// Binary layout:
    /// - the nodes form one depth-first tree (first child right after its parent, second child
    ///   after the first child's subtree) no deeper than the traversal stack;
    /// - every kept primitive is in exactly one leaf, and the primitive ids are distinct (as many
    ///   as the valid primitives but for bit-identical copies of a triangle, which are left out);
    /// - every child box lies inside its parent's box, and every primitive's box inside its
    ///   leaf's box.
    ///
    /// Wide layout:
    /// - every node is reached exactly once from the root, through children of higher index, no
    ///   deeper than the traversal stack; used lanes come first, unused ones hold the empty box;
    /// - each node's children's boxes lie inside the box its parent stores for it, and each
    ///   leaf's triangles (or primitives) inside the leaf's box;
    /// - every pack (or primitive slot) is in exactly one leaf; packs fill their lanes from the
    ///   first, unused lanes hold NaN; the triangle ids are distinct and as many as the valid
    ///   primitives but for bit-identical copies.
    ///
    /// # Errors
    /// The first broken invariant.
    pub fn validate(&self) -> Result<(), ValidationError> {
        match self.layout() {
            Layout::Binary => self.validate_binary(),
            Layout::Wide => self.validate_wide(),
        }
    }

    fn validate_binary(&self) -> Result<(), ValidationError> {
        let err = |node: Option<usize>, message: String| Err(ValidationError { node, message });
        let nodes = self.nodes();
        let n = self.primitives().len();
        if self.primitive_ids().len() != n {
            return err(
                None,
                format!("{} primitives but {} ids", n, self.primitive_ids().len()),
            );
        }
        if n == 0 {
            return if nodes.len() == 1 {
                Ok(())
            } else {
                err(None, "empty tree with more than one node".into())
            };
        }
        let mut covered = vec![false; n];
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
            let node = nodes.get(i).ok_or(ValidationError {
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
                    if !node.bounds.contains(&self.primitives()[k].bounds()) {
                        return err(
                            Some(i),
                            format!("primitive slot {k} sticks out of its leaf box"),
                        );
                    }
                }
            } else {
                let (a, b) = (i + 1, node.index as usize);
                if b <= a || b >= nodes.len() {
                    return err(Some(i), format!("second child {b} out of order or range"));
                }
                for c in [a, b] {
                    if !node.bounds.contains(&nodes[c].bounds) {
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
        if next_expected != nodes.len() {
            return err(
                None,
                format!("{} nodes reachable of {}", next_expected, nodes.len()),
            );
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return err(None, format!("primitive slot {k} is in no leaf"));
        }
        distinct_ids(
            self.primitive_ids().iter().copied(),
            self.stored,
            self.valid,
        )
    }

    fn validate_wide(&self) -> Result<(), ValidationError> {
        let err = |node: Option<usize>, message: String| Err(ValidationError { node, message });
        let nodes = self.wide_nodes();
        if nodes.is_empty() {
            return if self.valid == 0 && self.packs().is_empty() && self.primitives().is_empty() {
                Ok(())
            } else {
                err(None, "no nodes but primitives were kept".into())
            };
        }
        let packed = self.pack_test().is_some();
        let items = if packed {
            self.packs().len()
        } else {
            self.primitives().len()
        };
        if !packed && self.primitive_ids().len() != items {
            return err(
                None,
                format!("{items} primitives but {} ids", self.primitive_ids().len()),
            );
        }
        let mut reached = vec![false; nodes.len()];
        let mut covered = vec![false; items];
        // (node, depth, the box its parent stores for it; none for the root)
        let mut stack = vec![(0usize, 0usize, None::<Aabb>)];
        while let Some((i, depth, parent_box)) = stack.pop() {
            if std::mem::replace(&mut reached[i], true) {
                return err(Some(i), "reached twice".into());
            }
            if depth >= MAX_DEPTH {
                return err(
                    Some(i),
                    format!("depth {depth} exceeds the traversal stack ({MAX_DEPTH})"),
                );
            }
            let node = &nodes[i];
            let used = node
                .children
                .iter()
                .take_while(|&&c| c != ChildRef::EMPTY.0)
                .count();
            if used == 0 {
                return err(Some(i), "a node without children".into());
            }
            for lane in 0..WIDTH {
                let b = node.child_bounds(lane);
                if lane >= used {
                    if node.children[lane] != ChildRef::EMPTY.0
                        || b != Aabb::new(Vec3::INFINITY, Vec3::NEG_INFINITY)
                    {
                        return err(Some(i), format!("unused lane {lane} is not empty"));
                    }
                    continue;
                }
                if b.is_empty() {
                    return err(Some(i), format!("lane {lane} has an empty box"));
                }
                if let Some(p) = parent_box
                    && !p.contains(&b)
                {
                    return err(
                        Some(i),
                        format!("lane {lane}'s box is not inside its parent's"),
                    );
                }
                let c = node.child(lane);
                if !c.is_leaf() {
                    if c.index() <= i || c.index() >= nodes.len() {
                        return err(Some(i), format!("child node {} out of order", c.index()));
                    }
                    stack.push((c.index(), depth + 1, Some(b)));
                    continue;
                }
                let range = c.items();
                if range.end > items {
                    return err(Some(i), format!("leaf {range:?} past {items} items"));
                }
                for k in range {
                    if std::mem::replace(&mut covered[k], true) {
                        return err(Some(i), format!("item {k} is in two leaves"));
                    }
                    let boxes = if let Some(test) = self.pack_test() {
                        let pack = &self.packs()[k];
                        let n = pack.len();
                        if pack.ids[..n].contains(&u32::MAX)
                            || pack.rows.iter().any(|r| r[n..].iter().any(|x| !x.is_nan()))
                        {
                            return err(
                                Some(i),
                                format!("pack {k} has a gap or a filled unused lane"),
                            );
                        }
                        (0..n)
                            .map(|l| pack_triangle_bounds(pack, l, test))
                            .collect()
                    } else {
                        vec![self.primitives()[k].bounds()]
                    };
                    if boxes.iter().any(|t| !b.contains(t)) {
                        return err(Some(i), format!("item {k} sticks out of its leaf box"));
                    }
                }
            }
        }
        if let Some(k) = reached.iter().position(|r| !r) {
            return err(None, format!("node {k} is unreachable"));
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return err(None, format!("item {k} is in no leaf"));
        }
        if packed {
            let ids = self
                .packs()
                .iter()
                .flat_map(|p| p.ids.iter().copied().filter(|&id| id != u32::MAX));
            distinct_ids(ids, self.stored, self.valid)
        } else {
            distinct_ids(
                self.primitive_ids().iter().copied(),
                self.stored,
                self.valid,
            )
        }
    }
}

/// The box of the triangle in a pack's lane. Möller–Trumbore packs store edges, so the second
/// and third vertices are rebuilt as `v0 + e`, within a rounding of the input: the box is
/// widened by that much.
fn pack_triangle_bounds(pack: &TriPack, lane: usize, test: TriangleTest) -> Aabb {
    let b = pack.triangle(lane, test).bounds();
    match test {
        TriangleTest::Watertight => b,
        TriangleTest::MollerTrumbore => {
            let slack = b.min.abs().max(b.max.abs()) * (4.0 * f32::EPSILON);
            Aabb::new(b.min + slack, b.max - slack)
        }
    }
}

/// Checks that the ids are distinct and as many as the tree says it stores, no more than the
/// valid primitives.
fn distinct_ids(
    ids: impl Iterator<Item = u32>,
    stored: usize,
    valid: usize,
) -> Result<(), ValidationError> {
    let mut ids: Vec<u32> = ids.collect();
    if ids.len() != stored || stored > valid {
        return Err(ValidationError {
            node: None,
            message: format!(
                "{} ids for {stored} stored of {valid} valid primitives",
                ids.len()
            ),
        });
    }
    ids.sort_unstable();
    if ids.windows(2).any(|w| w[0] == w[1]) {
        return Err(ValidationError {
            node: None,
            message: "a primitive id appears twice".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::{Bvh, BvhParams, Node, Tree};
    use rt_core::{Accel, Triangle};
    use rt_scene::scenes;

    fn tree() -> Bvh<Triangle> {
        Bvh::build(&scenes::random_soup(500, 1).triangles(), &BvhParams::sah())
    }

    /// A binary tree's nodes and primitive ids, to break on purpose.
    fn parts(b: &mut Bvh<Triangle>) -> (&mut Vec<Node>, &mut Vec<u32>) {
        match &mut b.tree {
            Tree::Binary { nodes, items } => (nodes, &mut items.ids),
            Tree::Wide(_) => panic!("a binary tree"),
        }
    }

    /// `validate` accepts a built tree and rejects each kind of corruption it claims to detect.
    #[test]
    fn detects_each_broken_invariant() {
        assert_eq!(tree().validate(), Ok(()));

        let first_leaf = |b: &Bvh<Triangle>| b.nodes().iter().position(|n| n.is_leaf()).unwrap();
        let first_interior =
            |b: &Bvh<Triangle>| b.nodes().iter().position(|n| !n.is_leaf()).unwrap();

        let mut b = tree();
        let i = first_interior(&b);
        parts(&mut b).0[i].bounds.max.x -= 0.5;
        assert!(
            b.validate()
                .unwrap_err()
                .message
                .contains("not inside its parent")
        );

        let mut b = tree();
        let i = first_leaf(&b);
        parts(&mut b).0[i].bounds.min.y += 0.5;
        assert!(b.validate().is_err());

        let mut b = tree();
        let i = first_leaf(&b);
        parts(&mut b).0[i].index += 1; // overlaps the next leaf's first slot and drops its own
        assert!(b.validate().is_err());

        let mut b = tree();
        parts(&mut b).0[0].index = 0; // second child pointing backwards
        assert!(
            b.validate()
                .unwrap_err()
                .message
                .contains("out of order or range")
        );

        let mut b = tree();
        let ids = parts(&mut b).1;
        ids[3] = ids[4];
        assert!(b.validate().unwrap_err().message.contains("appears twice"));

        let mut b = tree();
        parts(&mut b).1.pop();
        assert!(b.validate().is_err());
    }
}

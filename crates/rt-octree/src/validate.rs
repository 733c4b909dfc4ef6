//! Structural checks: the invariants traversal relies on.

use crate::Octree;
use crate::builder::{Item, MAX_DEPTH, divisible, margin, split};
use crate::node::{Node, child_box, midpoint};
use rt_core::{Primitive, ValidationError};

impl<P: Primitive> Octree<P> {
    /// Checks the tree: every block referenced by exactly one interior node, no deeper than
    /// [`MAX_DEPTH`], only divisible boxes cut, reference ranges in bounds; the root box
    /// containing every valid primitive; and every leaf listing exactly the primitives of its
    /// parent's list that overlap its box (the builder's test, repeated from the root down), in
    /// increasing order. So no primitive is missing where a ray could hit it.
    pub fn validate(&self) -> Result<(), ValidationError> {
        let err = |s: String| Err(ValidationError::new(s));
        let valid: Vec<u32> = (0..self.prims.len() as u32)
            .filter(|&i| self.prims[i as usize].is_valid())
            .collect();
        if valid.len() != self.valid_prims {
            return err("the count of valid primitives is wrong".into());
        }
        let items: Vec<Item> = valid
            .iter()
            .map(|&id| Item {
                id,
                b: self.prims[id as usize].bounds().intersection(&self.bounds),
            })
            .collect();
        if let Some(i) = valid
            .iter()
            .find(|&&i| !self.bounds.contains(&self.prims[i as usize].bounds()))
        {
            return err(format!("the root box does not contain primitive {i}"));
        }
        let mut seen = vec![false; self.blocks.len()];
        let mut todo = vec![(self.root, self.bounds, 0u32, items)];
        let mut deepest = 0;
        while let Some((node, b, depth, items)) = todo.pop() {
            deepest = deepest.max(depth);
            let Some(block) = node.children() else {
                let range = node.references();
                let Some(listed) = self.refs.get(range.clone()) else {
                    return err(format!("a leaf's references {range:?} are out of range"));
                };
                if !listed.iter().copied().eq(items.iter().map(|i| i.id)) {
                    return err(format!(
                        "the leaf at depth {depth} with box {b:?} lists {} primitives, overlaps {}",
                        listed.len(),
                        items.len()
                    ));
                }
                continue;
            };
            if depth >= MAX_DEPTH || !divisible(&b) {
                return err(format!("an interior node at depth {depth} cannot be cut"));
            }
            match seen.get_mut(block) {
                Some(s) if !*s => *s = true,
                _ => return err(format!("block {block} is out of range or shared")),
            }
            let mid = midpoint(&b);
            let lists = split(&self.prims, &items, &b, margin(&self.bounds));
            for (i, list) in lists.into_iter().enumerate() {
                let child: Node = self.blocks[block].0[i];
                todo.push((child, child_box(&b, mid, i), depth + 1, list));
            }
        }
        if let Some(b) = seen.iter().position(|s| !s) {
            return err(format!("block {b} is not reachable"));
        }
        if deepest != self.depth {
            return err(format!(
                "the depth is {}, but the tree goes {deepest} deep",
                self.depth
            ));
        }
        Ok(())
    }
}

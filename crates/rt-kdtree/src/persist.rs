//! Saving and loading a built tree ([`Persist`]).
//!
//! The sections, in the framing of [`rt_persist`] (layout version [`LAYOUT`]):
//!
//! | tag | elements | what |
//! | --- | --- | --- |
//! | `meta` | `u64` × 5 | the traversal (0 stack, 1 restart), depth, leaves, empty leaves, valid primitives |
//! | `bounds` | [`Aabb`] × 1 | the root cell |
//! | `nodes` | [`Node`] | the tree, root first |
//! | `refs` | `u32` | the leaves' references into `prims` |
//! | `prims` | `P` | the primitives, in input order |
//!
//! Loading runs [`KdTree::validate`], which checks every node, split and reference and that
//! the counts match the tree.

use crate::{KdTree, Node, Traversal};
use rt_core::Aabb;
use rt_persist::{LoadError, Persist, Reader, SavedPrimitive, Writer, to_usize};

/// The version of the sections this module writes.
pub const LAYOUT: u32 = 1;

impl<P: SavedPrimitive> Persist for KdTree<P> {
    const KIND: &'static str = "rt-kdtree::KdTree";
    const LAYOUT: u32 = LAYOUT;
    type Saved = P;

    fn write_sections<'a>(&'a self, w: &mut Writer<'a>) {
        let meta: [u64; 5] = [
            u64::from(self.traversal == Traversal::Restart),
            self.max_depth as u64,
            self.leaves as u64,
            self.empty_leaves as u64,
            self.valid_prims as u64,
        ];
        w.section_owned("meta", meta.to_vec());
        w.section("bounds", std::slice::from_ref(&self.bounds));
        w.section("nodes", &self.nodes);
        w.section("refs", &self.refs);
        w.section("prims", &self.prims);
    }

    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError> {
        let meta: [u64; 5] = r.array("meta")?;
        let traversal = match meta[0] {
            0 => Traversal::Stack,
            1 => Traversal::Restart,
            other => {
                return Err(LoadError::Malformed(format!(
                    "traversal {other} is not 0 or 1"
                )));
            }
        };
        Ok(Self {
            nodes: r.section::<Node>("nodes")?,
            refs: r.section("refs")?,
            prims: r.section("prims")?,
            bounds: r.value::<Aabb>("bounds")?,
            traversal,
            max_depth: to_usize(meta[1], "the depth")?,
            leaves: to_usize(meta[2], "the leaf count")?,
            empty_leaves: to_usize(meta[3], "the empty leaf count")?,
            valid_prims: to_usize(meta[4], "the valid count")?,
        })
    }

    fn check_loaded(&self) -> Result<(), LoadError> {
        Ok(self.validate()?)
    }
}

//! Saving and loading a built tree ([`Persist`]).
//!
//! The sections, in the framing of [`rt_persist`] (layout version [`LAYOUT`]):
//!
//! | tag | elements | what |
//! | --- | --- | --- |
//! | `meta` | `u64` × 3 | `mailbox`, valid primitives, depth |
//! | `bounds` | [`Aabb`] × 1 | the root cube |
//! | `root` | [`Node`] × 1 | the root node |
//! | `blocks` | [`Block`] | the interior nodes' blocks of eight children |
//! | `refs` | `u32` | the leaves' references into `prims` |
//! | `prims` | `P` | the primitives, in input order |
//!
//! Loading runs [`Octree::validate`], which walks the tree from the root, checks every block
//! and reference range, and repeats the builder's overlap test.

use crate::{Block, Node, Octree};
use rt_core::Aabb;
use rt_persist::{LoadError, Persist, Reader, SavedPrimitive, Writer, to_bool, to_u32, to_usize};

/// The version of the sections this module writes.
pub const LAYOUT: u32 = 1;

impl<P: SavedPrimitive> Persist for Octree<P> {
    const KIND: &'static str = "rt-octree::Octree";
    const LAYOUT: u32 = LAYOUT;
    type Saved = P;

    fn write_sections<'a>(&'a self, w: &mut Writer<'a>) {
        w.section_owned(
            "meta",
            vec![
                u64::from(self.mailbox),
                self.valid_prims as u64,
                u64::from(self.depth),
            ],
        );
        w.section("bounds", std::slice::from_ref(&self.bounds));
        w.section("root", std::slice::from_ref(&self.root));
        w.section("blocks", &self.blocks);
        w.section("refs", &self.refs);
        w.section("prims", &self.prims);
    }

    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError> {
        let meta: [u64; 3] = r.array("meta")?;
        Ok(Self {
            root: r.value::<Node>("root")?,
            blocks: r.section::<Block>("blocks")?,
            refs: r.section("refs")?,
            bounds: r.value::<Aabb>("bounds")?,
            prims: r.section("prims")?,
            mailbox: to_bool(to_u32(meta[0], "mailbox")?, "mailbox")?,
            valid_prims: to_usize(meta[1], "the valid count")?,
            depth: to_u32(meta[2], "the depth")?,
        })
    }

    fn check_loaded(&self) -> Result<(), LoadError> {
        Ok(self.validate()?)
    }
}

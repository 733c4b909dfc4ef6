//! Saving and loading a built tree ([`Persist`]).
//!
//! The sections, in the framing of [`rt_persist`] (layout version [`LAYOUT`]):
//!
//! | tag | elements | what |
//! | --- | --- | --- |
//! | `meta` | `u64` × 12 | layout (0 binary, 1 wide), leaves (0 primitives, 1 packs), pack test (0 watertight, 1 Möller–Trumbore), `parallel`, depth, leaves, valid, stored, input length, the two SAH constants' bits, the built cost's bits |
//! | `nodes` | [`Node`] or [`WideNode`] | the tree |
//! | `packs` | [`TriPack`] | packed leaves (wide trees over triangles with one test) |
//! | `prims`, `ids` | `P`, `u32` | the leaves' primitives and their input indices (otherwise) |
//! | `invalid` | `u32` | input indices left out as invalid |
//! | `copies` | `[u32; 2]` | input indices left out as bit-identical copies, with the stored index |
//!
//! Loading checks, beyond [`Bvh::validate`], that the stored indices, the invalid ones and the
//! copies are exactly the input's indices once each, so that every id a query reports names a
//! primitive of the input. The kernels are chosen for the loading machine, as a build chooses
//! them.

use crate::WideNode;
use crate::{Ablation, Bvh, Input, Items, Kernels, Layout, Leaves, Node, Tree, TriPack, Wide};
use rt_core::{Primitive, TriangleTest, ValidationError};
use rt_persist::{LoadError, Persist, Reader, SavedPrimitive, Writer, to_bool, to_usize};
use rt_simd::Isa;

/// The version of the sections this module writes.
pub const LAYOUT: u32 = 1;

const META: usize = 12;

impl<P: SavedPrimitive> Persist for Bvh<P> {
    const KIND: &'static str = "rt-bvh::Bvh";
    const LAYOUT: u32 = LAYOUT;
    type Saved = P;

    fn write_sections<'a>(&'a self, w: &mut Writer<'a>) {
        let test = self.pack_test();
        let meta: [u64; META] = [
            u64::from(self.layout() == Layout::Wide),
            u64::from(test.is_some()),
            u64::from(test == Some(TriangleTest::MollerTrumbore)),
            u64::from(self.parallel),
            self.max_depth as u64,
            self.leaves as u64,
            self.valid as u64,
            self.stored as u64,
            self.input.len as u64,
            u64::from(self.costs.0.to_bits()),
            u64::from(self.costs.1.to_bits()),
            self.built_cost.to_bits(),
        ];
        w.section_owned("meta", meta.to_vec());
        match &self.tree {
            Tree::Binary { nodes, .. } => w.section("nodes", nodes),
            Tree::Wide(wide) => w.section("nodes", &wide.nodes),
        }
        match self.items() {
            Some(items) => {
                w.section("prims", &items.prims);
                w.section("ids", &items.ids);
            }
            None => w.section("packs", self.packs()),
        }
        w.section("invalid", &self.input.invalid);
        let copies: Vec<[u32; 2]> = self.input.copies.iter().map(|&(c, s)| [c, s]).collect();
        w.section_owned("copies", copies);
    }

    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError> {
        let meta: [u64; META] = r.array("meta")?;
        let flag = |i: usize, what: &str| to_bool(u32::try_from(meta[i]).unwrap_or(2), what);
        let (wide, packed, mt, parallel) = (
            flag(0, "the layout")?,
            flag(1, "the leaf kind")?,
            flag(2, "the pack test")?,
            flag(3, "parallel")?,
        );
        let f32_at = |i: usize| f32::from_bits(u32::try_from(meta[i]).unwrap_or(u32::MAX));
        let items = |r: &Reader<'_>| -> Result<Items<P>, LoadError> {
            Ok(Items {
                prims: r.section("prims")?,
                ids: r.section("ids")?,
            })
        };
        let tree = if wide {
            let leaves = if packed {
                let test = if mt {
                    TriangleTest::MollerTrumbore
                } else {
                    TriangleTest::Watertight
                };
                Leaves::Packs {
                    packs: r.section::<TriPack>("packs")?,
                    test,
                }
            } else {
                Leaves::Items(items(r)?)
            };
            Tree::Wide(Wide {
                nodes: r.section::<WideNode>("nodes")?,
                leaves,
                kernels: Kernels::Simd(Isa::Portable),
                isa: Isa::Portable,
                ablation: Ablation::default(),
            })
        } else if packed {
            return Err(LoadError::Malformed(
                "a binary tree with packed leaves".into(),
            ));
        } else {
            Tree::Binary {
                nodes: r.section::<Node>("nodes")?,
                items: items(r)?,
            }
        };
        let copies = r.section::<[u32; 2]>("copies")?;
        let mut input = Input {
            len: to_usize(meta[8], "the input length")?,
            invalid: r.section("invalid")?,
            copies: copies.iter().map(|&[c, s]| (c, s)).collect(),
            twins: Vec::new(),
        };
        // The input's length sizes what validation allocates, so it must come from the file's
        // own arrays: the stored ids, the invalid ones and the copies are every input index.
        let stored = match &tree {
            Tree::Wide(Wide {
                leaves: Leaves::Packs { packs, .. },
                ..
            }) => packs
                .iter()
                .map(|p| p.ids.iter().filter(|&&id| id != u32::MAX).count())
                .sum(),
            Tree::Binary { items, .. }
            | Tree::Wide(Wide {
                leaves: Leaves::Items(items),
                ..
            }) => items.ids.len(),
        };
        if input.len != stored + input.invalid.len() + input.copies.len() {
            return Err(LoadError::Malformed(format!(
                "an input of {} primitives, but {stored} stored, {} invalid and {} copies",
                input.len,
                input.invalid.len(),
                input.copies.len()
            )));
        }
        input.twins = input.copies.iter().map(|&(c, s)| (s, c)).collect();
        input.twins.sort_unstable();
        let mut bvh = Self {
            tree,
            max_depth: to_usize(meta[4], "the depth")?,
            leaves: to_usize(meta[5], "the leaf count")?,
            valid: to_usize(meta[6], "the valid count")?,
            stored: to_usize(meta[7], "the stored count")?,
            input,
            costs: (f32_at(9), f32_at(10)),
            parallel,
            built_cost: f64::from_bits(meta[11]),
        };
        if bvh.layout() == Layout::Wide {
            bvh.set_fastest_kernels();
        }
        Ok(bvh)
    }

    fn check_loaded(&self) -> Result<(), LoadError> {
        let stored = self.validated_ids()?;
        Ok(self.check_input(&stored)?)
    }
}

impl<P: Primitive> Bvh<P> {
    /// Checks that the invalid indices and the copies are the input indices not `stored` (one
    /// bit per index, from validation), each once, each copy naming a stored primitive, and
    /// that the counts agree.
    fn check_input(&self, stored: &[u64]) -> Result<(), ValidationError> {
        let err = |m: String| Err(ValidationError::new(m));
        let len = self.input.len;
        if len > u32::MAX as usize {
            return err(format!(
                "an input of {len} primitives, more than ids can name"
            ));
        }
        let is_stored = |id: u32| stored[id as usize / 64] & (1 << (id % 64)) != 0;
        let mut left_out = vec![false; len];
        for &id in self
            .input
            .invalid
            .iter()
            .chain(self.input.copies.iter().map(|c| &c.0))
        {
            if (id as usize) >= len
                || is_stored(id)
                || std::mem::replace(&mut left_out[id as usize], true)
            {
                return err(format!(
                    "input index {id} is out of range, stored, or left out twice"
                ));
            }
        }
        if let Some(&(copy, of)) = self
            .input
            .copies
            .iter()
            .find(|&&(_, of)| (of as usize) >= len || !is_stored(of))
        {
            return err(format!("copy {copy} names {of}, which is not stored"));
        }
        if self.stored + self.input.invalid.len() + self.input.copies.len() != len {
            return err(format!(
                "{} stored, {} invalid and {} copies of {len} input primitives",
                self.stored,
                self.input.invalid.len(),
                self.input.copies.len()
            ));
        }
        if self.valid != len - self.input.invalid.len() {
            return err(format!(
                "{} valid primitives of {len}, {} of them invalid",
                self.valid,
                self.input.invalid.len()
            ));
        }
        Ok(())
    }
}

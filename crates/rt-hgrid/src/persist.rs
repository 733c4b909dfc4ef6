//! Saving and loading a built hierarchy ([`Persist`]).
//!
//! The sections, in the framing of [`rt_persist`] (layout version [`LAYOUT`]):
//!
//! | tag | elements | what |
//! | --- | --- | --- |
//! | `meta` | `u64` × 3 | `mailbox`, valid primitives, depth |
//! | `levels` | `[u64; 13]` | per grid: its box (six `f32` bits: min then max), cells per axis, first cell, the parent cell's reference range, depth |
//! | `cells` | [`Cell`] | every grid's cells |
//! | `refs` | `u32` | the cells' references into `prims` |
//! | `prims` | `P` | the primitives, in input order |
//!
//! Loading computes each grid's cell size again from its box and resolution, then runs
//! [`HGrid::validate`], which checks every grid, nesting and reference range and repeats the
//! builder's overlap test.

use crate::{Cell, HGrid, Level};
use rt_core::Aabb;
use rt_core::glam::Vec3;
use rt_grid::persist::saved_shape;
use rt_persist::{LoadError, Persist, Reader, SavedPrimitive, Writer, to_bool, to_u32, to_usize};

/// The version of the sections this module writes.
pub const LAYOUT: u32 = 1;

impl<P: SavedPrimitive> Persist for HGrid<P> {
    const KIND: &'static str = "rt-hgrid::HGrid";
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
        let levels: Vec<[u64; 13]> = self
            .levels
            .iter()
            .map(|l| {
                let b = l.shape.bounds();
                let (lo, hi) = (b.min.to_array(), b.max.to_array());
                let res = l.shape.resolution_per_axis();
                let mut out = [0u64; 13];
                for a in 0..3 {
                    out[a] = u64::from(lo[a].to_bits());
                    out[3 + a] = u64::from(hi[a].to_bits());
                    out[6 + a] = u64::from(res[a]);
                }
                out[9] = l.first_cell as u64;
                out[10] = l.all.0 as u64;
                out[11] = l.all.1 as u64;
                out[12] = u64::from(l.depth);
                out
            })
            .collect();
        w.section_owned("levels", levels);
        w.section("cells", &self.cells);
        w.section("refs", &self.refs);
        w.section("prims", &self.prims);
    }

    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError> {
        let meta: [u64; 3] = r.array("meta")?;
        let levels = r
            .section::<[u64; 13]>("levels")?
            .iter()
            .map(|l| {
                let f = |i: usize| f32::from_bits(u32::try_from(l[i]).unwrap_or(u32::MAX));
                let bounds = Aabb::new(Vec3::new(f(0), f(1), f(2)), Vec3::new(f(3), f(4), f(5)));
                Ok(Level {
                    shape: saved_shape(bounds, [l[6], l[7], l[8]])?,
                    first_cell: to_usize(l[9], "a grid's first cell")?,
                    all: (
                        to_usize(l[10], "a reference range")?,
                        to_usize(l[11], "a reference range")?,
                    ),
                    depth: to_u32(l[12], "a grid's depth")?,
                })
            })
            .collect::<Result<Vec<_>, LoadError>>()?;
        Ok(Self {
            levels,
            cells: r.section::<Cell>("cells")?,
            refs: r.section("refs")?,
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

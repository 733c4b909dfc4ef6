//! Saving and loading a built grid ([`Persist`]).
//!
//! The sections, in the framing of [`rt_persist`] (layout version [`LAYOUT`]):
//!
//! | tag | elements | what |
//! | --- | --- | --- |
//! | `meta` | `u64` × 6 | `mailbox`, `exact_insertion`, valid primitives, cells per axis (x, y, z) |
//! | `bounds` | [`Aabb`] × 1 | the grid's box |
//! | `cells` | `u32` | each cell's first reference, and one past the last |
//! | `refs` | `u32` | the cells' references into `prims` |
//! | `prims` | `P` | the primitives, in input order |
//!
//! The cell size is computed again from the box and the resolution, exactly as the build
//! computed it. Loading then runs [`Grid::validate`], which repeats the builder's overlap test
//! for every primitive.

use crate::{Grid, GridShape, MAX_RESOLUTION};
use rt_core::Aabb;
use rt_persist::{LoadError, Persist, Reader, SavedPrimitive, Writer, to_bool, to_usize};

/// The version of the sections this module writes.
pub const LAYOUT: u32 = 1;

impl<P: SavedPrimitive> Persist for Grid<P> {
    const KIND: &'static str = "rt-grid::Grid";
    const LAYOUT: u32 = LAYOUT;
    type Saved = P;

    fn write_sections<'a>(&'a self, w: &mut Writer<'a>) {
        let res = self.shape.resolution_per_axis();
        let meta: [u64; 6] = [
            u64::from(self.mailbox),
            u64::from(self.exact),
            self.valid_prims as u64,
            u64::from(res[0]),
            u64::from(res[1]),
            u64::from(res[2]),
        ];
        w.section_owned("meta", meta.to_vec());
        w.section_owned("bounds", vec![self.shape.bounds()]);
        w.section("cells", &self.cells);
        w.section("refs", &self.refs);
        w.section("prims", &self.prims);
    }

    fn read_sections(r: &Reader<'_>) -> Result<Self, LoadError> {
        let meta: [u64; 6] = r.array("meta")?;
        let flag = |i: usize, what: &str| to_bool(u32::try_from(meta[i]).unwrap_or(2), what);
        let shape = saved_shape(r.value::<Aabb>("bounds")?, [meta[3], meta[4], meta[5]])?;
        Ok(Self {
            shape,
            cells: r.section("cells")?,
            refs: r.section("refs")?,
            prims: r.section("prims")?,
            mailbox: flag(0, "mailbox")?,
            exact: flag(1, "exact insertion")?,
            valid_prims: to_usize(meta[2], "the valid count")?,
        })
    }

    fn check_loaded(&self) -> Result<(), LoadError> {
        Ok(self.validate()?)
    }
}

/// The shape of a saved grid: a finite box and a resolution of `1..=MAX_RESOLUTION` per axis,
/// else an error. The hierarchical grid reads its grids' shapes through this too.
///
/// # Errors
/// [`LoadError::Malformed`] naming what is out of range.
pub fn saved_shape(bounds: Aabb, res: [u64; 3]) -> Result<GridShape, LoadError> {
    let finite = bounds.min.is_finite() && bounds.max.is_finite();
    if !finite || bounds.min.cmpgt(bounds.max).any() {
        return Err(LoadError::Malformed(format!(
            "the grid's box {bounds:?} is not a finite box"
        )));
    }
    let ok = |n: u64| (1..=u64::from(MAX_RESOLUTION)).contains(&n);
    if !res.iter().all(|&n| ok(n)) {
        return Err(LoadError::Malformed(format!(
            "resolution {res:?} is outside 1..={MAX_RESOLUTION} per axis"
        )));
    }
    Ok(GridShape::new(bounds, res.map(|n| n as u32)))
}

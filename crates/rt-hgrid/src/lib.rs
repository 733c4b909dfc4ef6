//! A hierarchical grid for CPU ray tracing: a coarse uniform grid whose crowded cells hold
//! nested grids, recursively.
//!
//! # The structure
//! A uniform grid fails on the "teapot in a stadium": cells sized for the stadium put the whole
//! teapot into a few of them, and every ray through those cells tests thousands of triangles.
//! The hierarchical grid keeps the uniform grid's cheap steps but refines where primitives
//! crowd: a coarse top grid, and in every cell holding at least `split_min` primitives a nested
//! grid over that cell, sized by the cell's own primitive count; nested cells are refined the same
//! way, down to `max_levels` levels. Sizing each top cell's grid by its count is the scheme of
//! Kalojanov, Billeter & Slusallek's two-level grids (2011); here it recurses.
//!
//! # Resolution
//! The top grid has `n_i = d_i · ∛(λ₁ · N / V)` cells per axis (Cleary & Wyvill's rule with
//! `top_density` λ₁ cells per primitive, as in `rt-grid`); a nested grid over a cell of volume `V_c`
//! holding `N_c` primitives has `d_i · ∛(λ₂ · N_c / V_c)` (`density` λ₂). Termination and memory
//! are bounded: at most `max_levels` (≤ [`MAX_LEVELS`]) levels, all grids together within
//! `max_cells` cells, and a cell stays a leaf when its grid would have a single cell, more than
//! eight references per primitive, or a nested cell with more than three quarters of the cell's
//! primitives (large, identical or overlapping primitives, which refining never separates).
//!
//! # Memory
//! 8 bytes per cell ([`Cell`]: a reference range, or a nested grid's index), 4 bytes per
//! reference, a [`Level`] per grid, plus the primitives. A parent cell also keeps its own
//! reference list, which a walk tests if it only grazes the cell (see below).
//!
//! # Traversal
//! `rt-grid`'s 3D-DDA ([`rt_grid::dda::Dda`]) through the top grid; at a cell holding a nested
//! grid the walk pushes a DDA through that grid, started where the ray enters the cell, and pops
//! it when the ray leaves. The stack has one entry per level and lives on the thread's stack. The
//! hit rule, mailboxing and exactness are the uniform grid's: the best hit is kept across cells,
//! the walk ends at the first cell starting beyond it, a per-ray mailbox tests a primitive listed
//! in several cells once, and where two boundaries are crossed within rounding of each other the
//! cells beside the path are tested too — a parent cell there by its whole list.
//!
//! # Bundles
//! [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`] trace coherent rays together by
//! `rt-grid`'s coherent grid traversal (Wald et al. 2006, [`rt_grid::bundle`]) on each level:
//! slice by slice through the top grid and, at a cell holding a nested grid, through that grid
//! with the lanes that cross the cell, each primitive tested once per bundle against all its
//! lanes, eight per vector step, and skipped when no lane can enter its box. Each ray answers
//! exactly as its single-ray query.
//!
//! # Closest points
//! [`Accel::closest_point`] visits the top grid's cells in growing
//! shells around the point (`rt_grid::nearest::shells`), and a cell's nested grid the same way
//! before the shell goes on.
//!
//! # Saving and loading
//! [`Persist`] writes a built hierarchy to a versioned file and reads it
//! back without rebuilding: every grid's box, resolution and cell range, the cells, the references
//! and the primitives (the sections are listed in [`persist`]). Loading checks the file's framing
//! and checksum, then runs [`HGrid::validate`], so a truncated, damaged or hostile file is refused
//! with a typed [`LoadError`] and a loaded hierarchy answers every
//! query bit for bit as the saved one.
//!
//! # Measurements
//! On the generated results pages, one per machine kind, listed by `docs/results.md` in the
//! repository (date, commit, CPU; written by `cargo xtask results`). What they show: on the teapot in a stadium, where the uniform grid's
//! cells sized for the stadium hold thousands of the teapot's triangles, the hierarchical grid
//! tests two orders of magnitude fewer primitives per ray for a little more memory
//! ([`HGridParams::lean`] takes no more memory than the uniform grid and still tests far fewer).
//! Where primitives are spread evenly (`random-soup`) the refinement buys nothing and the uniform
//! grid is better; on surfaces both grids trail the trees.
//!
//! # Depends on rt-grid
//! The one structure crate that depends on another: each level is a uniform grid, and this
//! crate uses `rt-grid`'s cell planes ([`rt_grid::GridShape`]), exact insertion, 3D-DDA and
//! shells, so every level rounds exactly as the uniform grid does.
//!
//! # Example
//! ```
//! use rt_hgrid::{HGrid, HGridParams};
//! use rt_core::{Accel, Ray, Triangle, glam::Vec3};
//!
//! let tris = vec![
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)),
//!     Triangle::new(Vec3::new(-1.0, -1.0, 3.0), Vec3::new(1.0, -1.0, 3.0), Vec3::new(0.0, 1.0, 3.0)),
//! ];
//! let grid = HGrid::build(&tris, &HGridParams::default());
//! let hit = grid.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).unwrap();
//! assert_eq!((hit.prim, hit.t), (1, 2.0));
//! assert!(grid.occluded(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)));
//! assert!(grid.validate().is_ok());
//! ```
#![warn(missing_docs)]

mod builder;
mod bundle;
mod nearest;
mod node;
mod overlap;
pub mod persist;
mod regions;
mod traverse;
mod validate;

pub use builder::MAX_LEVELS;
pub use node::{Cell, Level};
pub use rt_core::ValidationError;
/// Saving and loading, re-exported so that a user of this crate alone can save and load.
pub use rt_persist::{LoadError, Persist};

use rt_core::{Accel, BuildStats, Primitive};

/// Build and traversal parameters. `Default` is [`HGridParams::standard`].
#[derive(Clone, Debug, PartialEq)]
pub struct HGridParams {
    /// λ₁: cells per primitive in the top grid.
    pub top_density: f32,
    /// λ₂: cells per primitive in a nested grid, counting the primitives of its cell.
    pub density: f32,
    /// A cell with at least this many primitives (above the last level) gets a nested grid.
    pub split_min: u32,
    /// Levels, the top grid included; clamped to `1..=MAX_LEVELS`.
    pub max_levels: u32,
    /// The most cells of any one grid.
    pub max_cells: usize,
    /// Skip primitives this ray tested in the last few tests.
    pub mailbox: bool,
    /// Run the top grid's overlap tests in parallel (rayon); the grid is the same either way.
    pub parallel: bool,
}

impl HGridParams {
    /// λ₁ = 1/2, λ₂ = 1/2, nested grids in cells of 16 or more primitives, three levels.
    pub fn standard() -> Self {
        Self {
            top_density: 0.5,
            density: 0.5,
            split_min: 16,
            max_levels: 3,
            max_cells: 1 << 24,
            mailbox: true,
            parallel: true,
        }
    }
}

impl HGridParams {
    /// Fewer, coarser grids for a memory budget like the uniform grid's: λ₁ = 1/8, λ₂ = 1/2,
    /// nested grids in cells of 32 or more primitives, two levels.
    pub fn lean() -> Self {
        Self {
            top_density: 0.125,
            split_min: 32,
            max_levels: 2,
            ..Self::standard()
        }
    }
}

impl Default for HGridParams {
    fn default() -> Self {
        Self::standard()
    }
}

/// A hierarchical grid over primitives of type `P`.
#[derive(Clone, Debug)]
pub struct HGrid<P> {
    levels: Vec<Level>,
    cells: Vec<Cell>,
    refs: Vec<u32>,
    prims: Vec<P>,
    mailbox: bool,
    valid_prims: usize,
    depth: u32,
}

impl<P> HGrid<P> {
    /// The grids, the top one first; a nested grid comes after its parent.
    pub fn levels(&self) -> &[Level] {
        &self.levels
    }

    /// All grids' cells.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// The primitive references: input indices of the primitives.
    pub fn references(&self) -> &[u32] {
        &self.refs
    }
}

impl<P: Primitive> Accel for HGrid<P> {
    type Prim = P;
    type Params = HGridParams;
    const NAME: &'static str = "hgrid";

    fn presets() -> Vec<(&'static str, HGridParams)> {
        vec![
            ("standard", HGridParams::standard()),
            ("lean", HGridParams::lean()),
        ]
    }

    /// Builds the grids; invalid primitives (see [`Primitive::is_valid`]) are left out.
    ///
    /// Copies the primitives once, into the vector the leaves index, and builds over that.
    ///
    /// # Panics
    /// If the grids would hold more than 2³² - 1 references or cells (far beyond what
    /// `max_cells` and memory allow for triangles).
    fn build_from<G: rt_core::Geometry<Prim = P> + ?Sized>(
        geometry: &G,
        params: &HGridParams,
    ) -> Self {
        let prims = geometry.to_vec();
        let b = builder::build(&prims, params);
        Self {
            levels: b.levels,
            cells: b.cells,
            refs: b.refs,
            prims,
            mailbox: params.mailbox,
            valid_prims: b.valid_prims,
            depth: b.depth,
        }
    }

    fn bounds(&self) -> rt_core::Aabb {
        if self.valid_prims == 0 {
            rt_core::Aabb::EMPTY
        } else {
            self.levels[0].shape.bounds()
        }
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.levels.capacity() * size_of::<Level>()
            + self.cells.capacity() * size_of::<Cell>()
            + self.refs.capacity() * size_of::<u32>()
            + self.prims.capacity() * size_of::<P>()
    }

    fn build_stats(&self) -> BuildStats {
        let leaves: Vec<&Cell> = self.cells.iter().filter(|c| c.nested().is_none()).collect();
        BuildStats {
            nodes: self.cells.len(),
            leaves: leaves.len(),
            empty_leaves: leaves.iter().filter(|c| c.references().is_empty()).count(),
            max_depth: self.depth as usize,
            prim_refs: leaves.iter().map(|c| c.references().len()).sum(),
            valid_prims: self.valid_prims,
            extra: vec![("grids", self.levels.len() as f64)],
        }
    }

    // The walks, each in its phase file: the ray walk (`traverse.rs`), the bundle walk
    // (`bundle.rs`), closest points (`nearest.rs`), box overlap (`overlap.rs`), the drawing
    // (`regions.rs`).
    rt_core::accel_walks!(
        build: build_from,
        ray: query,
        ordered_bundle: bundle_query,
        ball: ball,
        boxes: box_cells,
        regions: walk_regions,
    );
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

// With `share-dyn`, debug and test builds of the crates that use a `HGrid` as a trait
// object (the shootout, the renderer's tests) link this crate's copy of its methods instead of
// compiling their own.
#[cfg(feature = "share-dyn")]
rt_core::share_dyn_accel!(HGrid);

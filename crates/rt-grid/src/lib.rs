//! A uniform grid for CPU ray tracing: equal cells, each listing the primitives that overlap it,
//! walked by 3D-DDA.
//!
//! # The structure
//! The scene box is cut into `n_x × n_y × n_z` equal cells. A ray walks the cells it crosses in
//! order of distance (Amanatides & Woo's 3D-DDA, the "3D line rasterization" of the lecture) and
//! stops at the first cell that yields a hit inside it. Nothing adapts to the scene: a grid is
//! cheap to build and to step through where primitives are spread evenly, and wasteful where they
//! are not — the "teapot in a stadium", where the teapot falls into a handful of cells holding
//! all its triangles while most cells are empty. `rt-hgrid` is the answer to that.
//!
//! # Resolution
//! Cleary & Wyvill's rule, "about as many cells as primitives": `n_i = d_i · ∛(λ · N / V)` cells
//! on an axis of extent `d_i`, for `N` primitives in a box of volume `V`, so cells are cubes and
//! there are about `λ · N` of them (`density` λ in [`GridParams`]). Each `n_i` is at least 1 and
//! at most [`MAX_RESOLUTION`], and all are scaled down together until the total is at most
//! `max_cells`, so memory stays bounded whatever the scene. A flat axis gets one cell.
//!
//! # Build
//! Each primitive is tested against the cells of its bounding box and listed only in those it
//! overlaps ([`Primitive::clip_bounds`]: the exact triangle–box test shared with the kd-tree), not
//! in every cell of its box; `compare` shows the result as references per primitive. The
//! (cell, primitive) pairs are counting-sorted into one offset array (`cells`, 4 bytes per cell
//! plus one) and one reference array (4 bytes per reference): no `Vec` per cell. The overlap tests
//! run in parallel for large inputs (feature `parallel`); the result does not depend on it. O(N + cells)
//! besides the tests.
//!
//! # Traversal
//! A DDA step costs a three-way comparison, one increment and one multiplication. A cell costs
//! its primitive tests, minus those a per-ray [`Mailbox`](rt_core::Mailbox) saves: a primitive
//! spanning several cells is tested once per ray (the mailbox keeps the last 8 primitives tested
//! on the stack, so the grid stays immutable and shareable between threads, unlike a ray id
//! stored on each primitive). A hit beyond the current cell is kept as the best so far; the walk
//! stops at the first cell that starts beyond it. Rays starting inside, outside or on the grid's
//! boundary, with `±0` direction components, lying in a cell plane or passing through cell edges
//! and corners are handled exactly; see `traverse.rs`.
//!
//! # Bundles
//! [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`] trace coherent rays (a camera's
//! pixel tiles, shadow rays towards one light) together by coherent grid traversal (Wald, Ize,
//! Kensler, Knoll & Parker 2006): a bundle walks the grid slice by slice along its major axis,
//! covers in each slice the rectangle of cells its lanes cross, and tests each primitive there
//! once for all lanes, eight lanes per vector step ([`rt_simd::Lanes`]). Primitives
//! whose box no lane can enter are skipped with one interval test for the whole bundle
//! ([`Bundle::may_enter`](rt_simd::Bundle::may_enter)), Wald et al.'s frustum culling, which is
//! what pays most where cells hold many primitives (the teapot in a stadium). Rays in spread-out
//! directions, whose rectangle would widen with every slice, and bundles that turn out to cost
//! more than their single rays would, go singly. Each ray answers exactly as its single-ray
//! query, bit for bit; `bundle.rs` says why.
//!
//! # Closest points
//! [`Accel::closest_point`] visits cells in growing shells around
//! the point's cell ([`nearest::shells`]), tests each cell the query's ball still reaches, and stops
//! at the first shell wholly outside the ball. Far from the surface the ball holds many empty cells
//! that a hierarchy would discard at once, so closest points are where the grid falls furthest
//! behind the trees.
//!
//! # Choosing the density
//! `density` (λ) trades cells for tests: more cells mean fewer primitives per cell but more
//! empty steps. The speed peaks where empty steps start to cost more than the tests they save,
//! at λ = 2 to 4 on the bunny and the random soup, hence the default λ = 4; `cargo run
//! --release -p rt-grid --example density_sweep` prints the trade-off on a scene of your choice.
//! Exact insertion (the default) lists a triangle only in the cells it overlaps; listing every
//! cell of its bounding box (`GridParams::bbox_insertion`, row `grid-bbox`) builds faster but
//! references and tests several times more on scenes of large triangles.
//!
//! # Saving and loading
//! [`Persist`] writes a built grid to a versioned file and reads it back
//! without rebuilding: the box and resolution, the cell offsets, the references and the primitives
//! (the sections are listed in [`persist`]). Loading checks the file's framing and checksum, then
//! runs [`Grid::validate`], so a truncated, damaged or hostile file is refused with a typed
//! [`LoadError`] and a loaded grid answers every query bit for bit as
//! the saved one.
//!
//! # Measurements
//! On the generated results pages, one per machine kind, listed by `docs/results.md` in the
//! repository (date, commit, CPU; written by `cargo xtask results`). What they show: where primitives are spread evenly (the random soup)
//! the grid traces as fast as a BVH and its mailbox saves a third of its tests; on a surface
//! (the bunny) most cells are empty and a tree is several times faster; on the teapot in a
//! stadium, cells sized for the stadium hold thousands of the teapot's triangles — the lecture's
//! failure, which `rt-hgrid` answers.
//!
//! # Example
//! ```
//! use rt_grid::{Grid, GridParams};
//! use rt_core::{Accel, Ray, Triangle, glam::Vec3};
//!
//! let tris = vec![
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)),
//!     Triangle::new(Vec3::new(-1.0, -1.0, 3.0), Vec3::new(1.0, -1.0, 3.0), Vec3::new(0.0, 1.0, 3.0)),
//! ];
//! let grid = Grid::build(&tris, &GridParams::default());
//! let hit = grid.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).unwrap();
//! assert_eq!((hit.prim, hit.t), (1, 2.0));
//! assert!(grid.occluded(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)));
//! assert!(grid.validate().is_ok());
//! ```
#![warn(missing_docs)]

mod builder;
pub mod bundle;
mod cell;
pub mod dda;
pub mod nearest;
pub mod overlap;
pub mod persist;
mod regions;
mod traverse;
mod validate;

pub use builder::cells_overlapping;
pub use cell::{GridShape, MAX_RESOLUTION};
pub use rt_core::ValidationError;
/// Saving and loading, re-exported so that a user of this crate alone can save and load.
pub use rt_persist::{LoadError, Persist};

use rt_core::{Accel, BuildStats, Primitive};

/// Build and traversal parameters. `Default` is [`GridParams::standard`].
#[derive(Clone, Debug, PartialEq)]
pub struct GridParams {
    /// λ: cells per primitive.
    pub density: f32,
    /// The most cells the grid may have (4 bytes each).
    pub max_cells: usize,
    /// List a primitive only in the cells it overlaps (exact for triangles); `false` lists it in
    /// every cell of its bounding box, the naive insertion.
    pub exact_insertion: bool,
    /// Skip primitives this ray tested in the last few tests.
    pub mailbox: bool,
    /// Run the overlap tests in parallel (rayon); the grid is the same either way.
    pub parallel: bool,
}

impl GridParams {
    /// λ = 4 cells per primitive, at most 2²⁴ cells (64 MiB of offsets), mailboxing on.
    pub fn standard() -> Self {
        Self {
            density: 4.0,
            max_cells: 1 << 24,
            exact_insertion: true,
            mailbox: true,
            parallel: true,
        }
    }

    /// [`standard`](Self::standard) without the mailbox, to measure what it saves.
    pub fn no_mailbox() -> Self {
        Self {
            mailbox: false,
            ..Self::standard()
        }
    }
}

impl GridParams {
    /// [`standard`](Self::standard) with every primitive in all cells of its bounding box, to
    /// measure what the exact insertion saves.
    pub fn bbox_insertion() -> Self {
        Self {
            exact_insertion: false,
            ..Self::standard()
        }
    }
}

impl Default for GridParams {
    fn default() -> Self {
        Self::standard()
    }
}

/// A uniform grid over primitives of type `P`.
#[derive(Clone, Debug)]
pub struct Grid<P> {
    shape: GridShape,
    /// `cells[i]..cells[i + 1]` indexes `refs` for cell `i`.
    cells: Vec<u32>,
    refs: Vec<u32>,
    prims: Vec<P>,
    mailbox: bool,
    exact: bool,
    valid_prims: usize,
}

impl<P> Grid<P> {
    /// The grid's box and resolution.
    pub fn shape(&self) -> &GridShape {
        &self.shape
    }

    /// The offsets into [`references`](Self::references), one per cell plus one.
    pub fn cell_offsets(&self) -> &[u32] {
        &self.cells
    }

    /// The primitive references of all cells, cell by cell: input indices of the primitives.
    pub fn references(&self) -> &[u32] {
        &self.refs
    }
}

impl<P: Primitive> Accel for Grid<P> {
    type Prim = P;
    type Params = GridParams;
    const NAME: &'static str = "grid";

    fn presets() -> Vec<(&'static str, GridParams)> {
        vec![
            ("standard", GridParams::standard()),
            ("nomailbox", GridParams::no_mailbox()),
            ("bbox", GridParams::bbox_insertion()),
        ]
    }

    /// Builds the grid; invalid primitives (see [`Primitive::is_valid`]) are left out.
    ///
    /// Copies the primitives once, into the vector the leaves index, and builds over that.
    ///
    /// # Panics
    /// If the grid would hold more than 2³² - 1 references (far beyond what `max_cells` and
    /// memory allow for triangles).
    fn build_from<G: rt_core::Geometry<Prim = P> + ?Sized>(
        geometry: &G,
        params: &GridParams,
    ) -> Self {
        let prims = geometry.to_vec();
        let b = builder::build(&prims, params);
        Self {
            shape: b.shape,
            cells: b.cells,
            refs: b.refs,
            prims,
            mailbox: params.mailbox,
            exact: params.exact_insertion,
            valid_prims: b.valid_prims,
        }
    }

    fn bounds(&self) -> rt_core::Aabb {
        if self.valid_prims == 0 {
            rt_core::Aabb::EMPTY
        } else {
            self.shape.bounds()
        }
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.cells.capacity() * size_of::<u32>()
            + self.refs.capacity() * size_of::<u32>()
            + self.prims.capacity() * size_of::<P>()
    }

    fn build_stats(&self) -> BuildStats {
        let n = self.shape.cell_count();
        let empty = self.cells.windows(2).filter(|w| w[0] == w[1]).count();
        let res = self.shape.resolution_per_axis();
        BuildStats {
            nodes: n,
            leaves: n,
            empty_leaves: empty,
            max_depth: 0,
            prim_refs: self.refs.len(),
            valid_prims: self.valid_prims,
            extra: vec![
                ("resolution_x", f64::from(res[0])),
                ("resolution_y", f64::from(res[1])),
                ("resolution_z", f64::from(res[2])),
            ],
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

// With `share-dyn`, debug and test builds of the crates that use a `Grid` as a trait
// object (the shootout, the renderer's tests) link this crate's copy of its methods instead of
// compiling their own.
#[cfg(feature = "share-dyn")]
rt_core::share_dyn_accel!(Grid);

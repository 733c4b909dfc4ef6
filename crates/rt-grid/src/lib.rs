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
//! run in parallel with rayon for large inputs; the result does not depend on it. O(N + cells)
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
//! # Closest points
//! [`Accel::closest_point`] visits cells in growing shells around
//! the point's cell ([`nearest::shells`]), tests each cell the query's ball still reaches, and stops
//! at the first shell wholly outside the ball. Far from the surface the ball holds many empty cells
//! that a hierarchy would discard at once: on the bunny, 100,000 points (`cargo xtask compare --query closest-point --scene ../shared/meshes/stanford-bunny.obj --structures bvh,kdtree,grid,hgrid,octree`), 4,308 cells and
//! 315 tests per query, 7 times brute force's speed.
//!
//! # Measured
//! The BVH in this section is the binary SAH tree: the `bvh` row when these figures were
//! measured, `bvh-binary` since rt-bvh's default became its 8-wide tree (faster still; see
//! rt-bvh's documentation).
//!
//! One run each of `cargo xtask compare --scene S --rays R --structures
//! bvh-binary,kdtree,grid,grid-nomailbox` (1024×768 rays, 2 threads, 0 mismatches
//! everywhere); tests and Mrays/s per ray kind:
//!
//! | scene, rays | bvh-binary | kdtree | grid | grid without mailbox |
//! | --- | --- | --- | --- | --- |
//! | `random-soup` (20k random triangles), primary | 3.62 / 7.00 | 1.35 / 10.7 | 2.37 / 9.78 | 3.69 / 8.25 |
//! | `random-soup`, incoherent | 12.5 / 1.06 | 3.65 / 1.65 | 7.63 / 3.16 | 10.9 / 2.42 |
//! | `random-soup`, shadow | 8.84 / 3.66 | 4.33 / 4.27 | 6.57 / 6.11 | 9.53 / 4.86 |
//! | bunny, primary | 0.793 / 15.7 | 0.764 / 16.2 | 6.67 / 4.44 | 6.98 / 4.03 |
//! | bunny, incoherent | 1.59 / 4.62 | 1.52 / 2.22 | 13.5 / 1.74 | 14.2 / 1.85 |
//! | `teapot-in-stadium`, primary | 2.04 / 7.93 | 2.56 / 10.7 | 533 / 0.191 | 537 / 0.190 |
//!
//! Where primitives are spread evenly the grid is the fastest structure here (1.4× the BVH on
//! primary rays, 3× on incoherent ones), and the mailbox saves a third of its primitive tests.
//! On the bunny, a surface, 94% of the cells are empty and the others hold 11 triangles each:
//! the grid runs at 0.28× the BVH, and the mailbox saves little because the bunny's triangles are
//! small next to the cells. On the teapot in a stadium (a later run, with `hgrid` in the list)
//! the cells sized for the stadium hold thousands of the teapot's triangles and the grid tests
//! 533 per ray: the lecture's failure, which `rt-hgrid` answers. Builds: 66 ms for the random
//! soup (11.1 references per triangle; the exact overlap tests dominate) and 14 ms for the bunny
//! (2.68), on 2 threads.
//!
//! Exact insertion against listing every cell of a primitive's box (`GridParams::bbox_insertion`,
//! row `grid-bbox`), one run of `cargo xtask compare --scene random-soup --structures
//! bvh-binary,grid,grid-bbox`: 11.1 against 31.9 references per triangle, 2.36 against 6.65
//! tests per primary ray, 12.1 against 6.37 Mrays/s, for a build of 51 against 5 ms. On the
//! bunny, whose triangles are small next to the cells, 2.68 against 3.17 references per
//! triangle.
//!
//! `density` trades cells for tests. `cargo run --release -p rt-grid --example density_sweep`
//! (bunny, 512×384 primary rays, single-threaded, one run): λ = 1 gives 69k cells and 13.6 tests
//! per ray, λ = 4 277k and 6.7, λ = 16 1.1M and 3.2; the speed peaks at λ = 4 (2.33 Mrays/s;
//! 1.96 at λ = 1, 2.03 at λ = 16) as empty steps replace tests. With `-- random-soup` it peaks at
//! λ = 2–4 (5.91 and 5.90 Mrays/s), hence the default λ = 4.
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
mod cell;
pub mod dda;
pub mod nearest;
mod regions;
mod traverse;
mod validate;

pub use builder::cells_overlapping;
pub use cell::{GridShape, MAX_RESOLUTION};
pub use rt_core::ValidationError;

use rt_core::{Accel, BuildStats, Hit, Primitive, Ray, Stats};

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
    /// # Panics
    /// If the grid would hold more than 2³² - 1 references (far beyond what `max_cells` and
    /// memory allow for triangles).
    fn build(prims: &[P], params: &GridParams) -> Self {
        Self::build_from(prims, params)
    }

    /// Copies the primitives once, into the vector the leaves index, and builds over that.
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

    #[inline]
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        self.walk::<S, false>(ray, stats)
    }

    #[inline]
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        self.walk::<S, true>(ray, stats).is_some()
    }

    fn bounds(&self) -> rt_core::Aabb {
        if self.valid_prims == 0 {
            rt_core::Aabb::EMPTY
        } else {
            self.shape.bounds()
        }
    }

    /// Cells in growing shells around the centre ([`nearest::shells`]).
    fn ball_query<Q: rt_core::BallQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.ball(query, stats);
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.cells.capacity() * size_of::<u32>()
            + self.refs.capacity() * size_of::<u32>()
            + self.prims.capacity() * size_of::<P>()
    }

    fn regions(&self, visit: &mut dyn FnMut(rt_core::Region)) {
        self.walk_regions(visit);
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
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

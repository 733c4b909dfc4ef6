//! An adaptive octree for CPU ray tracing, walked by Revelles, Ureña & Lastra's parametric
//! front-to-back traversal.
//!
//! # The structure
//! The root is a cube around the scene. A node holding more than `max_prims` primitives is cut
//! at its centre into eight equal children, recursively, down to `max_depth` (Glassner's octree
//! for ray tracing, 1984). So the cells adapt to the scene like a kd-tree's, with no split to
//! choose: large where space is empty, small where primitives crowd. A triangle is listed only
//! in the children it really overlaps (the exact triangle–box clipping shared in `rt-core`,
//! [`Primitive::clip_bounds`]), not in every child its bounding box reaches.
//!
//! The root is made cubic (centred on the scene box, with its longest side): every cell is then
//! a cube, and a flat scene (a terrain, a single planar mesh) does not produce nodes of zero
//! thickness, whose mid-plane would coincide with their faces. The price is empty space beside
//! a flat scene, which the first cuts turn into empty leaves that the walk skips without a
//! visit.
//!
//! # Build
//! Each node's primitives are split among its children with their boxes clipped to the node, so
//! a primitive that lies in one octant goes there without a test, and the others are clipped
//! against each child they reach. A node also stays a leaf when cutting it would separate
//! nothing: one child would keep all of its primitives while the other seven together hold at
//! least half as many references again (a fan of triangles around a vertex, identical triangles
//! on a mid-plane). A cluster inside one octant, such as a teapot in a stadium's corner cell, is
//! still zoomed into, since little lies outside it. Memory is bounded whatever the input: the
//! tree never holds more than `max_refs_per_prim` references per primitive (each node has a
//! budget of references, and what its children's lists leave of it is shared among them), and
//! the build, depth first, holds at most about the root's list again as scratch (28 bytes a
//! reference). Large nodes' subtrees are built in parallel (feature `parallel`), and the result
//! does not depend on the threads. Cost: O(N) clipped primitives per level, O(N log N) in all for
//! primitives spread over a surface.
//!
//! # Memory
//! 8 bytes per node ([`Node`]: a reference range, or the index of its children's [`Block`]). The
//! eight children of a node sit together in one 64-byte block, empty ones included, so a child
//! is found without decoding a mask, and a node's children share one cache line. Plus 4 bytes
//! per reference and the copy of the primitives.
//!
//! # Traversal
//! Revelles, Ureña & Lastra's parametric algorithm (2000), iterative, with a fixed stack of
//! one frame per level. For each node the walk computes, per axis, the ray parameters of the
//! near face, the far face and the mid-plane. The first child follows from the entry parameter
//! and the mid-planes already crossed, and the following ones from the mid-planes crossed next,
//! in order, until the node's exit. Negative directions are mirrored, which swaps near and far
//! on that axis and XORs the child index with the mask of negative axes. Zero (`±0`) direction
//! components have no parameter on their axis: the ray stays on its origin's side of the
//! mid-plane there. Rays may start inside the octree; children behind `t_min` are skipped.
//! Crossings within [`NEAR_TIE`](rt_core::NEAR_TIE) of each other are taken in both orders, so
//! rounding never skips a cell the ray passes through near an edge or a corner. See
//! `traverse.rs` for the details.
//!
//! A visited node costs the parameters of its six faces (two subtractions and two
//! multiplications of 3-vectors) and a comparison with the best hit; an interior node also the
//! parameters of its three mid-planes, a sort of three numbers, and the read of its children's
//! 64-byte block, which tells empty children apart before they are visited. A leaf costs its primitive tests, minus
//! those the per-ray [`Mailbox`](rt_core::Mailbox) saves (the last 8 primitives tested, kept on
//! the stack, as the grids do). The in-cell hit rule: a hit beyond the current leaf is kept as
//! the best so far, and the walk stops at the first child that starts beyond the best hit.
//! Any-hit queries stop at the first hit.
//!
//! # Knobs
//! - `max_prims` (default 8): a node with more primitives is cut. Lower means deeper trees,
//!   fewer primitive tests and more memory. [`OctreeParams::lean`] uses 16, which on the bunny
//!   takes less memory than the uniform grid.
//! - `max_depth` (default 12, at most [`MAX_DEPTH`]): below it, fans of thin triangles around a
//!   pole (surfaces of revolution, such as the teapot's base) keep nodes crowded however far they
//!   are cut. On the teapot in a stadium a deeper limit saves few tests for much more memory and
//!   build time and no speed, while a shallower one cannot reach the teapot's triangles from
//!   the stadium's scale.
//! - `max_refs_per_prim` (default 16): the safety bound on memory.
//!
//! `cargo run --release -p rt-octree --example threshold_sweep -- <scene>` prints the trade-off
//! for a scene, with the uniform grid as the first row.
//!
//! # Bundles
//! [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`] trace coherent rays as packets:
//! the lanes of a bundle share their direction octant, so one child order is front to back for
//! all of them. Each stack entry carries the lanes that entered its parent; the first of them
//! is tested against the node's box with its own slab test and, when it fails (and at leaves),
//! all of them, eight per vector step, so lanes that have hit drop out; one interval test
//! ([`Bundle::may_enter`](rt_simd::Bundle::may_enter)) culls a box for the whole bundle. A
//! leaf's primitives are tested against its lanes with the single ray's watertight arithmetic,
//! eight lanes per vector step (`bundle.rs`). Bundles whose directions spread go singly. Each
//! ray answers exactly as its single-ray query.
//!
//! # Closest points
//! [`Accel::closest_point`] visits children nearest first, cutting
//! each box at the same midpoints the builder used, and skips any child farther than the best
//! distance so far (`nearest.rs`).
//!
//! # Saving and loading
//! [`Persist`] writes a built tree to a versioned file and reads it back
//! without rebuilding: the root, the blocks of children, the references, the primitives and the
//! root cube (the sections are listed in [`persist`]). Loading checks the file's framing and
//! checksum, then runs [`Octree::validate`], so a truncated, damaged or hostile file is refused
//! with a typed [`LoadError`] and a loaded tree answers every query
//! bit for bit as the saved one.
//!
//! # Measurements
//! On the generated results pages, one per machine kind, listed by `docs/results.md` in the
//! repository (date, commit, CPU; written by `cargo xtask results`). What they show: the octree visits a fraction of the uniform grid's
//! cells on surfaces and needs two orders of magnitude fewer tests on the teapot in a stadium,
//! in less memory; on surfaces the BVHs are faster still (cubes cannot follow a surface as
//! fitted boxes do, and a step costs more); where primitives are spread evenly the uniform grid
//! is better than both. Fewer visits do not always pay: on incoherent rays the octree is no
//! faster than the grid.
//!
//! # Example
//! ```
//! use rt_octree::{Octree, OctreeParams};
//! use rt_core::{Accel, Ray, Triangle, glam::Vec3};
//!
//! let tris = vec![
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)),
//!     Triangle::new(Vec3::new(-1.0, -1.0, 3.0), Vec3::new(1.0, -1.0, 3.0), Vec3::new(0.0, 1.0, 3.0)),
//! ];
//! let octree = Octree::build(&tris, &OctreeParams::default());
//! let hit = octree.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).unwrap();
//! assert_eq!((hit.prim, hit.t), (1, 2.0));
//! assert!(octree.occluded(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)));
//! assert!(octree.validate().is_ok());
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

pub use builder::MAX_DEPTH;
pub use node::{Block, Node};
pub use rt_core::ValidationError;
/// Saving and loading, re-exported so that a user of this crate alone can save and load.
pub use rt_persist::{LoadError, Persist};

use rt_core::{Aabb, Accel, BuildStats, Primitive};

/// Build and traversal parameters. `Default` is [`OctreeParams::standard`].
#[derive(Clone, Debug, PartialEq)]
pub struct OctreeParams {
    /// A node holding more than this many primitives is cut into eight (below `max_depth`).
    pub max_prims: u32,
    /// The deepest a node may lie (the root has depth 0); clamped to [`MAX_DEPTH`].
    pub max_depth: u32,
    /// The most references the octree may hold, per valid primitive (at least 2¹⁴ in all). The
    /// root has that budget; a node is cut only if its children's lists fit in its budget, and
    /// the rest of its budget is shared among them in proportion to their lists. Real meshes stay
    /// far below it; it bounds memory for adversarial input.
    pub max_refs_per_prim: f32,
    /// Skip primitives this ray tested in the last few tests.
    pub mailbox: bool,
    /// Build the subtrees of large nodes in parallel (rayon); the octree is the same either way.
    pub parallel: bool,
}

impl OctreeParams {
    /// Nodes of more than 8 primitives are cut, down to depth 12.
    pub fn standard() -> Self {
        Self {
            max_prims: 8,
            max_depth: 12,
            max_refs_per_prim: 16.0,
            mailbox: true,
            parallel: true,
        }
    }
}

impl OctreeParams {
    /// Fewer, fuller leaves for a memory budget like the uniform grid's: nodes of more than 16
    /// primitives are cut.
    pub fn lean() -> Self {
        Self {
            max_prims: 16,
            ..Self::standard()
        }
    }
}

impl Default for OctreeParams {
    fn default() -> Self {
        Self::standard()
    }
}

/// An octree over primitives of type `P`.
#[derive(Clone, Debug)]
pub struct Octree<P> {
    root: Node,
    blocks: Vec<Block>,
    refs: Vec<u32>,
    bounds: Aabb,
    prims: Vec<P>,
    mailbox: bool,
    valid_prims: usize,
    depth: u32,
}

impl<P> Octree<P> {
    /// The root node; its box is [`Octree::bounds`].
    pub fn root(&self) -> Node {
        self.root
    }

    /// The blocks of eight children that interior nodes point to.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// The primitive references: input indices of the primitives, leaf by leaf.
    pub fn references(&self) -> &[u32] {
        &self.refs
    }

    /// The root's box: the cube around the valid primitives' bounds.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The leaves, each with its box and depth, depth first.
    pub fn leaves(&self) -> Vec<(Node, Aabb, u32)> {
        let mut out = Vec::new();
        let mut todo = vec![(self.root, self.bounds, 0)];
        while let Some((node, b, depth)) = todo.pop() {
            match node.children() {
                None => out.push((node, b, depth)),
                Some(block) => {
                    let mid = node::midpoint(&b);
                    for (i, &c) in self.blocks[block].0.iter().enumerate().rev() {
                        todo.push((c, node::child_box(&b, mid, i), depth + 1));
                    }
                }
            }
        }
        out
    }
}

impl<P: Primitive> Accel for Octree<P> {
    type Prim = P;
    type Params = OctreeParams;
    const NAME: &'static str = "octree";

    fn presets() -> Vec<(&'static str, OctreeParams)> {
        vec![
            ("standard", OctreeParams::standard()),
            ("lean", OctreeParams::lean()),
        ]
    }

    /// Builds the octree; invalid primitives (see [`Primitive::is_valid`]) are left out.
    ///
    /// Copies the primitives once, into the vector the leaves index, and builds over that.
    ///
    /// # Panics
    /// If the octree would hold more than 2³² - 1 references or blocks (far beyond what memory
    /// allows for triangles, since a split that would multiply references is refused).
    fn build_from<G: rt_core::Geometry<Prim = P> + ?Sized>(
        geometry: &G,
        params: &OctreeParams,
    ) -> Self {
        let prims = geometry.to_vec();
        let b = builder::build(&prims, params);
        Self {
            root: b.root,
            blocks: b.blocks,
            refs: b.refs,
            bounds: b.bounds,
            prims,
            mailbox: params.mailbox,
            valid_prims: b.valid_prims,
            depth: b.depth,
        }
    }

    /// The root cube (a cube around the scene box, see [`Octree::bounds`]).
    fn bounds(&self) -> Aabb {
        if self.valid_prims == 0 {
            Aabb::EMPTY
        } else {
            self.bounds
        }
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.blocks.capacity() * size_of::<Block>()
            + self.refs.capacity() * size_of::<u32>()
            + self.prims.capacity() * size_of::<P>()
    }

    fn build_stats(&self) -> BuildStats {
        let nodes = 1 + 8 * self.blocks.len();
        let leaves = nodes - self.blocks.len();
        let empty = usize::from(self.root.is_empty_leaf())
            + self
                .blocks
                .iter()
                .flat_map(|b| b.0.iter())
                .filter(|n| n.is_empty_leaf())
                .count();
        BuildStats {
            nodes,
            leaves,
            empty_leaves: empty,
            max_depth: self.depth as usize,
            prim_refs: self.refs.len(),
            valid_prims: self.valid_prims,
            extra: vec![],
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

// With `share-dyn`, debug and test builds of the crates that use a `Octree` as a trait
// object (the shootout, the renderer's tests) link this crate's copy of its methods instead of
// compiling their own.
#[cfg(feature = "share-dyn")]
rt_core::share_dyn_accel!(Octree);

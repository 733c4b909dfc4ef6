//! A cost-optimized kd-tree for CPU ray tracing, built by the surface area heuristic.
//!
//! # The structure
//! A binary space partition by axis-aligned planes. Each interior node cuts its cell in two at
//! one plane; each leaf cell lists the primitives that overlap it. Unlike a BVH, cells never
//! overlap, so a ray visits the leaves it crosses in order of distance and can stop at the first
//! one that yields a hit inside it. The price is that a primitive crossing a plane is referenced
//! from both sides (the duplication factor), and that traversal needs the in-cell rule below.
//!
//! A good tree is long and thin: deep (tens of levels), leaves of one to three primitives, and
//! large empty cells cut off early so that rays cross empty space in a few steps. The surface area
//! heuristic produces this shape when it is evaluated on every candidate plane, which the builder
//! does in O(N log N) (Wald & Havran 2006).
//!
//! # Build
//! - **Cost model** (Wald & Havran 2006; pbrt-v4 §7.4 for the kd-tree of pbrt-v3): a split of a
//!   cell `V` into `V_L`, `V_R` with `N_L`, `N_R` primitives costs
//!   `λ · (K_T + K_I · (P_L · N_L + P_R · N_R))`, with `P = SA(child) / SA(V)` and `λ =
//!   1 - empty_bonus` when one side is empty; a leaf costs `K_I · N`. A node becomes a leaf when
//!   no plane beats the leaf cost (or after `max_bad_refines` such planes on one path, as in
//!   pbrt), when it holds at most `leaf_size` primitives (after the empty-space cuts below), or
//!   at the depth limit `depth_base + 1.3 · log2 N` (pbrt: `8 + 1.3 · log2 N`).
//! - **Empty space** (`empty_cut`): an empty slab at a face of the cell that spans at least this
//!   fraction of the cell's extent is cut off without pricing any plane. The SAH with an
//!   empty-side bonus would pick most such cuts anyway; skipping the sweep there saves build
//!   time for slightly more primitive tests (see the sweep below).
//! - **O(N log N) build**: the split candidates (the bounds of each primitive's part in the cell,
//!   per axis) are sorted once, and each node splits the sorted lists in linear time; only the
//!   primitives straddling the plane get new candidates, which are sorted and merged in.
//! - **Planar primitives** (a triangle lying in a candidate plane, or whose part in the cell is
//!   flat) are counted on neither side while the plane is priced, then put on the cheaper side.
//! - **Perfect splits** (`perfect_splits`): a straddling triangle is clipped to each child cell
//!   ([`rt_core::clip_triangle_bounds`]), so its candidates are the bounds of the part inside
//!   and a triangle that merely has its bounding box in a cell is not referenced there.
//! - **Parallel** (feature `parallel`, default): the two subtrees of a large node are built at
//!   once (`rt_core::par::join`), each into its own buffer, appended in a fixed order: the tree
//!   is the same as the sequential build's.
//!
//! # Memory
//! 8 bytes per [`Node`] (split position, then axis or leaf flag in two bits and a 30-bit index;
//! children are stored side by side, so one index finds both; no bounding box), 4 bytes per
//! primitive reference, plus the primitives themselves.
//!
//! # Traversal
//! Front to back (Hapala & Havran's listing in the lecture). A step at an interior node costs
//! one subtraction and one multiplication (the distance to the plane) and picks the near child
//! by the direction's sign, with no comparison; a leaf tests its primitives, skipping those
//! among the last 8 this ray tested ([`rt_core::Mailbox`]: a primitive spanning several leaves
//! is tested once). A hit
//! counts as final only if its distance lies inside the current leaf's interval
//! `[t_entry, t_exit]`, since a primitive spanning several cells may be hit behind a closer
//! primitive in the next leaf; such a hit is kept as the best so far, and the walk stops at the
//! first leaf that starts beyond it. Rays lying in a split plane visit both sides. Two traversals
//! ([`Traversal`]):
//! - `Stack`: far children go on a fixed stack of [`MAX_DEPTH`] entries ([`rt_core::Stack`]),
//!   neither allocated nor zeroed per ray.
//! - `Restart`: stackless kd-restart with push-down (Foley & Sugerman 2005; Horn et al. 2007).
//!   After a leaf it descends again from the deepest node known to hold the rest of the ray,
//!   with the interval starting at the leaf's exit. A ray that passes exactly through an edge or
//!   corner of cells, or lies in a split plane, finishes with the stack walk (restart cannot
//!   visit a leaf it only touches at one point), so the answers stay exact.
//!
//! Any-hit queries return at the first hit in the ray's interval.
//!
//! # Bundles
//! [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`] trace coherent rays as packets
//! (Wald 2004, §7): the lanes of a bundle share their direction signs, so one child order at
//! every plane is front to back for all of them. Each stack entry carries its node's cell and
//! the lanes that entered its parent; the walk tests the first of those lanes against the cell
//! with its own slab test and, when it fails, all of them eight per vector step, with each
//! lane's best hit so far, so lanes that have hit drop out (the first-active-lane rule of Wald,
//! Boulos & Shirley 2007). One interval test over the bundle culls a cell for all lanes at
//! once, and a leaf tests its primitives against its lanes with the single ray's watertight
//! arithmetic, eight lanes per vector step (`bundle.rs`). Lanes that disagree at a plane need no
//! special case: each child is entered by the lanes whose test reaches its cell, and a lane in
//! the plane reaches both, as the single walk's in-plane rule has it. Every ray answers exactly
//! as its single-ray query does, whichever [`Traversal`] that uses. Bundles whose directions
//! spread more than [`MAX_SPREAD`] go singly.
//!
//! # Closest points
//! [`Accel::closest_point`] descends the near side of each plane
//! first and goes to the far side only while the query's ball reaches across it; each stack entry
//! carries its cell, cut from the scene box by the planes above it (`nearest.rs`).
//!
//! # Choosing the constants
//! The ratio K_T / K_I sets the leaf size, and the depth limit and the bad-refine allowance
//! decide how far a path may go. Wald & Havran's published constants
//! ([`KdParams::wald_havran`]: K_T 15, depth `8 + 1.3 · log2 N`) price every node down to one
//! primitive. The default ([`KdParams::sah`]) lets a path take up to three non-improving splits,
//! which finds the splits that pay off two levels down, while a higher K_T and one level less of
//! depth keep the tree from growing where they do not; cutting off wide empty slabs without
//! pricing pays for most of the extra build time. It stops pricing planes at three primitives
//! (`leaf_size: 3`): a node of at most three primitives becomes a leaf (its wide empty slabs are
//! still cut off). Pricing the planes of a node of two or three primitives mostly adds levels of
//! small cells, which a ray crosses in more steps than the tests they save; on the meshes
//! measured, stopping at three was faster on every ray kind and built faster, and stopping at
//! four or more lost on some views. [`KdParams::fewest_tests`] is the same tree priced down to
//! one primitive: it keeps the textbook promise of fewer primitive tests per ray than the binary
//! SAH BVH, and pays for it in nodes, build time and speed. Prefer `wald_havran` for a smaller
//! tree than `fewest_tests`'s at the same leaf size. Keep `leaf_size` at 0 and lower
//! `traversal_cost` when a primitive test is expensive compared with a traversal step (curved or
//! displaced primitives).
//! `cargo run --release -p rt-kdtree --example cost_sweep` prints the trade-off (nodes, depth,
//! references, visits and tests per ray, build time, speed) on the bunny.
//!
//! # Saving and loading
//! [`Persist`] writes a built tree to a versioned file and reads it back
//! without rebuilding: the nodes, the references, the primitives and the root cell (the sections
//! are listed in [`persist`]). Loading checks the file's framing and checksum, then runs
//! [`KdTree::validate`], so a truncated, damaged or hostile file is refused with a typed
//! [`LoadError`] and a loaded tree answers every query bit for bit as
//! the saved one.
//!
//! # Measurements
//! The kd-tree's figures beside every other structure's (build time, memory, shape, visits and
//! tests per ray, speed on several scenes and ray kinds, one thread and two), and the sweep
//! above, are on the generated results pages, one per machine kind (`docs/results.md` in the
//! repository lists them), stamped with the date, the commit and the CPU and written by
//! `cargo xtask results`. In short: the `fewest-tests` tree
//! tests fewer triangles per ray than the binned-SAH BVH and the default a few more; both visit
//! several times more nodes and build several times slower than the wide BVH, and the stackless
//! restart pays for its restarts with extra visits (on a CPU a fixed stack costs nothing worth
//! saving).
//!
//! # Example
//! ```
//! use rt_kdtree::{KdParams, KdTree};
//! use rt_core::{Accel, Ray, Triangle, glam::Vec3};
//!
//! let tris = vec![
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)),
//!     Triangle::new(Vec3::new(-1.0, -1.0, 3.0), Vec3::new(1.0, -1.0, 3.0), Vec3::new(0.0, 1.0, 3.0)),
//! ];
//! let tree = KdTree::build(&tris, &KdParams::sah());
//! let hit = tree.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).unwrap();
//! assert_eq!((hit.prim, hit.t), (1, 2.0));
//! assert!(tree.occluded(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)));
//! assert!(tree.validate().is_ok());
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

pub use bundle::MAX_SPREAD;
pub use node::Node;
pub use rt_core::ValidationError;
/// Saving and loading, re-exported so that a user of this crate alone can save and load.
pub use rt_persist::{LoadError, Persist};

use rt_core::{Aabb, Accel, BuildStats, Primitive, Ray, RayQuery, Stats};

/// The deepest a tree may be (the size of the fixed traversal stack); `max_depth` is clamped to it.
pub const MAX_DEPTH: usize = 64;

/// Which traversal a tree uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Traversal {
    /// Front to back with a fixed-size stack of far children.
    #[default]
    Stack,
    /// Stackless kd-restart with push-down.
    Restart,
}

/// Build and traversal parameters. `Default` is [`KdParams::sah`].
#[derive(Clone, Debug, PartialEq)]
pub struct KdParams {
    /// K_T: the cost of one traversal step, in the same unit as `intersection_cost`.
    pub traversal_cost: f32,
    /// K_I: the cost of one primitive test.
    pub intersection_cost: f32,
    /// The fraction of the cost waived for a split with an empty side (`1 - λ`), in `0..=1`.
    pub empty_bonus: f32,
    /// Clip straddling primitives to the child cells before computing their split candidates.
    pub perfect_splits: bool,
    /// Cut off an empty slab at a face of the cell without pricing any split when the slab spans
    /// at least this fraction of the cell's extent on its axis; `0` prices every split.
    pub empty_cut: f32,
    /// Depth limit; `None` is `depth_base + 1.3 · log2 N`, rounded. Clamped to [`MAX_DEPTH`].
    pub max_depth: Option<u32>,
    /// The constant of the automatic depth limit (pbrt uses 8).
    pub depth_base: f32,
    /// How many splits that do not lower the cost a path may take before a node becomes a leaf.
    pub max_bad_refines: u32,
    /// Nodes with at most this many primitives price no split plane: they become leaves, after
    /// any empty slabs around them wide enough for `empty_cut` are cut off.
    pub leaf_size: u32,
    /// Build the subtrees of large nodes in parallel (rayon); the tree is the same either way.
    pub parallel: bool,
    /// The traversal used by [`Accel::intersect`] and [`Accel::occluded`].
    pub traversal: Traversal,
}

impl KdParams {
    /// The default, the tree that traces fastest at equal exactness: Wald & Havran's cost model
    /// and perfect splits, with constants chosen at a bounded build time (see "Choosing the
    /// constants" in the crate documentation): K_T = 25, K_I = 20, λ = 0.8 for an empty side, up
    /// to three splits that do not lower the cost on a path, depth limit `7 + 1.3 · log2 N`,
    /// empty slabs wider than a quarter of the cell cut off without pricing, and no plane priced
    /// in a node of three primitives or fewer (`leaf_size: 3`).
    pub fn sah() -> Self {
        Self {
            leaf_size: 3,
            ..Self::fewest_tests()
        }
    }

    /// [`sah`](Self::sah) priced down to one primitive (`leaf_size: 0`): the tree that tests the
    /// fewest primitives per ray, fewer than the binary SAH BVH, for more nodes, a slower build
    /// and slower traversal. The lecture's claim about the kd-tree is shown with this preset.
    pub fn fewest_tests() -> Self {
        Self {
            traversal_cost: 25.0,
            intersection_cost: 20.0,
            empty_bonus: 0.2,
            perfect_splits: true,
            empty_cut: 0.25,
            max_depth: None,
            depth_base: 7.0,
            max_bad_refines: 3,
            leaf_size: 0,
            parallel: true,
            traversal: Traversal::Stack,
        }
    }

    /// Wald & Havran (2006) as published: K_T = 15, K_I = 20, λ = 0.8 for an empty side, perfect
    /// splits, every node priced down to one primitive and a leaf as soon as no split beats it,
    /// and pbrt's depth limit `8 + 1.3 · log2 N`.
    pub fn wald_havran() -> Self {
        Self {
            traversal_cost: 15.0,
            empty_cut: 0.0,
            depth_base: 8.0,
            max_bad_refines: 0,
            ..Self::fewest_tests()
        }
    }

    /// pbrt-v3's `KdTreeAccel` defaults: K_I = 80, K_T = 1, empty bonus 0.5, one primitive per
    /// leaf, up to two bad refines, depth limit `8 + 1.3 · log2 N`, candidates from bounding boxes
    /// (no perfect splits).
    pub fn pbrt() -> Self {
        Self {
            traversal_cost: 1.0,
            intersection_cost: 80.0,
            empty_bonus: 0.5,
            perfect_splits: false,
            empty_cut: 0.0,
            depth_base: 8.0,
            max_bad_refines: 2,
            leaf_size: 1,
            ..Self::sah()
        }
    }

    /// [`sah`](Self::sah) without perfect splits: candidates from bounding boxes cut to the cell.
    pub fn noclip() -> Self {
        Self {
            perfect_splits: false,
            ..Self::sah()
        }
    }

    /// The [`sah`](Self::sah) tree with the stackless kd-restart traversal.
    pub fn restart() -> Self {
        Self {
            traversal: Traversal::Restart,
            ..Self::sah()
        }
    }

    /// The depth limit for `n` primitives.
    pub fn resolved_max_depth(&self, n: usize) -> u32 {
        let auto = (f64::from(self.depth_base) + 1.3 * (n.max(1) as f64).log2())
            .round()
            .max(0.0) as u32;
        self.max_depth.unwrap_or(auto).min(MAX_DEPTH as u32)
    }
}

impl Default for KdParams {
    fn default() -> Self {
        Self::sah()
    }
}

/// A kd-tree over primitives of type `P`. See the [crate documentation](crate).
#[derive(Clone, Debug)]
pub struct KdTree<P: Primitive> {
    nodes: Vec<Node>,
    refs: Vec<u32>,
    prims: Vec<P>,
    bounds: Aabb,
    traversal: Traversal,
    max_depth: usize,
    leaves: usize,
    empty_leaves: usize,
    valid_prims: usize,
}

impl<P: Primitive> KdTree<P> {
    /// The nodes, root first; an interior node's children are `index()` and `index() + 1`.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The primitive references the leaves index into: input indices of the primitives.
    pub fn references(&self) -> &[u32] {
        &self.refs
    }

    /// The scene box: the root cell.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The traversal this tree uses.
    pub fn traversal(&self) -> Traversal {
        self.traversal
    }

    /// One ray by the tree's traversal, for query `q`, with the record of tested primitives
    /// its query needs ([`rt_core::leaf::walk_once`]: a mailbox of the last few, or every one).
    #[inline(always)]
    fn single<S: Stats, Q: RayQuery>(&self, ray: &Ray, q: &mut Q, stats: &mut S) {
        rt_core::leaf::walk_once::<_, { traverse::MAILBOX }, Q, S>(self, ray, q, stats);
    }

    /// Switches the traversal; the tree is the same for both.
    pub fn set_traversal(&mut self, traversal: Traversal) {
        self.traversal = traversal;
    }
}

impl<P: Primitive> rt_core::leaf::CellWalk for KdTree<P> {
    #[inline(always)]
    fn prim_count(&self) -> usize {
        self.prims.len()
    }

    /// The tree's traversal.
    #[inline(always)]
    fn walk<Q: RayQuery, S: Stats, M: rt_core::leaf::Seen>(
        &self,
        ray: &Ray,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) {
        match self.traversal {
            Traversal::Stack => self.traverse_stack(ray, q, seen, stats),
            Traversal::Restart => self.traverse_restart(ray, q, seen, stats),
        }
    }
}

impl<P: Primitive> Accel for KdTree<P> {
    type Prim = P;
    type Params = KdParams;
    const NAME: &'static str = "kdtree";

    fn presets() -> Vec<(&'static str, KdParams)> {
        vec![
            ("sah", KdParams::sah()),
            ("fewest-tests", KdParams::fewest_tests()),
            ("wald-havran", KdParams::wald_havran()),
            ("restart", KdParams::restart()),
            ("noclip", KdParams::noclip()),
            ("pbrt", KdParams::pbrt()),
        ]
    }

    /// Builds the tree; invalid primitives (see [`Primitive::is_valid`]) are left out.
    ///
    /// Copies the primitives once, into the vector the leaves index, and builds over that.
    ///
    /// # Panics
    /// If the tree would need more than 2³⁰ nodes or references, the most an 8-byte node can
    /// index (far beyond what fits in memory for triangles).
    fn build_from<G: rt_core::Geometry<Prim = P> + ?Sized>(
        geometry: &G,
        params: &KdParams,
    ) -> Self {
        let prims = geometry.to_vec();
        let b = builder::build(&prims, params);
        Self {
            nodes: b.nodes,
            refs: b.refs,
            prims,
            bounds: b.bounds,
            traversal: params.traversal,
            max_depth: b.max_depth,
            leaves: b.leaves,
            empty_leaves: b.empty_leaves,
            valid_prims: b.valid_prims,
        }
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.nodes.capacity() * size_of::<Node>()
            + self.refs.capacity() * size_of::<u32>()
            + self.prims.capacity() * size_of::<P>()
    }

    fn build_stats(&self) -> BuildStats {
        BuildStats {
            nodes: self.nodes.len(),
            leaves: self.leaves,
            empty_leaves: self.empty_leaves,
            max_depth: self.max_depth,
            prim_refs: self.refs.len(),
            valid_prims: self.valid_prims,
            extra: Vec::new(),
        }
    }

    // The walks, each in its phase file: the ray walk (`traverse.rs`), the bundle walk
    // (`bundle.rs`), closest points (`nearest.rs`), box overlap (`overlap.rs`), the drawing
    // (`regions.rs`).
    rt_core::accel_walks!(
        build: build_from,
        ray: single,
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

// With `share-dyn`, debug and test builds of the crates that use a `KdTree` as a trait
// object (the shootout, the renderer's tests) link this crate's copy of its methods instead of
// compiling their own.
#[cfg(feature = "share-dyn")]
rt_core::share_dyn_accel!(KdTree);

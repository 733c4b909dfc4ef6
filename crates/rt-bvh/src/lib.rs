//! A bounding volume hierarchy (BVH) for CPU ray tracing: by default an 8-wide tree traced with
//! SIMD kernels chosen at run time, and the binary tree of the lectures as presets.
//!
//! # The structure
//! A tree of axis-aligned boxes. Each interior node splits its primitives into groups, and each
//! group gets the tightest box around it; a leaf holds a few primitives. A ray only descends
//! into children whose boxes it enters, so it tests a few dozen boxes and a handful of
//! primitives instead of all of them. Unlike spatial subdivisions (kd-trees, grids), every
//! primitive is in exactly one leaf: no duplicated references and no mailboxing, at the price
//! of sibling boxes that may overlap.
//!
//! The same splits make two layouts ([`Layout`]):
//! - **Binary** (presets `binary`, `median`, `middle`): two children per node, a flat
//!   depth-first array of 32-byte [`Node`]s (pbrt-v4's layout: the first child follows its
//!   parent, the second child's index is stored), primitives reordered so each leaf is a
//!   contiguous range.
//! - **Wide** (the default, preset `wide`): the binary split tree collapsed so that a node has up
//!   to eight children, by splitting the child with the largest surface area until there are
//!   eight (Wald et al. 2008; Embree's BVH8 builder), built directly without the binary tree in
//!   between. One SIMD slab test handles all children of a node; triangles sit in leaves as
//!   [`TriPack`]s of four, one SIMD triangle test per pack ("pre-processed triangles", memory
//!   laid out by rate of access: the boxes a ray tests at every step, the triangles only in
//!   leaves).
//! - **Reinserted** (preset `reinserted`, either layout with
//!   [`BvhParams::reinsertion_passes`]): before the splits become nodes, the subtrees with the
//!   largest boxes are taken out one at a time and put back where they add the least area
//!   (Bittner, Hapala & Havran 2013), keeping every leaf. A top-down build never revisits a
//!   split; this repairs the ones made near the root where large and small triangles mix.
//! - **Stream** (preset `stream`, [`Ablation::stream_walk`]): the wide tree, whose stream
//!   queries ([`Accel::intersect_stream`]) walk up to 4,096 rays together, node by node, each
//!   node's rays filtered into its children's lists (Barringer & Akenine-Möller 2014). Still
//!   being measured, so off by default: the default stream queries trace ray by ray.
//!
//! # Layouts in bytes
//! - [`Node`] (binary): 32 bytes — its box (24), second child or first primitive (4), primitive
//!   count (2), split axis (1), padding (1). At most `2N - 1` nodes.
//! - [`WideNode`]: 256 bytes, four cache lines, aligned to one — the children's boxes as six
//!   rows of eight floats (minimum x, y, z, maximum x, y, z: 192), eight 32-bit [`ChildRef`]s
//!   (32: a node index, or a leaf of up to eight items with its first item), and 32 bytes of
//!   padding (224-byte nodes, which straddle cache lines, traced slower when measured).
//! - [`TriPack`]: 160 bytes for four triangles, 40 per triangle — nine rows of four floats
//!   (`v0`, `v1`, `v2` for the watertight test; `v0`, `e1`, `e2` for Möller–Trumbore) and four
//!   32-bit input indices. Unused lanes hold NaN.
//! - [`Accel::build_from`] reads a [`Mesh`](rt_core::Mesh) or an
//!   [`IndexedTriangles`](rt_core::IndexedTriangles) view through its indices straight into the
//!   packs, so no triangle list exists during the build. Packs that gathered their vertices
//!   through the mesh's indices instead would keep a little less memory but lose the side-by-side
//!   vertices the SIMD test loads, so the tree keeps its own copy.
//!
//! # Cost model
//! - **Build**: O(N log N). Each set of primitives is binned once (SAH) and partitioned once,
//!   and there are O(log N) levels for balanced splits; sets whose remaining depth budget only
//!   just fits a balanced tree are split by count, so the depth never exceeds [`MAX_DEPTH`] and
//!   degenerate input costs O(N · MAX_DEPTH) at worst. Scratch memory: 32 bytes per primitive,
//!   up to 512 KB per running build task for partitioning, plus, in the parallel build, the
//!   subtrees built as tasks until the finished tree is copied into place from them (up to a
//!   second copy of the tree), so a
//!   build's scratch stays below the finished tree plus its input (`cargo xtask scale` measures
//!   it). With the `parallel` feature (default) large inputs build on rayon's threads; the
//!   tree is the same, byte for byte, on any number of threads and without the feature.
//! - **Memory**: see the layouts above.
//! - **Traversal step** (wide): a node visit is one 8-lane slab test (six loads, six blends
//!   that pick each axis' near and far plane by the direction's sign, subtractions,
//!   multiplications and min/max, one compare and a mask: 256-bit operations with AVX2, two
//!   128-bit halves with SSE2), then the children entered are sorted by entry distance (closest
//!   hit: sorting networks, whose compare-exchanges do not branch on the distances) or pushed as
//!   they are (any hit), and every inner child entered is prefetched, so that the memory reads
//!   of the nodes a ray will visit overlap. A leaf visit is one 4-lane triangle test per pack
//!   (about forty vector operations; the watertight test skips its division when no lane can
//!   hit). The binary step: two scalar slab tests, the nearer child next, the farther pushed.
//! - **Stack**: fixed, `7 · MAX_DEPTH` entries of 8 bytes, not zeroed per ray.
//!
//! # Exactness
//! Each SIMD lane performs the scalar test's operations in the scalar test's order (Rust never
//! fuses a multiply and an add on its own), and the watertight test redoes an exactly zero edge
//! function in `f64` as the scalar one does: the kernels answer like
//! [`Triangle::intersect_watertight`](rt_core::Triangle::intersect_watertight) (or
//! [`rt_core::moller_trumbore_edges`] for [`MtTriangle`](rt_core::MtTriangle)) bit for bit. The
//! tie rule (smallest `t`, then smallest index) holds across lanes, packs and nodes.
//! Bit-identical copies of a triangle are stored once (only the smallest index can ever win),
//! so a million copies cost a ray one test instead of a million. A ray outside the precondition
//! of [`Accel`] (NaN, an origin beyond [`Ray::MAX_ORIGIN`], ...) returns before the root.
//!
//! # Kernels and dispatch ([`Kernels`])
//! The kernels are rt-simd's, written once over the lane width: the slab test of eight child
//! boxes and the watertight (or Möller–Trumbore) test of four triangles. A plain `cargo build`
//! runs the fastest the CPU has ([`Isa::detect`]; `RT_ACCEL_PORTABLE=1` forces the portable
//! ones): the wide traversal is compiled once inside a function with AVX2 and FMA enabled (for
//! CPUs with AVX2 or AVX-512), once with SSE2 intrinsics (every x86-64 CPU) and once on plain
//! arrays (any target, what aarch64 runs). [`Bvh::set_kernels`] or [`BvhParams::kernels`] force
//! one; `Scalar` tests each triangle with rt-core's scalar functions, the reference the others
//! are tested against. The crate has no `unsafe` code: rt-simd holds it.
//!
//! # Ray bundles
//! [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`] trace coherent rays (a camera's
//! 8×8 pixel tiles, shadow rays towards one light) through the wide tree together, up to 64 of
//! one direction octant at a time ([`rt_simd::bundle`]): the interval-culled packet traversal of
//! Wald, Boulos & Shirley (2007) with per-lane masks (Overbeck et al. 2008). At a node one
//! vector test bounds every lane against all eight children; the children left are tested lane
//! by lane with each lane's own slab arithmetic, eight lanes per vector (when the lanes share
//! one origin, as a camera's do, only the leaves are: an inner child then takes every active
//! lane, as Embree's coherent packets do, since the bound is nearly as tight). A leaf of triangle
//! packs tests each triangle against a vector of lanes (eight, or sixteen with AVX-512) where
//! the lanes that reached it fill their vectors (ray-parallel, as packet tracers do), else each
//! lane alone with its single ray's four-triangle test (`bundle.rs`, `traverse.rs`). Every lane answers exactly
//! as its single ray does, bit for bit (the conformance kit checks it in every order and bundle
//! size). A bundle of one ray, a ray with a zero direction component, a bundle whose
//! directions spread wider than a camera tile's (rays in random directions, which would share
//! few nodes) and one whose origins spread over a quarter of the tree's box (shadow rays from
//! scattered points, which part ways where the tree is finest) take the single-ray path. The binary tree walks bundles with a lane mask per
//! stack entry and the first-active-lane rule at each box, and tests each primitive of a leaf
//! against eight lanes per step (`bundle.rs`).
//!
//! # Tuning knobs ([`BvhParams`])
//! - `layout`: [`Layout::Wide`] (default) or [`Layout::Binary`].
//! - [`SplitMethod`]: binned SAH (the default; Wald 2007, pbrt-v4 §7.3), median split by count
//!   (quickselect along the longest centroid axis), or middle of the centroid extent (pbrt's
//!   `Middle`).
//! - `bins`: at most this many SAH buckets per axis (32); a set of `n` primitives gets
//!   `min(bins, 4 + n / 20)`, Embree's rule (Wald 2007 finds 16-32 within a few percent of a
//!   full sweep). Scenes of very unequal triangles (a small model in a large room) need the
//!   finer planes most: with 16 a split near the top of the tree cannot separate the small
//!   model from its large neighbours.
//! - `traversal_cost` / `intersection_cost`: the SAH constants (0.7 and 1 in the wide tree, 1
//!   and 1 in the binary one; pbrt-v4 uses 1/2 and 1). In the wide tree a leaf is priced by
//!   its packs of four, as Embree does; a node visit there tests eight boxes in one step, and a
//!   bundle tests a leaf's triangles one by one against its lanes, so splitting small leaves
//!   pays more often than packs alone suggest.
//! - `max_leaf_size`: the most primitives a leaf may hold (8; at most 32 triangles, or 8 other
//!   primitives, in the wide tree).
//! - `parallel` (true): build (and refit) large inputs on rayon's threads (with the crate's
//!   `parallel` feature; without it every build runs on the calling thread).
//! - `ablation` ([`Ablation`], measurement only): switch off the nearest-first order or the
//!   any-hit path, to measure what each gains (`cargo run --release -p rt-bvh --example steps`).
//!
//! # Closest points
//! [`Accel::closest_point`] walks the same tree nearest box first
//! (`nearest.rs`): the children a query's ball reaches are sorted by their distance from the point,
//! the nearest visited next and the others pushed, and a popped box is skipped once the best
//! distance so far is smaller. Triangle packs are read back lane by lane.
//!
//! # Instances
//! [`Instances`] is the top level of a two-level scene: a binary SAH BVH (one instance per leaf,
//! an instance priced at 8 node visits) over the world boxes of [`rt_instance::Instance`]s, each a
//! built structure of any kind (shared, never copied) with an affine transform. The walk is near
//! child first; at each instance the ray is carried into object space and the bottom level
//! traced up to the best hit so far. Node boxes are tested grown by
//! [`InstanceTransform::ray_pad`](rt_instance::InstanceTransform::ray_pad), so the rounding of that
//! transform never culls an instance holding a hit, and the answers equal
//! [`LinearInstances`](rt_instance::LinearInstances)'s exactly. Per instance: 192 bytes for the
//! record (both affine maps, the world box, the id, the shared structure's pointer) and the top
//! level's nodes.
//!
//! # Refitting
//! When the primitives move, [`Refit::refit`](rt_core::Refit::refit) keeps the tree and
//! updates its boxes bottom-up: `O(N)`, no allocation, the triangle packs re-read on rayon's
//! threads for large inputs. It first checks that the primitives can be followed (the same
//! count, and each stored one still valid and still a triangle; see
//! [`RefitError`](rt_core::RefitError)) and otherwise leaves the tree as it was. The tree keeps
//! the shape the build chose for the first positions; [`Bvh::sah_cost`] (`O(nodes)`) against
//! a fresh build's, or against [`Bvh::built_sah_cost`], measures how far it has drifted: a tree
//! bent by a wave stays close to a rebuilt one, while an explosion drives neighbours apart until
//! a rebuild and its trace are cheaper than a refit and its trace (`cargo xtask animate`).
//!
//! # Saving and loading
//! [`Persist`] writes a built tree to a versioned file and reads it back
//! without rebuilding: the nodes (binary or wide), the triangle packs or the reordered primitives
//! and their ids, and what the build left out; the SIMD kernels are chosen again for the loading
//! CPU (the sections are listed in [`persist`]). Loading checks the file's framing and checksum,
//! then runs [`Bvh::validate`], so a truncated, damaged or hostile file is refused with a typed
//! [`LoadError`] and a loaded tree answers every query bit for bit as
//! the saved one.
//!
//! # Measurements
//! Every figure (the shootout, rt-bvh against Embree 3, what each step from the binary tree
//! gains, builds at scale) is on the generated results pages, one per machine kind (`docs/results.md` in the
//! repository lists them), each stamped with the date, the commit and the CPU, and written by
//! `cargo xtask results`; the commands
//! that measure each part are `cargo xtask compare`, `cargo bench -p rt-benches --features
//! embree --bench peers`, `cargo run --release -p rt-bvh --example steps` and `--example large`.
//!
//! # Example
//! ```
//! use rt_bvh::{Bvh, BvhParams};
//! use rt_core::{Accel, Ray, Triangle, glam::Vec3};
//!
//! let tris = vec![
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)),
//!     Triangle::new(Vec3::new(-1.0, -1.0, 3.0), Vec3::new(1.0, -1.0, 3.0), Vec3::new(0.0, 1.0, 3.0)),
//! ];
//! let bvh = Bvh::build(&tris, &BvhParams::default()); // the wide tree
//! let hit = bvh.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).unwrap();
//! assert_eq!((hit.prim, hit.t), (1, 2.0));
//! assert!(bvh.validate().is_ok());
//! ```
//!
//! Loading a mesh, as in the README (compiled, not run: the file is yours):
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use rt_bvh::{Bvh, BvhParams};
//! use rt_core::{Accel, Ray, glam::Vec3};
//!
//! let mesh = rt_scene::load_obj("bunny.obj")?; // typed error naming file and line
//! // Read straight from the indices into the packs; `Bvh::build(&mesh.triangles(), ..)` builds
//! // the same tree through a triangle list.
//! let bvh = Bvh::build_from(&mesh, &BvhParams::default());
//! let ray = Ray::new(Vec3::new(0.0, 0.1, 1.0), Vec3::new(0.0, 0.0, -1.0));
//! if let Some(hit) = bvh.intersect(&ray) {
//!     // closest hit: triangle index, t, u, v
//!     println!("triangle {} at t = {}", hit.prim, hit.t);
//! }
//! let in_shadow = bvh.occluded(&ray); // any hit, stops at the first
//! # let _ = in_shadow;
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

mod builder;
mod bundle;
mod instance;
mod kernels;
mod nearest;
mod node;
mod overlap;
pub mod persist;
mod refit;
mod regions;
mod stream;
mod traverse;
mod validate;

pub use instance::Instances;
pub use node::{ChildRef, Node, PACK, TriPack, WIDTH, WideNode};
pub use rt_core::ValidationError;
/// Saving and loading, re-exported so that a user of this crate alone can save and load.
pub use rt_persist::{LoadError, Persist};
/// The instruction set of [`Kernels::Simd`], re-exported from rt-simd.
pub use rt_simd::Isa;

use rt_core::{Accel, BuildStats, Hit, Primitive, Ray, RayQuery, Stats, TriangleTest};
use rt_simd::{Bundle, Lanes};
use traverse::{Packs, Prims, ScalarPacks};

/// The deepest a tree may be, and so the size of the fixed traversal stacks.
pub const MAX_DEPTH: usize = 64;

/// How an interior node chooses where to split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplitMethod {
    /// Binned surface area heuristic: the plane that minimizes the expected cost of a ray
    /// through the node.
    Sah,
    /// Half the primitives on each side, along the longest centroid axis.
    Median,
    /// The middle of the centroid extent along its longest axis.
    Middle,
}

/// The node layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Two children per node, 32-byte [`Node`]s: the lecture's structure.
    Binary,
    /// Up to eight children per 256-byte [`WideNode`], tested with one SIMD slab test; triangles
    /// in [`TriPack`]s of four tested with one SIMD triangle test.
    Wide,
}

/// Which code traces a wide tree (see [`Bvh::set_kernels`]). By default rt-simd's kernels with
/// the instruction set [`Isa::detect`] finds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernels {
    /// rt-simd's kernels (the slab test of eight children, the triangle tests of four) with
    /// this instruction set: AVX2 (for [`Isa::Avx2`] and [`Isa::Avx512`], compiled with AVX2
    /// and FMA enabled), SSE2, or the portable ones on plain arrays (any target; what aarch64
    /// runs).
    Simd(Isa),
    /// Triangles tested one at a time with the scalar functions of `rt-core`: the reference the
    /// SIMD kernels are tested against, bit for bit.
    Scalar,
}

/// Build parameters. `Default` is [`BvhParams::wide`].
#[derive(Clone, Debug, PartialEq)]
pub struct BvhParams {
    /// Binary or wide nodes.
    pub layout: Layout,
    /// How nodes are split.
    pub split: SplitMethod,
    /// SAH buckets per axis, clamped to `2..=32`.
    pub bins: u32,
    /// SAH cost of visiting a node, relative to `intersection_cost`.
    pub traversal_cost: f32,
    /// SAH cost of one primitive test (of one pack of four, for the wide layout's triangles).
    pub intersection_cost: f32,
    /// Most primitives in one leaf, clamped to `1..=255` for the binary layout, `1..=32` for
    /// wide triangle packs and `1..=8` for other primitives in the wide layout. SAH may stop
    /// earlier when splitting does not pay; median and middle split until they reach it.
    pub max_leaf_size: u32,
    /// Passes of reinsertion over the split tree before it becomes nodes (Bittner et al. 2013):
    /// each moves the tenth of the subtrees with the largest boxes to where they add the least
    /// area, keeping every leaf as it is; passes stop early once one gains less than 0.1%.
    /// 0 (the default) for none. The tree is the same whatever the number of threads.
    pub reinsertion_passes: u32,
    /// Build large subtrees on rayon's threads. The tree is the same either way.
    pub parallel: bool,
    /// Force the kernels of a wide tree; `None`, or kernels this CPU cannot run, picks the
    /// fastest it runs.
    pub kernels: Option<Kernels>,
    /// Measurement only: switches that turn off optimisations of the wide traversal to measure
    /// what each gains. Leave it at its default.
    pub ablation: Ablation,
}

/// Measurement only: switches that turn off one optimisation of the wide traversal each, so that
/// `cargo run --release -p rt-bvh --example steps` can measure what it gains, and one that turns
/// on a traversal still being measured. Turning an optimisation off is never faster; the
/// default is what every user wants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ablation {
    /// Closest hit: visit the children a ray enters nearest first (sorted by entry distance).
    /// `false` visits them in lane order.
    pub sort_children: bool,
    /// Any hit: the dedicated path (children in lane order, no sorting, stop at the first hit).
    /// `false` answers occlusion with the closest-hit traversal.
    pub any_hit_path: bool,
    /// The stream queries ([`Accel::intersect_stream`], [`Accel::occluded_stream`]): `true`
    /// walks the rays as streams, node by node (the dynamic ray stream traversal of Barringer
    /// & Akenine-Möller, 2014); `false`, the default, traces them one by one. Off until it is
    /// measured faster than single rays (`cargo xtask compare --stream -s bvh-stream` prints
    /// both; the `stream` preset turns it on): exact either way, and the conformance kit
    /// checks both.
    pub stream_walk: bool,
}

impl Default for Ablation {
    fn default() -> Self {
        Self {
            sort_children: true,
            any_hit_path: true,
            stream_walk: false,
        }
    }
}

impl BvhParams {
    /// The wide layout with binned SAH: 32 buckets, costs 0.7 and 1, leaves of up to 8
    /// triangles.
    // PERF: 32 buckets and a traversal cost of 0.7, against 16 and 1.0 (private harness, one
    // thread, 1024×768, medians of three alternating runs, Mrays/s, with each view's share of
    // primary rays that hit). Bundles of 8×8 tiles, primary rays of close views: the teapot in
    // a stadium (100%) 53.4 -> 59.5, the bunny (79.5%) 44.8 -> 49.9, the teapot (97.5%) 52.9
    // -> 61.7, the sphereflake (94.2%) 34.4 -> 37.2, and meshes not tuned on: rocker arm
    // (100%) 39.9 -> 48.0, homer (70.6%) 43.9 -> 49.8, fandisk (100%) 48.0 -> 52.7, woody
    // (86.9%) 52.0 -> 59.5, cow (91.3%) 49.2 -> 54.5; their shadow rays +4 to +17%; single rays of every kind within -3% and
    // +15% (the stadium's shadow rays); incoherent rays within ±2%. The build takes up to 10%
    // longer and the tree up to 12% more memory (deeper trees). Costs of 0.4 to 0.85 traced
    // alike; 32 buckets alone helped the stadium most (a teapot among large triangles).
    pub fn wide() -> Self {
        Self {
            layout: Layout::Wide,
            split: SplitMethod::Sah,
            bins: 32,
            traversal_cost: 0.7,
            intersection_cost: 1.0,
            max_leaf_size: 8,
            reinsertion_passes: 0,
            parallel: true,
            kernels: None,
            ablation: Ablation::default(),
        }
    }

    /// The binary layout with binned SAH: 32 buckets, costs 1 and 1, leaves of up to 8
    /// primitives.
    pub fn sah() -> Self {
        Self {
            layout: Layout::Binary,
            traversal_cost: 1.0,
            ..Self::wide()
        }
    }

    /// [`wide`](Self::wide), with three passes of reinsertion: the same leaves, with subtrees
    /// moved to where they add the least area. It pays where triangle sizes vary widely (a
    /// teapot in a stadium) and costs about twice the build time; on scanned meshes of even
    /// triangles the binned tree is already close to what reinsertion finds. The results pages
    /// (`docs/results.md`, see [Measurements](crate#measurements)) have a row for each.
    pub fn reinserted() -> Self {
        Self {
            reinsertion_passes: 3,
            ..Self::wide()
        }
    }

    /// Binary, median split by count (quickselect), leaves of up to 4 primitives.
    pub fn median() -> Self {
        Self {
            split: SplitMethod::Median,
            max_leaf_size: 4,
            ..Self::sah()
        }
    }

    /// Binary, middle-of-extent split, leaves of up to 4 primitives.
    pub fn middle() -> Self {
        Self {
            split: SplitMethod::Middle,
            max_leaf_size: 4,
            ..Self::sah()
        }
    }
}

impl Default for BvhParams {
    fn default() -> Self {
        Self::wide()
    }
}

/// A bounding volume hierarchy over primitives of type `P`. See the [crate documentation](crate).
#[derive(Clone, Debug)]
pub struct Bvh<P: Primitive> {
    /// The nodes and leaves, in the one layout the tree was built with.
    tree: Tree<P>,
    max_depth: usize,
    leaves: usize,
    valid: usize,
    stored: usize,
    /// What [`Accel::build_from`] was given, and what it left out: for [`rt_core::Refit`].
    input: Input,
    /// The SAH constants, for [`Bvh::sah_cost`].
    costs: (f32, f32),
    /// Whether large refits may run on rayon's threads ([`BvhParams::parallel`]).
    parallel: bool,
    /// [`Bvh::sah_cost`] when the tree was built.
    built_cost: f64,
}

/// A tree in its layout: binary or wide, never both.
#[derive(Clone, Debug)]
enum Tree<P> {
    /// Two children per node; the leaves' primitives in leaf order.
    Binary { nodes: Vec<Node>, items: Items<P> },
    /// Up to eight children per node.
    Wide(Wide<P>),
}

/// The wide tree, with the kernels that trace it.
#[derive(Clone, Debug)]
struct Wide<P> {
    nodes: Vec<WideNode>,
    leaves: Leaves<P>,
    kernels: Kernels,
    isa: Isa,
    ablation: Ablation,
}

/// What a wide tree's leaves hold.
#[derive(Clone, Debug)]
enum Leaves<P> {
    /// Packs of four triangles, all with one test: every valid primitive is such a triangle.
    Packs {
        packs: Vec<TriPack>,
        test: TriangleTest,
    },
    /// Primitives one at a time.
    Items(Items<P>),
}

/// Primitives in leaf order, each with its index in the build input.
#[derive(Clone, Debug)]
pub(crate) struct Items<P> {
    pub(crate) prims: Vec<P>,
    pub(crate) ids: Vec<u32>,
}

impl<P> Items<P> {
    fn memory_bytes(&self) -> usize {
        self.prims.capacity() * size_of::<P>() + self.ids.capacity() * size_of::<u32>()
    }
}

/// The primitives of the build input the tree does not store, so that a refit can check they
/// still need not be stored.
#[derive(Clone, Debug, Default)]
struct Input {
    /// How many primitives the input had.
    len: usize,
    /// The invalid ones (usually none).
    invalid: Vec<u32>,
    /// Bit-identical copies of stored triangles, with the copy stored (usually none).
    copies: Vec<(u32, u32)>,
    /// The same pairs the other way round, `(stored, copy)`, in ascending order: what a box
    /// query looks up to report every copy of a stored triangle it finds.
    twins: Vec<(u32, u32)>,
}

impl<P: Primitive> Bvh<P> {
    /// The layout this tree was built with.
    pub fn layout(&self) -> Layout {
        match self.tree {
            Tree::Binary { .. } => Layout::Binary,
            Tree::Wide(_) => Layout::Wide,
        }
    }

    /// The binary tree's nodes, root first, in depth-first order (empty for the wide layout).
    pub fn nodes(&self) -> &[Node] {
        match &self.tree {
            Tree::Binary { nodes, .. } => nodes,
            Tree::Wide(_) => &[],
        }
    }

    /// The wide tree's nodes, root first (empty for the binary layout and for an empty tree).
    pub fn wide_nodes(&self) -> &[WideNode] {
        match &self.tree {
            Tree::Binary { .. } => &[],
            Tree::Wide(w) => &w.nodes,
        }
    }

    /// The wide tree's triangle packs, which its leaves index (empty unless the tree is wide
    /// and every valid primitive is a triangle with one test; see
    /// [`Primitive::as_triangle`]).
    pub fn packs(&self) -> &[TriPack] {
        match &self.tree {
            Tree::Wide(Wide {
                leaves: Leaves::Packs { packs, .. },
                ..
            }) => packs,
            _ => &[],
        }
    }

    /// The test of the [`packs`](Bvh::packs), if the leaves are packed.
    pub fn pack_test(&self) -> Option<TriangleTest> {
        match &self.tree {
            Tree::Wide(Wide {
                leaves: Leaves::Packs { test, .. },
                ..
            }) => Some(*test),
            _ => None,
        }
    }

    /// The leaves' primitives and their input indices, unless the leaves are triangle packs.
    fn items(&self) -> Option<&Items<P>> {
        match &self.tree {
            Tree::Binary { items, .. }
            | Tree::Wide(Wide {
                leaves: Leaves::Items(items),
                ..
            }) => Some(items),
            Tree::Wide(_) => None,
        }
    }

    /// The kept primitives, reordered so each leaf's are contiguous (empty when the leaves are
    /// triangle packs).
    pub fn primitives(&self) -> &[P] {
        self.items().map_or(&[], |i| &i.prims)
    }

    /// For each slot of [`primitives`](Bvh::primitives), its index in the build input.
    pub fn primitive_ids(&self) -> &[u32] {
        self.items().map_or(&[], |i| &i.ids)
    }

    /// The kernels that trace this tree (always the portable ones for the binary layout,
    /// whose traversal is scalar).
    pub fn kernels(&self) -> Kernels {
        match &self.tree {
            Tree::Binary { .. } => Kernels::Simd(Isa::Portable),
            Tree::Wide(w) => w.kernels,
        }
    }

    /// Chooses the fastest kernels this CPU runs for a wide tree ([`Isa::detect`]:
    /// `RT_ACCEL_PORTABLE=1` chooses the portable ones).
    pub(crate) fn set_fastest_kernels(&mut self) {
        self.set_kernels(Kernels::Simd(Isa::detect()));
    }

    /// Chooses the kernels that trace a wide tree. Returns `false`, changing nothing, for a
    /// binary tree (whose traversal is scalar) unless `kernels` are the portable ones.
    pub fn set_kernels(&mut self, kernels: Kernels) -> bool {
        let Tree::Wide(wide) = &mut self.tree else {
            return kernels == Kernels::Simd(Isa::Portable);
        };
        wide.kernels = kernels;
        wide.isa = match kernels {
            Kernels::Simd(isa) => isa,
            Kernels::Scalar => Isa::Portable,
        };
        true
    }

    /// The query core behind [`Accel::ray_query`]: the tree's walk for `q`, which sees each
    /// stored triangle once (bit-identical copies left out of the tree are
    /// [`Accel::ray_query`]'s to add).
    #[inline(always)]
    fn query<S: Stats, Q: RayQuery>(&self, ray: &Ray, q: &mut Q, stats: &mut S) {
        // Outside the precondition (NaN, huge origins, ...): answer at once, walk nothing.
        if !ray.is_valid() {
            return;
        }
        match &self.tree {
            Tree::Binary { nodes, items } => traverse::binary(nodes, items, ray, q, stats),
            Tree::Wide(w) if w.nodes.is_empty() => {}
            // Occlusion through the closest-hit traversal: only to measure the any-hit path.
            Tree::Wide(w) if Q::OCCLUSION && !w.ablation.any_hit_path => {
                let mut closest = rt_core::ClosestHit::new(ray);
                w.walk(ray, &mut closest, stats);
                if let Some(hit) = closest.hit() {
                    let _ = q.offer(hit.prim, rt_core::query::BLOCKS);
                }
            }
            Tree::Wide(w) => w.walk(ray, q, stats),
        }
    }
}

impl<P: Primitive> Bvh<P> {
    /// The bundle queries' core: each of the first `slots` rays answered through `answer(slot,
    /// answer)`, where an any-hit answer is `Some` when occluded. The wide tree traces coherent
    /// rays as bundles (`bundle.rs`) through rt-core's frame for bundle queries
    /// ([`walk_groups`](rt_simd::bundle::walk_groups)): a bundle that misses the
    /// root's box is answered at once; one whose directions spread more than
    /// [`bundle::MAX_SPREAD`] or whose origins spread more than [`bundle::MAX_ORIGIN_SPREAD`],
    /// a bundle of one ray and a ray that cannot travel in one take the single-ray path. The binary tree walks its own way ([`bundle::binary_bundle`]).
    fn bundle_query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        order: Option<&[u32]>,
        stats: &mut S,
        mut answer: impl FnMut(usize, Option<Hit>),
    ) {
        let rays = &rays[..rays.len().min(slots)];
        let root = self.root_bounds();
        let side = (root.max - root.min).max_element();
        let coherent = |b: &Bundle| {
            let lb = b.lane_bounds();
            b.direction_spread() <= bundle::MAX_SPREAD
                && (lb.origin_hi - lb.origin_lo).max_element() <= bundle::MAX_ORIGIN_SPREAD * side
        };
        let wide = match &self.tree {
            // PERF: a call with one ray goes straight to the single-ray path, without sorting
            // it into a bundle first.
            Tree::Wide(w)
                if rays.len() > 1 && !w.nodes.is_empty() && (!ANY || w.ablation.any_hit_path) =>
            {
                w
            }
            Tree::Binary { nodes, items } if rays.len() > 1 && !items.ids.is_empty() => {
                let bounds = root;
                rt_simd::bundle::walk_groups_ordered::<S, ANY>(
                    rays,
                    slots,
                    order,
                    stats,
                    |ray, stats| rt_simd::bundle::single::<_, S, ANY>(self, ray, stats),
                    |b| b.route(&bounds, coherent),
                    // Inlined, so that the walk is compiled with the vector instructions `walk_groups` runs
                    // with (`Isa::run`).
                    #[inline(always)]
                    |b, lanes, stats| {
                        bundle::binary_bundle::<P, S, ANY>(nodes, items, b, lanes, stats);
                        0
                    },
                    answer,
                );
                return;
            }
            _ => {
                for slot in rt_simd::bundle::slots_of(rays.len(), order) {
                    if let Some(ray) = rays.get(slot) {
                        stats.single_ray();
                        answer(slot, rt_simd::bundle::single::<_, S, ANY>(self, ray, stats));
                    }
                }
                return;
            }
        };
        let bounds = root;
        rt_simd::bundle::walk_groups_ordered::<S, ANY>(
            rays,
            slots,
            order,
            stats,
            |ray, stats| rt_simd::bundle::single::<_, S, ANY>(self, ray, stats),
            |b| b.route(&bounds, coherent),
            |b, lanes, stats| {
                wide.bundle::<S, ANY>(b, lanes, stats);
                0
            },
            answer,
        );
    }
}

impl<P: Primitive> Bvh<P> {
    /// The stream queries' core: each of the first `slots` rays answered through
    /// `answer(slot, answer)`, where an any-hit answer is `Some` when occluded. With
    /// [`Ablation::stream_walk`], the wide tree walks the rays in streams of [`stream::CHUNK`]
    /// (`stream.rs`), where a ray that cannot travel takes the single-ray path, which answers
    /// it at once; otherwise every ray takes the single-ray path.
    fn stream_query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        stats: &mut S,
        mut answer: impl FnMut(usize, Option<Hit>),
    ) {
        let rays = &rays[..rays.len().min(slots)];
        let wide = match &self.tree {
            Tree::Wide(w)
                if w.ablation.stream_walk
                    && !w.nodes.is_empty()
                    && (!ANY || w.ablation.any_hit_path) =>
            {
                w
            }
            _ => {
                for (slot, ray) in rays.iter().enumerate() {
                    answer(slot, rt_simd::bundle::single::<_, S, ANY>(self, ray, stats));
                }
                return;
            }
        };
        stream::with_scratch(|sc| {
            for (c, chunk) in rays.chunks(stream::CHUNK).enumerate() {
                if sc.start(chunk) {
                    let sort = wide.ablation.sort_children;
                    wide.with_leaves(OneStream::<S, ANY>(chunk, sort, sc, stats));
                }
                for (i, ray) in chunk.iter().enumerate() {
                    let best = sc.best[i];
                    let hit = if !ray.is_valid() {
                        rt_simd::bundle::single::<_, S, ANY>(self, ray, stats)
                    } else if best.prim == u32::MAX {
                        None
                    } else if ANY {
                        Some(rt_simd::bundle::BLOCKED)
                    } else {
                        Some(best)
                    };
                    answer(c * stream::CHUNK + i, hit);
                }
            }
        });
    }
}

/// A traversal to run over a wide tree's leaves, whichever kind they are: [`Wide::with_leaves`]
/// picks the leaf test once and hands it to [`LeafWalk::walk`], so every traversal (single
/// rays, bundles) shares one choice of kernels.
trait LeafWalk {
    type Out;
    fn walk<L: traverse::Leaves>(self, nodes: &[WideNode], isa: Isa, leaves: &L) -> Self::Out;
}

/// One ray through [`traverse::wide`].
/// `sort`: whether a closest-hit ray sorts the children it enters ([`Ablation::sort_children`]).
struct OneRay<'a, S, Q> {
    ray: &'a Ray,
    sort: bool,
    q: &'a mut Q,
    stats: &'a mut S,
}

impl<S: Stats, Q: RayQuery> LeafWalk for OneRay<'_, S, Q> {
    type Out = ();
    #[inline(always)]
    fn walk<L: traverse::Leaves>(self, nodes: &[WideNode], isa: Isa, leaves: &L) {
        let (ray, sort, q, stats) = (self.ray, self.sort, self.q, self.stats);
        isa.wide(traverse::WideRay {
            nodes,
            leaves,
            ray,
            sort,
            q,
            stats,
        })
    }
}

/// One ray's closest hit through [`traverse::wide`], written into `out`
/// ([`traverse::WideRayInto`] says why).
struct OneRayInto<'a, S> {
    ray: &'a Ray,
    sort: bool,
    stats: &'a mut S,
    out: &'a mut Option<Hit>,
}

impl<S: Stats> LeafWalk for OneRayInto<'_, S> {
    type Out = ();
    #[inline(always)]
    fn walk<L: traverse::Leaves>(self, nodes: &[WideNode], isa: Isa, leaves: &L) {
        let (ray, sort, stats, out) = (self.ray, self.sort, self.stats, self.out);
        isa.wide(traverse::WideRayInto {
            nodes,
            leaves,
            ray,
            sort,
            stats,
            out,
        })
    }
}

/// One bundle through [`bundle::wide_bundle`].
struct OneBundle<'a, 'b, S, const ANY: bool>(&'a Bundle, &'a mut Lanes<'b>, &'a mut S);

impl<S: Stats, const ANY: bool> LeafWalk for OneBundle<'_, '_, S, ANY> {
    type Out = ();
    #[inline(always)]
    fn walk<L: traverse::Leaves>(self, nodes: &[WideNode], isa: Isa, leaves: &L) {
        // The bundle walk stays in the AVX2 frame, unlike the single-ray walk.
        // PERF: Intel Xeon (Emerald Rapids), bunny, 8x8 tiles, one thread, three alternating
        // runs of `compare -s bvh --bundle 8x8 -j 1`, Mrays/s in the AVX-512 frame -> the AVX2
        // frame: primary 35.1 35.3 35.2 -> 37.3 36.9 37.0, shadow 19.6 19.4 19.7 -> 20.8 20.5
        // 20.7.
        isa.wide_avx2_frame(bundle::WideBundle::<L, S, ANY> {
            nodes,
            leaves,
            bundle: self.0,
            lanes: self.1,
            stats: self.2,
        })
    }
}

/// One stream through [`stream::wide_stream`].
struct OneStream<'a, S, const ANY: bool>(&'a [Ray], bool, &'a mut stream::Scratch, &'a mut S);

impl<S: Stats, const ANY: bool> LeafWalk for OneStream<'_, S, ANY> {
    type Out = ();
    #[inline(always)]
    fn walk<L: traverse::Leaves>(self, nodes: &[WideNode], isa: Isa, leaves: &L) {
        isa.wide(stream::WideStream::<L, S, ANY> {
            nodes,
            leaves,
            rays: self.0,
            sort: self.1,
            scratch: self.2,
            stats: self.3,
        })
    }
}

impl<P: Primitive> Wide<P> {
    /// Runs `walk` with this tree's leaves and kernels.
    #[inline(always)]
    fn with_leaves<W: LeafWalk>(&self, walk: W) -> W::Out {
        let (nodes, isa) = (&self.nodes[..], self.isa);
        match (&self.leaves, self.kernels) {
            (Leaves::Packs { packs, test }, Kernels::Scalar) => {
                walk.walk(nodes, isa, &ScalarPacks { packs, test: *test })
            }
            (
                Leaves::Packs {
                    packs,
                    test: TriangleTest::Watertight,
                },
                _,
            ) => walk.walk(nodes, isa, &Packs::<false> { packs }),
            (
                Leaves::Packs {
                    packs,
                    test: TriangleTest::MollerTrumbore,
                },
                _,
            ) => walk.walk(nodes, isa, &Packs::<true> { packs }),
            (Leaves::Items(items), _) => walk.walk(
                nodes,
                isa,
                &Prims {
                    prims: &items.prims,
                    ids: &items.ids,
                },
            ),
        }
    }

    /// The bundle traversal with this tree's leaves and kernels.
    fn bundle<S: Stats, const ANY: bool>(&self, b: &Bundle, lanes: &mut Lanes, stats: &mut S) {
        self.with_leaves(OneBundle::<S, ANY>(b, lanes, stats));
    }

    /// The wide traversal with this tree's leaves, kernels and child ordering.
    #[inline(always)]
    fn walk<S: Stats, Q: RayQuery>(&self, ray: &Ray, q: &mut Q, stats: &mut S) {
        self.with_leaves(OneRay {
            ray,
            sort: self.ablation.sort_children,
            q,
            stats,
        })
    }
}

impl<P: Primitive> Accel for Bvh<P> {
    type Prim = P;
    type Params = BvhParams;
    const NAME: &'static str = "bvh";

    fn presets() -> Vec<(&'static str, BvhParams)> {
        vec![
            ("wide", BvhParams::wide()),
            ("binary", BvhParams::sah()),
            ("median", BvhParams::median()),
            ("middle", BvhParams::middle()),
            ("reinserted", BvhParams::reinserted()),
            // The wide tree whose stream queries walk the rays together
            // ([`Ablation::stream_walk`]), for `compare --stream` to measure.
            (
                "stream",
                BvhParams {
                    ablation: Ablation {
                        stream_walk: true,
                        ..Ablation::default()
                    },
                    ..BvhParams::wide()
                },
            ),
        ]
    }

    fn build(prims: &[P], params: &BvhParams) -> Self {
        Self::build_from(prims, params)
    }

    /// Reads the primitives straight into the tree's layout: the wide tree's triangle packs
    /// (no triangle list is made), or the reordered primitives of the binary tree and of wide
    /// leaves that are not packed.
    fn build_from<G: rt_core::Geometry<Prim = P> + ?Sized>(
        geometry: &G,
        params: &BvhParams,
    ) -> Self {
        let builder::Built { tree: b, prims } = builder::build(geometry, params);
        let items = Items { prims, ids: b.ids };
        let tree = match params.layout {
            Layout::Binary => Tree::Binary {
                nodes: b.binary,
                items,
            },
            Layout::Wide => Tree::Wide(Wide {
                nodes: b.wide,
                leaves: match b.test {
                    Some(test) => Leaves::Packs {
                        packs: b.packs,
                        test,
                    },
                    None => Leaves::Items(items),
                },
                kernels: Kernels::Simd(Isa::Portable),
                isa: Isa::Portable,
                ablation: params.ablation,
            }),
        };
        let mut bvh = Self {
            tree,
            max_depth: b.max_depth,
            leaves: b.leaves,
            valid: b.valid,
            stored: b.stored,
            input: Input::default(),
            costs: (params.traversal_cost, params.intersection_cost),
            parallel: params.parallel,
            built_cost: 0.0,
        };
        bvh.input = refit::left_out(&bvh, geometry);
        bvh.built_cost = bvh.sah_cost();
        if bvh.layout() == Layout::Wide {
            // The kernels asked for, else the fastest this CPU runs.
            let chosen = params.kernels.is_some_and(|k| bvh.set_kernels(k));
            if !chosen {
                bvh.set_fastest_kernels();
            }
        }
        bvh
    }

    /// The tree's walk; bit-identical copies of a stored triangle, which the tree stores once,
    /// are offered with it to a query they can change (not a closest or any hit:
    /// [`RayQuery::COPIES_CHANGE_NOTHING`]).
    #[inline]
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        // A query that copies can change always walks wrapped, copies or not: an empty list
        // costs a test per hit, where walking it unwrapped too would compile a second walk for
        // every such query type, kernel set and statistics sink.
        // PERF: AMD Zen 3, rt-shootout's library (`cargo llvm-lines -p rt-shootout --lib`):
        // copies of the walk 510 -> 300, LLVM IR lines before inlining 1,267,784 -> 1,130,787,
        // its build in the test profile 548 -> 349 CPU seconds. Speed unchanged: all hits,
        // a filtered closest hit and one filtered through `dyn FnMut` on the bunny and the
        // teapot, primary and incoherent rays, wrapped / unwrapped 1.01, 1.01 and 1.01
        // (geometric means of three alternating runs, best of 5 passes).
        if Q::COPIES_CHANGE_NOTHING {
            self.query(ray, query, stats);
        } else {
            self.query(
                ray,
                &mut overlap::WithCopies::new(query, &self.input.twins),
                stats,
            );
        }
    }

    /// Coherent rays of the wide tree walk it in bundles (`bundle.rs`); see
    /// [`rt_core::bundle`] for how their steps count.
    #[inline]
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        // One ray goes straight to the single-ray walk, which writes its answer in place
        // (`traverse::WideRayInto` says why).
        if let ([ray], [slot]) = (rays, &mut *out) {
            stats.single_ray();
            match &self.tree {
                Tree::Wide(w) if ray.is_valid() && !w.nodes.is_empty() => {
                    w.with_leaves(OneRayInto {
                        ray,
                        sort: w.ablation.sort_children,
                        stats,
                        out: slot,
                    });
                }
                Tree::Binary { nodes, items } if ray.is_valid() => {
                    traverse::binary_into::<P, S>(nodes, items, ray, stats, slot)
                }
                _ => *slot = self.intersect_with(ray, stats),
            }
            return;
        }
        self.bundle_query::<S, false>(rays, out.len(), None, stats, |slot, hit| out[slot] = hit);
    }

    #[inline]
    fn intersect_bundle_ordered_with<S: Stats>(
        &self,
        rays: &[Ray],
        order: &[u32],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        self.bundle_query::<S, false>(rays, out.len(), Some(order), stats, |slot, hit| {
            out[slot] = hit
        });
    }

    #[inline]
    fn occluded_bundle_ordered_with<S: Stats>(
        &self,
        rays: &[Ray],
        order: &[u32],
        out: &mut [bool],
        stats: &mut S,
    ) {
        self.bundle_query::<S, true>(rays, out.len(), Some(order), stats, |slot, hit| {
            out[slot] = hit.is_some()
        });
    }

    #[inline]
    fn occluded_bundle_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        if let ([ray], [slot]) = (rays, &mut *out) {
            stats.single_ray();
            *slot = self.occluded_with(ray, stats);
            return;
        }
        self.bundle_query::<S, true>(rays, out.len(), None, stats, |slot, hit| {
            out[slot] = hit.is_some()
        });
    }

    /// Rays one by one, or with [`Ablation::stream_walk`] in streams (`stream.rs`).
    #[inline]
    fn intersect_stream_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        self.stream_query::<S, false>(rays, out.len(), stats, |slot, hit| out[slot] = hit);
    }

    #[inline]
    fn occluded_stream_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        self.stream_query::<S, true>(rays, out.len(), stats, |slot, hit| {
            out[slot] = hit.is_some()
        });
    }

    fn bounds(&self) -> rt_core::Aabb {
        self.root_bounds()
    }

    /// Nearest box first, pruned by the query's radius (`nearest.rs`).
    fn ball_query<Q: rt_core::BallQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        match self.layout() {
            Layout::Binary => self.ball_binary(query, stats),
            Layout::Wide => self.ball_wide(query, stats),
        }
    }

    /// Every subtree whose box meets the query box (`overlap.rs`). Bit-identical copies of a
    /// triangle, which the tree stores once, are offered with it.
    fn box_query<Q: rt_core::BoxQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        // Wrapped whether or not there are copies, for the reason `ray_query` gives.
        let mut with = overlap::WithCopies::new(query, &self.input.twins);
        let _ = self.box_walk(&mut with, stats);
        for _ in 0..with.offered() {
            stats.prim_test();
        }
    }

    fn memory_bytes(&self) -> usize {
        let tree = match &self.tree {
            Tree::Binary { nodes, items } => {
                nodes.capacity() * size_of::<Node>() + items.memory_bytes()
            }
            Tree::Wide(w) => {
                w.nodes.capacity() * size_of::<WideNode>()
                    + match &w.leaves {
                        Leaves::Packs { packs, .. } => packs.capacity() * size_of::<TriPack>(),
                        Leaves::Items(items) => items.memory_bytes(),
                    }
            }
        };
        size_of::<Self>()
            + tree
            + self.input.invalid.capacity() * size_of::<u32>()
            + (self.input.copies.capacity() + self.input.twins.capacity()) * size_of::<(u32, u32)>()
    }

    fn regions(&self, visit: &mut dyn FnMut(rt_core::Region)) {
        self.walk_regions(visit);
    }

    fn build_stats(&self) -> BuildStats {
        let nodes = match self.layout() {
            Layout::Binary if self.valid == 0 => 0,
            Layout::Binary => self.nodes().len(),
            Layout::Wide => self.wide_nodes().len() + self.leaves,
        };
        let mut extra = Vec::new();
        if self.layout() == Layout::Wide {
            extra.push(("wide nodes", self.wide_nodes().len() as f64));
            extra.push(("triangle packs", self.packs().len() as f64));
        }
        BuildStats {
            nodes,
            leaves: self.leaves,
            empty_leaves: 0,
            max_depth: self.max_depth,
            prim_refs: self.stored,
            valid_prims: self.valid,
            extra,
        }
    }
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

// With `share-dyn`, debug and test builds of the crates that use a `Bvh` as a trait
// object (the shootout, the renderer's tests) link this crate's copy of its methods instead of
// compiling their own.
#[cfg(feature = "share-dyn")]
rt_core::share_dyn_accel!(Bvh);

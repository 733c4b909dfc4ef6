//! A bounding volume hierarchy (BVH) for CPU ray tracing.
//!
//! # The structure
//! A binary tree of axis-aligned boxes. Each interior node splits its primitives into two
//! groups, and each group gets the tightest box around it; a leaf holds a few primitives. A
//! ray only descends into children whose boxes it enters, so it tests a few dozen boxes and a
//! handful of primitives instead of all of them. Unlike spatial subdivisions (kd-trees, grids),
//! every primitive is in exactly one leaf: no duplicated references and no mailboxing, at the
//! price of sibling boxes that may overlap.
//!
//! The tree is built top-down into a flat, depth-first array of 32-byte [`Node`]s (pbrt-v4's
//! layout: the first child follows its parent, the second child's index is stored), and the
//! primitives are reordered so that each leaf is a contiguous range.
//!
//! # Cost model
//! - **Build**: O(N log N). Every node costs O(n) for its bounds and split choice (binning,
//!   quickselect or partition), and there are O(log N) levels for balanced splits. Degenerate
//!   input cannot make it worse than O(N · 64): once a subtree would not fit under the depth
//!   limit [`MAX_DEPTH`] (the traversal stack size) it is split by count.
//! - **Memory**: 32 bytes per node (at most `2N - 1` nodes), plus the reordered primitives and a
//!   4-byte original index per primitive.
//! - **Traversal step**: one node visit loads the node and tests both children's boxes (two slab
//!   tests, six multiply-adds and a few compares each), then continues with the nearer child and
//!   pushes the farther one; a leaf tests its primitives.
//!
//! # Tuning knobs ([`BvhParams`])
//! - [`SplitMethod`]: binned SAH (the default; Wald 2007, pbrt-v4 §7.3), median split by count
//!   (quickselect along the longest centroid axis), or middle of the centroid extent (pbrt's
//!   `Middle`). The presets `sah`, `median` and `middle` select them.
//! - `bins`: SAH buckets per axis (16; Wald 2007 finds 16–32 within a few percent of a full sweep).
//! - `traversal_cost` / `intersection_cost`: the SAH constants, relative cost of stepping into a
//!   node and of one primitive test (1 and 1 here; pbrt-v4 uses 1/2 and 1).
//! - `max_leaf_size`: the most primitives a leaf may hold (8 for SAH, 4 for the others).
//!
//! # Measured
//! On the Stanford bunny (69,451 triangles), `cargo xtask compare --scene
//! ../shared/meshes/stanford-bunny.obj` (1024×768 primary rays, 2 threads):
//!
//! | preset | build ms | nodes | depth | visits/ray | tests/ray | Mrays/s |
//! | --- | ---: | ---: | ---: | ---: | ---: | ---: |
//! | `sah` | 42.1 | 77,359 | 19 | 6.8 | 0.8 | 20.6 |
//! | `median` | 14.1 | 40,597 | 15 | 8.0 | 2.4 | 14.2 |
//! | `middle` | 14.1 | 44,817 | 20 | 7.4 | 1.8 | 16.8 |
//!
//! Single-threaded on the same triangles and rays at 512×384, one run of `cargo bench -p
//! rt-benches --bench trace` gives the SAH tree 1.15× the speed of `obvhs` (PLOC with
//! reinsertion, its slow preset) on the bunny and 0.90× on the sphereflake, and 2.7–3.1× that of
//! the `bvh` crate; its build takes 36.3 ms on the bunny against obvhs' 19.5 ms (medium preset).
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
//! let bvh = Bvh::build(&tris, &BvhParams::sah());
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
//! let mesh = rt_core::load_obj("bunny.obj")?; // typed error naming file and line
//! let bvh = Bvh::build(&mesh.triangles(), &BvhParams::sah());
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
mod kernels;
mod node;
mod simd;
mod traverse;
mod validate;

pub use node::{ChildRef, Node, PACK, TriPack, WIDTH, WideNode};
pub use validate::ValidationError;

use rt_core::{Accel, BuildStats, Hit, Primitive, Ray, Stats, TriangleTest};
use simd::Isa;
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

/// Which code traces a wide tree (see [`Bvh::set_kernels`]). By default the first of `Avx2`,
/// `Sse2` and `Portable` that the CPU runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernels {
    /// The SIMD kernels with AVX2 intrinsics, compiled with AVX2 and FMA enabled (x86-64 CPUs
    /// that have both, detected at run time).
    Avx2,
    /// The same kernels with SSE2 intrinsics (every x86-64 CPU).
    Sse2,
    /// The same kernels on plain arrays, compiled for the target's baseline (any target; what
    /// aarch64 runs).
    Portable,
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
    /// Build large subtrees on rayon's threads. The tree is the same either way.
    pub parallel: bool,
    /// Force the kernels of a wide tree; `None`, or kernels this CPU cannot run, picks the
    /// fastest it runs.
    pub kernels: Option<Kernels>,
    /// Wide tree, closest hit: visit the children a ray enters nearest first (sorted by entry
    /// distance). `false` visits them in lane order: only there to measure what sorting gains.
    pub sort_children: bool,
    /// Wide tree, any hit: the dedicated path (children in lane order, no sorting, stop at the
    /// first hit). `false` answers occlusion with the closest-hit traversal: only there to
    /// measure what the dedicated path gains.
    pub any_hit_path: bool,
}

impl BvhParams {
    /// The wide layout with binned SAH: 16 buckets, costs 1 and 1, leaves of up to 8 triangles.
    pub fn wide() -> Self {
        Self {
            layout: Layout::Wide,
            split: SplitMethod::Sah,
            bins: 16,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            max_leaf_size: 8,
            parallel: true,
            kernels: None,
            sort_children: true,
            any_hit_path: true,
        }
    }

    /// The binary layout with binned SAH: 16 buckets, costs 1 and 1, leaves of up to 8
    /// primitives.
    pub fn sah() -> Self {
        Self {
            layout: Layout::Binary,
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
    layout: Layout,
    binary: Vec<Node>,
    wide: Vec<WideNode>,
    packs: Vec<TriPack>,
    test: Option<TriangleTest>,
    prims: Vec<P>,
    ids: Vec<u32>,
    kernels: Kernels,
    isa: Isa,
    sort_children: bool,
    any_hit_path: bool,
    max_depth: usize,
    leaves: usize,
    valid: usize,
    stored: usize,
}

impl<P: Primitive> Bvh<P> {
    /// The layout this tree was built with.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The binary tree's nodes, root first, in depth-first order (empty for the wide layout).
    pub fn nodes(&self) -> &[Node] {
        &self.binary
    }

    /// The wide tree's nodes, root first (empty for the binary layout and for an empty tree).
    pub fn wide_nodes(&self) -> &[WideNode] {
        &self.wide
    }

    /// The wide tree's triangle packs, which its leaves index (empty unless the tree is wide
    /// and every valid primitive is a triangle with one test; see
    /// [`Primitive::as_triangle`]).
    pub fn packs(&self) -> &[TriPack] {
        &self.packs
    }

    /// The test of the [`packs`](Bvh::packs), if the leaves are packed.
    pub fn pack_test(&self) -> Option<TriangleTest> {
        self.test
    }

    /// The kept primitives, reordered so each leaf's are contiguous (empty when the leaves are
    /// triangle packs).
    pub fn primitives(&self) -> &[P] {
        &self.prims
    }

    /// For each slot of [`primitives`](Bvh::primitives), its index in the build input.
    pub fn primitive_ids(&self) -> &[u32] {
        &self.ids
    }

    /// The kernels that trace this tree (always [`Kernels::Portable`] for the binary layout,
    /// whose traversal is scalar).
    pub fn kernels(&self) -> Kernels {
        self.kernels
    }

    /// Chooses the kernels that trace a wide tree. Returns `false`, changing nothing, when this
    /// CPU cannot run them (AVX2 without AVX2 and FMA) or the tree is binary.
    pub fn set_kernels(&mut self, kernels: Kernels) -> bool {
        if self.layout == Layout::Binary {
            return kernels == Kernels::Portable;
        }
        let isa = match kernels {
            Kernels::Avx2 => Isa::avx2(),
            Kernels::Sse2 => Isa::sse2(),
            Kernels::Portable | Kernels::Scalar => Some(Isa::Portable),
        };
        let Some(isa) = isa else {
            return false;
        };
        self.kernels = kernels;
        self.isa = isa;
        true
    }

    /// The query core shared by [`Accel::intersect_with`] and [`Accel::occluded_with`].
    #[inline(always)]
    fn query<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        // Outside the precondition (NaN, huge origins, ...): answer at once, walk nothing.
        if !ray.is_valid() {
            return None;
        }
        match self.layout {
            Layout::Binary => self.traverse_binary::<S, ANY>(ray, stats),
            Layout::Wide if self.wide.is_empty() => None,
            // Occlusion through the closest-hit traversal: only to measure the any-hit path.
            Layout::Wide if ANY && !self.any_hit_path => self.wide::<S, false>(ray, stats),
            Layout::Wide => self.wide::<S, ANY>(ray, stats),
        }
    }

    /// The wide traversal with this tree's leaves, kernels and child ordering.
    #[inline(always)]
    fn wide<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        if self.sort_children {
            self.wide_with::<S, ANY, true>(ray, stats)
        } else {
            self.wide_with::<S, ANY, false>(ray, stats)
        }
    }

    #[inline(always)]
    fn wide_with<S: Stats, const ANY: bool, const SORT: bool>(
        &self,
        ray: &Ray,
        stats: &mut S,
    ) -> Option<Hit> {
        let (nodes, isa) = (&self.wide[..], self.isa);
        match (self.test, self.kernels) {
            (Some(test), Kernels::Scalar) => {
                let leaves = ScalarPacks {
                    packs: &self.packs,
                    test,
                };
                simd::dispatch::<_, S, ANY, SORT>(isa, nodes, &leaves, ray, stats)
            }
            (Some(TriangleTest::Watertight), _) => {
                let leaves = Packs::<false> { packs: &self.packs };
                simd::dispatch::<_, S, ANY, SORT>(isa, nodes, &leaves, ray, stats)
            }
            (Some(TriangleTest::MollerTrumbore), _) => {
                let leaves = Packs::<true> { packs: &self.packs };
                simd::dispatch::<_, S, ANY, SORT>(isa, nodes, &leaves, ray, stats)
            }
            (None, _) => {
                let leaves = Prims {
                    prims: &self.prims,
                    ids: &self.ids,
                };
                simd::dispatch::<_, S, ANY, SORT>(isa, nodes, &leaves, ray, stats)
            }
        }
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
        ]
    }

    fn build(prims: &[P], params: &BvhParams) -> Self {
        let b = builder::build(prims, params);
        let mut bvh = Self {
            layout: params.layout,
            binary: b.binary,
            wide: b.wide,
            packs: b.packs,
            test: b.test,
            prims: b.prims,
            ids: b.ids,
            kernels: Kernels::Portable,
            isa: Isa::Portable,
            sort_children: params.sort_children,
            any_hit_path: params.any_hit_path,
            max_depth: b.max_depth,
            leaves: b.leaves,
            valid: b.valid,
            stored: b.stored,
        };
        if params.layout == Layout::Wide {
            // The kernels asked for, else the fastest this CPU runs.
            let chosen = params.kernels.is_some_and(|k| bvh.set_kernels(k));
            if !chosen {
                let _ = [Kernels::Avx2, Kernels::Sse2, Kernels::Portable]
                    .into_iter()
                    .any(|k| bvh.set_kernels(k));
            }
        }
        bvh
    }

    #[inline]
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        self.query::<S, false>(ray, stats)
    }

    #[inline]
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        self.query::<S, true>(ray, stats).is_some()
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.binary.capacity() * size_of::<Node>()
            + self.wide.capacity() * size_of::<WideNode>()
            + self.packs.capacity() * size_of::<TriPack>()
            + self.prims.capacity() * size_of::<P>()
            + self.ids.capacity() * size_of::<u32>()
    }

    fn build_stats(&self) -> BuildStats {
        let nodes = match self.layout {
            Layout::Binary if self.valid == 0 => 0,
            Layout::Binary => self.binary.len(),
            Layout::Wide => self.wide.len() + self.leaves,
        };
        let mut extra = Vec::new();
        if self.layout == Layout::Wide {
            extra.push(("wide nodes", self.wide.len() as f64));
            extra.push(("triangle packs", self.packs.len() as f64));
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

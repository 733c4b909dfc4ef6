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
mod node;
mod traverse;
mod validate;

pub use node::Node;
pub use validate::ValidationError;

use rt_core::{Accel, BuildStats, Hit, Primitive, Ray, Stats};

/// The deepest a tree may be, and so the size of the fixed traversal stack.
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

/// Build parameters. `Default` is [`BvhParams::sah`].
#[derive(Clone, Debug, PartialEq)]
pub struct BvhParams {
    /// How nodes are split.
    pub split: SplitMethod,
    /// SAH buckets per axis, clamped to `2..=32`.
    pub bins: u32,
    /// SAH cost of visiting a node, relative to `intersection_cost`.
    pub traversal_cost: f32,
    /// SAH cost of one primitive test.
    pub intersection_cost: f32,
    /// Most primitives in one leaf, clamped to `1..=255`. SAH may stop earlier when splitting
    /// does not pay; median and middle split until they reach it.
    pub max_leaf_size: u32,
}

impl BvhParams {
    /// Binned SAH with 16 buckets, costs 1 and 1, leaves of up to 8 primitives.
    pub fn sah() -> Self {
        Self {
            split: SplitMethod::Sah,
            bins: 16,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            max_leaf_size: 8,
        }
    }

    /// Median split by count (quickselect), leaves of up to 4 primitives.
    pub fn median() -> Self {
        Self {
            split: SplitMethod::Median,
            max_leaf_size: 4,
            ..Self::sah()
        }
    }

    /// Middle-of-extent split, leaves of up to 4 primitives.
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
        Self::sah()
    }
}

/// A bounding volume hierarchy over primitives of type `P`. See the [crate documentation](crate).
#[derive(Clone, Debug)]
pub struct Bvh<P: Primitive> {
    nodes: Vec<Node>,
    prims: Vec<P>,
    ids: Vec<u32>,
    max_depth: usize,
    leaves: usize,
}

impl<P: Primitive> Bvh<P> {
    /// The flattened nodes, root first, in depth-first order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The kept primitives, reordered so each leaf's are contiguous.
    pub fn primitives(&self) -> &[P] {
        &self.prims
    }

    /// For each slot of [`primitives`](Bvh::primitives), its index in the build input.
    pub fn primitive_ids(&self) -> &[u32] {
        &self.ids
    }
}

impl<P: Primitive> Accel for Bvh<P> {
    type Prim = P;
    type Params = BvhParams;
    const NAME: &'static str = "bvh";

    fn presets() -> Vec<(&'static str, BvhParams)> {
        vec![
            ("sah", BvhParams::sah()),
            ("median", BvhParams::median()),
            ("middle", BvhParams::middle()),
        ]
    }

    fn build(prims: &[P], params: &BvhParams) -> Self {
        let b = builder::build(prims, params);
        Self {
            nodes: b.nodes,
            prims: b.prims,
            ids: b.ids,
            max_depth: b.max_depth,
            leaves: b.leaves,
        }
    }

    #[inline]
    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
        self.traverse::<S, false>(ray, stats)
    }

    #[inline]
    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        self.traverse::<S, true>(ray, stats).is_some()
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.nodes.capacity() * size_of::<Node>()
            + self.prims.capacity() * size_of::<P>()
            + self.ids.capacity() * size_of::<u32>()
    }

    fn build_stats(&self) -> BuildStats {
        BuildStats {
            nodes: if self.prims.is_empty() {
                0
            } else {
                self.nodes.len()
            },
            leaves: self.leaves,
            empty_leaves: 0,
            max_depth: self.max_depth,
            prim_refs: self.prims.len(),
            valid_prims: self.prims.len(),
            extra: Vec::new(),
        }
    }
}

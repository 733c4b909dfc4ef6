//! Lab: traversing an octree, in five steps.
//!
//! An octree cuts a cube at its centre into eight equal cubes, and each of those again where
//! triangles crowd, until a leaf holds few. The tree here is built for you by `rt-octree`'s
//! builder (the one the `octree` row of the shootout uses); you write the walk, with the
//! parametric algorithm of Revelles, Ureña & Lastra (2000): everything is decided by the ray
//! parameters at which it crosses planes, never by points, and a node's children get their
//! parameters from their parent's without a division. Read `HANDOUT.md` first; then fill in the
//! `todo!()`s step by step, checking each with `cargo test step_N`:
//!
//! 1. [`step1`]: the per-ray constants (mirrored axes, flat axes) and the parameters of a box's
//!    near and far faces.
//! 2. [`step2`]: the mid-planes' parameters, a child's faces from its parent's, and the order
//!    in which the ray passes through a node's children.
//! 3. [`step3`]: the walk over the leaves, front to back, with a stack of nodes.
//! 4. [`step4`]: the walk for a query (the closest hit is one), with the rule for when it may
//!    stop, and a mailbox.
//! 5. [`step5`]: the any-hit walk (shadow rays): stop at the first hit.
//!
//! Nothing outside the step files needs to change: this file builds the tree, gives the cut
//! every node is made at, and wires the steps into the [`rt_core::Accel`] trait, so the
//! conformance kit and the shootout can run your traversal.

use rt_core::glam::Vec3;
use rt_core::query::Deduplicated;
use rt_core::{Aabb, Accel, BallQuery, BuildStats, Ray, RayQuery, Region, Stats, Triangle};
use rt_octree::Octree;

pub use rt_octree::{Block, MAX_DEPTH, Node, OctreeParams};

pub mod step1;
pub mod step2;
pub mod step3;
pub mod step4;
pub mod step5;

/// Parameters: how the tree is built, and whether the walk keeps a mailbox.
#[derive(Clone, Debug, Default)]
pub struct OctreeLabParams {
    /// The builder's parameters (`rt_octree::OctreeParams`; the default cuts nodes of more than
    /// 8 triangles, down to depth 12).
    pub tree: OctreeParams,
    /// Whether a ray skips a triangle it tested in an earlier leaf (step 4).
    pub no_mailbox: bool,
}

/// An octree built by `rt-octree`, walked by your code.
#[derive(Clone, Debug)]
pub struct LabOctree {
    /// The built tree: [`Octree::root`] (its box is [`Octree::bounds`], a cube), and
    /// [`Octree::blocks`]: an interior node's eight children are
    /// `blocks()[node.children().unwrap()].0`, child `i` covering the upper half of its parent
    /// on axis `a` exactly when bit `a` of `i` is set (x is bit 0, y bit 1, z bit 2). A leaf
    /// lists `references()[node.references()]`; an empty leaf lists nothing.
    pub tree: Octree<Triangle>,
    /// The input triangles; hits name their index here.
    pub tris: Vec<Triangle>,
    /// The parameters it was built with.
    pub params: OctreeLabParams,
}

impl LabOctree {
    /// The triangle indices leaf `node` lists.
    pub fn leaf_ids(&self, node: &Node) -> &[u32] {
        &self.tree.references()[node.references()]
    }
}

/// Where a node with box `[lo, hi]` is cut into eight: `lo / 2 + hi / 2` per axis, exactly as
/// the builder cuts it. Compute the mid-planes with this function and nothing else: a plane
/// the walk puts a hair away from the builder's would put a triangle on the wrong side of it.
pub fn mid(lo: Vec3, hi: Vec3) -> Vec3 {
    lo * 0.5 + hi * 0.5
}

/// The box of child `i` (block order: bit `a` of `i` set for the upper half on axis `a`) of a
/// node with box `[lo, hi]`.
pub fn child_box(lo: Vec3, hi: Vec3, i: u32) -> (Vec3, Vec3) {
    let m = mid(lo, hi);
    let upper = rt_core::glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0);
    (Vec3::select(upper, m, lo), Vec3::select(upper, hi, m))
}

impl Accel for LabOctree {
    type Prim = Triangle;
    type Params = OctreeLabParams;
    const NAME: &'static str = "lab-octree";

    fn presets() -> Vec<(&'static str, OctreeLabParams)> {
        let no_mailbox = OctreeLabParams {
            no_mailbox: true,
            ..OctreeLabParams::default()
        };
        vec![
            ("default", OctreeLabParams::default()),
            ("nomailbox", no_mailbox),
        ]
    }

    fn build(prims: &[Triangle], params: &OctreeLabParams) -> Self {
        Self {
            tree: Octree::build(prims, &params.tree),
            tris: prims.to_vec(),
            params: params.clone(),
        }
    }

    /// The walks of steps 4 and 5: an occlusion query (a shadow ray's) takes step 5's walk,
    /// every other query step 4's. A query that must see each hit once (all hits, counts) is
    /// offered each triangle once ([`Deduplicated`]), since the walk may meet a triangle again.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if Q::OCCLUSION {
            step5::any_hit(self, ray, query, stats);
        } else if Q::REPEATABLE {
            step4::walk(self, ray, query, stats);
        } else {
            step4::walk(self, ray, &mut Deduplicated::new(query), stats);
        }
    }

    fn bounds(&self) -> Aabb {
        Accel::bounds(&self.tree)
    }

    /// Closest points are not a step of this lab: `rt-octree`'s own query answers them.
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.tree.ball_query(query, stats);
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>() + self.tree.memory_bytes() + self.tris.capacity() * size_of::<Triangle>()
    }

    fn build_stats(&self) -> BuildStats {
        self.tree.build_stats()
    }

    fn regions(&self, visit: &mut dyn FnMut(Region)) {
        self.tree.regions(visit);
    }
}

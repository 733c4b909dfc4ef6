//! Lab: traversing a kd-tree, in five steps.
//!
//! A kd-tree cuts space in two with an axis-aligned plane, then each half again, until a leaf's
//! cell holds few triangles. The tree here is built for you by `rt-kdtree`'s SAH builder (the
//! one the `kdtree` row of the shootout uses); you write the walk. A ray meets the cells of a
//! kd-tree in order along its length, and its nodes store no box, only a plane: the whole
//! traversal is about the parameter interval `[t0, t1]` the ray spends in the current cell and
//! where the plane cuts it. Read `HANDOUT.md` first; then fill in the `todo!()`s step by step,
//! checking each with `cargo test step_N`:
//!
//! 1. [`step1`]: where the ray crosses a node's plane, and which child it meets first.
//! 2. [`step2`]: which children the interval `[t0, t1]` reaches, with the corner cases.
//! 3. [`step3`]: the walk over the leaves, in order, with a stack of far children.
//! 4. [`step4`]: the walk for a query (the closest hit is one), with the rule for when it may
//!    stop, and a mailbox.
//! 5. [`step5`]: the any-hit walk (shadow rays): stop at the first hit.
//!
//! Nothing outside the step files needs to change: this file builds the tree and wires the
//! steps into the [`rt_core::Accel`] trait, so the conformance kit and the shootout can run
//! your traversal.

// Until a step is written, its stub leaves parameters and imports unused. (The reference
// solution's copy of this file has no such line.)
#![allow(unused_imports, unused_variables)]

use rt_core::query::Deduplicated;
use rt_core::{Aabb, Accel, BallQuery, BuildStats, Ray, RayQuery, Region, Stats, Triangle};
use rt_kdtree::{KdParams, KdTree};

pub use rt_kdtree::{MAX_DEPTH, Node};

pub mod step1;
pub mod step2;
pub mod step3;
pub mod step4;
pub mod step5;

/// Parameters: how the tree is built, and whether the walk keeps a mailbox.
#[derive(Clone, Debug, Default)]
pub struct KdLabParams {
    /// The builder's parameters (`rt_kdtree::KdParams`; the default is its SAH build).
    pub tree: KdParams,
    /// Whether a ray skips a triangle it tested in an earlier leaf (step 4).
    pub no_mailbox: bool,
}

/// A kd-tree built by `rt-kdtree`, walked by your code.
#[derive(Clone, Debug)]
pub struct LabKdTree {
    /// The built tree: [`KdTree::nodes`] (root first; an interior node's children are
    /// `index()` and `index() + 1`), [`KdTree::references`] (a leaf lists
    /// `references()[index()..index() + count()]`), and [`KdTree::bounds`] (the root's cell).
    pub tree: KdTree<Triangle>,
    /// The input triangles; hits name their index here.
    pub tris: Vec<Triangle>,
    /// The parameters it was built with.
    pub params: KdLabParams,
}

impl LabKdTree {
    /// The triangle indices leaf `node` lists.
    pub fn leaf_ids(&self, node: &Node) -> &[u32] {
        &self.tree.references()[node.index()..node.index() + node.count()]
    }
}

impl Accel for LabKdTree {
    type Prim = Triangle;
    type Params = KdLabParams;
    const NAME: &'static str = "lab-kdtree";

    fn presets() -> Vec<(&'static str, KdLabParams)> {
        let no_mailbox = KdLabParams {
            no_mailbox: true,
            ..KdLabParams::default()
        };
        vec![
            ("default", KdLabParams::default()),
            ("nomailbox", no_mailbox),
        ]
    }

    fn build(prims: &[Triangle], params: &KdLabParams) -> Self {
        Self {
            tree: KdTree::build(prims, &params.tree),
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
        self.tree.bounds()
    }

    /// Closest points are not a step of this lab: `rt-kdtree`'s own query answers them.
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

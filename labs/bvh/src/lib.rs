//! Lab: a bounding volume hierarchy, in seven steps.
//!
//! A BVH groups the triangles into a binary tree of boxes: each leaf lists a few triangles,
//! each interior node's box holds its two children's. A ray enters a node only if it meets the
//! node's box, so one box test skips a whole subtree. Unlike a grid's cells or a kd-tree's
//! halves, sibling boxes may overlap, and every triangle sits in exactly one leaf. Read
//! `HANDOUT.md` first; then fill in the `todo!()`s step by step, checking each with
//! `cargo test step_N`:
//!
//! 1. [`step1`]: the box around some triangles and the box around their centroids; where a ray
//!    enters a box.
//! 2. [`step2`]: the build with a median split, written depth first into one array of nodes.
//! 3. [`step3`]: one traversal step: which children of a node the ray enters, nearest first.
//! 4. [`step4`]: the walk for a query (the closest hit is one): a stack, nearest child first,
//!    and nothing beyond the query's far end.
//! 5. [`step5`]: the any-hit walk (shadow rays): stop at the first hit.
//! 6. [`step6`]: the surface area heuristic (SAH) instead of the median split.
//! 7. [`step7`]: ray packets: up to 64 coherent rays down the tree together.
//!
//! Nothing outside the step files needs to change: this file holds the node layout, the
//! split dispatcher, a `validate` for the tree, and wires the steps into the
//! [`rt_core::Accel`] trait, so the conformance kit and the shootout can run your BVH.

// Until a step is written, its stub leaves parameters and imports unused. (The reference
// solution's copy of this file has no such line.)
#![allow(unused_imports, unused_variables)]

use rt_core::query::Deduplicated;
use rt_core::{
    Aabb, Accel, BallQuery, BuildStats, Hit, Primitive, Ray, RayQuery, Region, Stats, Triangle,
    ValidationError, predicted_cost,
};
use rt_simd::Bundle;

pub mod step1;
pub mod step2;
pub mod step3;
pub mod step4;
pub mod step5;
pub mod step6;
pub mod step7;

/// The deepest a tree may be: the traversal stack has room for this many nodes.
pub const MAX_DEPTH: usize = 64;

/// Below this depth the SAH chooses the splits; deeper, the median split does, so that even a
/// scene the SAH splits badly (one triangle off per level) stays within [`MAX_DEPTH`].
pub const SAH_DEPTH: usize = 24;

/// The widest spread of directions (about the angle in radians, [`Bundle::direction_spread`])
/// a bundle may have to walk as a packet (step 7); wider bundles go ray by ray. Rays that far
/// apart share few boxes below the top of the tree, and carrying them together costs more than
/// it saves.
pub const MAX_SPREAD: f32 = 1.0;

/// The point that stands for a triangle where the builder sorts and bins triangles: the centre
/// of its box. `rt-bvh`'s builder takes the same point, so the median split here and its
/// `bvh-median` row make the same tree. (The vertices' mean, [`Primitive::centroid`], is the
/// other common choice: it moves long thin triangles to other sides of a split, and so makes a
/// different tree with different figures.)
pub fn centroid(t: &Triangle) -> rt_core::glam::Vec3 {
    t.bounds().center()
}

/// How the builder chooses where to split a node's triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Split {
    /// Half the triangles to each side, along the widest axis of their centroids (step 2).
    Median,
    /// The cheapest of several planes by the surface area heuristic (step 6).
    Sah,
}

/// Build parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhParams {
    /// How to split.
    pub split: Split,
    /// A node of at most this many triangles becomes a leaf with the median split; the SAH may
    /// make leaves up to this size, and must split bigger nodes.
    pub leaf_size: usize,
    /// Whether the bundle queries ([`Accel::intersect_bundle_with`]) trace coherent rays as
    /// packets (step 7) rather than one ray at a time (the trait's default loop).
    pub packets: bool,
}

impl Default for BvhParams {
    fn default() -> Self {
        Self {
            split: Split::Median,
            leaf_size: 4,
            packets: false,
        }
    }
}

impl BvhParams {
    /// The SAH split (step 6), leaves of up to 8 triangles where the SAH finds them cheaper.
    pub fn sah() -> Self {
        Self {
            split: Split::Sah,
            leaf_size: 8,
            packets: false,
        }
    }

    /// The SAH tree (step 6), its bundle queries traced as packets (step 7).
    pub fn packets() -> Self {
        Self {
            packets: true,
            ..Self::sah()
        }
    }
}

/// One node of the flat tree, 32 bytes. The tree is stored depth first: an interior node's
/// first child is the next node in the array, its second child is at `first`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// The box around every triangle below this node.
    pub bounds: Aabb,
    /// A leaf: where its triangles start in [`LabBvh::ids`]. An interior node: the index of its
    /// second child.
    pub first: u32,
    /// A leaf: how many triangles it lists (at least 1). An interior node: 0.
    pub count: u32,
}

const _: () = assert!(size_of::<Node>() == 32);

impl Node {
    /// Whether this node is a leaf.
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// The BVH: the nodes, and the triangle indices the leaves list.
#[derive(Clone, Debug)]
pub struct LabBvh {
    /// The nodes, depth first; node 0 is the root. Empty when no triangle is valid.
    pub nodes: Vec<Node>,
    /// Indices of the valid triangles, leaf after leaf: a leaf lists
    /// `ids[first..first + count]`.
    pub ids: Vec<u32>,
    /// The input triangles; hits name their index here.
    pub tris: Vec<Triangle>,
    /// The parameters it was built with.
    pub params: BvhParams,
}

impl LabBvh {
    /// The two children of interior node `i`: `[i + 1, nodes[i].first]`.
    pub fn children(&self, i: u32) -> [u32; 2] {
        [i + 1, self.nodes[i as usize].first]
    }

    /// The triangle indices a leaf lists.
    pub fn leaf_ids(&self, node: &Node) -> &[u32] {
        &self.ids[node.first as usize..(node.first + node.count) as usize]
    }

    /// The cost the SAH predicts for a line through the root's box: nodes entered plus
    /// triangles tested (traversal and intersection costing the same). Lower is better; the
    /// SAH build (step 6) minimises it one split at a time.
    pub fn sah_cost(&self) -> f64 {
        let mut regions = Vec::new();
        self.regions(&mut |r| regions.push(r));
        predicted_cost(&regions).map_or(0.0, |c| c.visits + c.tests)
    }

    /// The depth of the deepest leaf (the root alone has depth 0).
    pub fn depth(&self) -> usize {
        let mut deepest = 0;
        self.walk(&mut |_, depth| deepest = deepest.max(depth));
        deepest
    }

    /// Calls `visit(index, depth)` for every node reachable from the root, parents first.
    fn walk(&self, visit: &mut dyn FnMut(u32, usize)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![(0u32, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            visit(i, depth);
            let node = &self.nodes[i as usize];
            if !node.is_leaf() && depth < MAX_DEPTH {
                for c in self.children(i) {
                    if (c as usize) < self.nodes.len() {
                        stack.push((c, depth + 1));
                    }
                }
            }
        }
    }

    /// Checks the tree's invariants: every child after its parent and inside the array, every
    /// box holding what lies below it, every node reached exactly once, every valid triangle in
    /// exactly one leaf and no invalid one in any, no leaf empty, depth within [`MAX_DEPTH`].
    pub fn validate(&self) -> Result<(), ValidationError> {
        let err = |s: String| Err(ValidationError::new(s));
        let valid = self.tris.iter().filter(|t| t.is_valid()).count();
        if self.nodes.is_empty() {
            return if valid == 0 && self.ids.is_empty() {
                Ok(())
            } else {
                err(format!("no nodes, but {valid} valid triangles"))
            };
        }
        let n = self.nodes.len();
        let mut reached = vec![0u32; n];
        let mut listed = vec![0u32; self.tris.len()];
        let mut problem = None;
        self.walk(&mut |i, depth| {
            reached[i as usize] += 1;
            let node = &self.nodes[i as usize];
            if problem.is_some() {
                return;
            }
            if depth >= MAX_DEPTH {
                problem = Some(format!(
                    "node {i} is at depth {depth}, the limit is {MAX_DEPTH}"
                ));
            } else if node.is_leaf() {
                let end = node.first as usize + node.count as usize;
                if end > self.ids.len() {
                    problem = Some(format!(
                        "leaf {i} lists ids up to {end} of {}",
                        self.ids.len()
                    ));
                    return;
                }
                for &id in self.leaf_ids(node) {
                    let Some(t) = self.tris.get(id as usize) else {
                        problem = Some(format!("leaf {i} lists triangle {id}, which is not one"));
                        return;
                    };
                    listed[id as usize] += 1;
                    if !t.is_valid() {
                        problem = Some(format!("leaf {i} lists invalid triangle {id}"));
                    } else if !node.bounds.contains(&t.bounds()) {
                        problem = Some(format!("leaf {i}'s box does not hold triangle {id}"));
                    }
                }
            } else {
                for c in self.children(i) {
                    if c <= i || c as usize >= n {
                        problem = Some(format!("node {i} has child {c} (of {n} nodes)"));
                    } else if !node.bounds.contains(&self.nodes[c as usize].bounds) {
                        problem = Some(format!("node {i}'s box does not hold child {c}'s"));
                    }
                }
            }
        });
        if let Some(p) = problem {
            return err(p);
        }
        if let Some(i) = reached.iter().position(|&r| r != 1) {
            return err(format!(
                "node {i} is reached {} times, not once",
                reached[i]
            ));
        }
        for (id, t) in self.tris.iter().enumerate() {
            if t.is_valid() && listed[id] != 1 {
                return err(format!(
                    "triangle {id} is in {} leaves, not one",
                    listed[id]
                ));
            }
        }
        if self.ids.len() != valid {
            return err(format!(
                "{} ids for {valid} valid triangles",
                self.ids.len()
            ));
        }
        Ok(())
    }
}

impl LabBvh {
    /// The bundle queries with packets: the first `slots` rays sorted into bundles by rt-core
    /// ([`rt_simd::bundle::walk_groups`]); a bundle that misses the root's box answered "no
    /// hit" at once; one of directions within [`MAX_SPREAD`] walked by step 7; every other ray
    /// traced by steps 4 and 5. Calls `answer(slot, answer)` for each ray, where an any-hit
    /// answer is `Some` when the ray is blocked.
    fn packet_query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        stats: &mut S,
        answer: impl FnMut(usize, Option<Hit>),
    ) {
        let bounds = self.bounds();
        rt_simd::bundle::walk_groups::<S, ANY>(
            rays,
            slots,
            stats,
            |ray, stats| rt_simd::bundle::single::<_, S, ANY>(self, ray, stats),
            |b: &Bundle| b.route(&bounds, |b| b.direction_spread() <= MAX_SPREAD),
            |b, lanes, stats| {
                step7::walk::<S, ANY>(self, b, lanes, stats);
                // No lane is left to the single-ray walk.
                0
            },
            answer,
        );
    }
}

/// Where to split a node's triangles `ids`, whose box is `bounds` and centroids' box
/// `centroids`, at depth `depth`: reorders `ids` and returns how many of them go to the first
/// child, or `None` to make a leaf. Dispatches on `params.split`, and guards the build: the SAH
/// gives way to the median split where it finds no split but the node is too big for a leaf,
/// and deep in the tree; a split that leaves one side empty makes a leaf instead of looping.
pub fn split(
    tris: &[Triangle],
    params: &BvhParams,
    ids: &mut [u32],
    bounds: &Aabb,
    centroids: &Aabb,
    depth: usize,
) -> Option<usize> {
    let n = ids.len();
    if n <= 1 || depth + 1 >= MAX_DEPTH {
        return None;
    }
    let mid = match params.split {
        Split::Median if n <= params.leaf_size => return None,
        Split::Median => step2::median_split(tris, ids, centroids),
        Split::Sah if depth >= SAH_DEPTH => step2::median_split(tris, ids, centroids),
        Split::Sah => match step6::sah_split(tris, ids, bounds, centroids, params.leaf_size) {
            Some(mid) => mid,
            None if n > params.leaf_size => step2::median_split(tris, ids, centroids),
            None => return None,
        },
    };
    (0 < mid && mid < n).then_some(mid)
}

impl Accel for LabBvh {
    type Prim = Triangle;
    type Params = BvhParams;
    const NAME: &'static str = "lab-bvh";

    fn presets() -> Vec<(&'static str, BvhParams)> {
        vec![
            ("default", BvhParams::default()),
            ("sah", BvhParams::sah()),
            ("packets", BvhParams::packets()),
        ]
    }

    fn build(prims: &[Triangle], params: &BvhParams) -> Self {
        let mut bvh = step2::build(prims, params);
        // A vector that grew by doubling may hold up to twice what it uses: the tree keeps only
        // its nodes and ids, so that its memory figure counts those.
        bvh.nodes.shrink_to_fit();
        bvh.ids.shrink_to_fit();
        bvh
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

    /// With [`BvhParams::packets`], coherent rays go down the tree as packets (step 7).
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        if self.params.packets {
            self.packet_query::<S, false>(rays, out.len(), stats, |slot, hit| out[slot] = hit);
        } else {
            rt_core::bundle::intersect_each(self, rays, out, stats);
        }
    }

    /// With [`BvhParams::packets`], coherent rays go down the tree as packets (step 7).
    fn occluded_bundle_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        if self.params.packets {
            self.packet_query::<S, true>(rays, out.len(), stats, |slot, hit| {
                out[slot] = hit.is_some();
            });
        } else {
            rt_core::bundle::occluded_each(self, rays, out, stats);
        }
    }

    fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |root| root.bounds)
    }

    /// Closest points are not a step of this lab. This answers them nearest box first: the
    /// nearer child next, the other on a stack with its distance, skipped when popped if the
    /// ball has shrunk below it.
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        let c = query.center();
        let mut stack = vec![(0u32, 0.0f32)];
        if self.nodes.is_empty() || self.nodes[0].bounds.distance_squared(c) > query.radius_sq() {
            return;
        }
        while let Some((i, d)) = stack.pop() {
            if d > query.radius_sq() {
                continue;
            }
            stats.node_visit();
            let node = &self.nodes[i as usize];
            if node.is_leaf() {
                for &id in &self.ids[node.first as usize..(node.first + node.count) as usize] {
                    stats.prim_test();
                    query.test(&self.tris[id as usize], id);
                }
                continue;
            }
            let mut children = self
                .children(i)
                .map(|k| (k, self.nodes[k as usize].bounds.distance_squared(c)));
            if children[0].1 < children[1].1 {
                children.swap(0, 1);
            }
            stack.extend(
                children
                    .into_iter()
                    .filter(|&(_, d)| d <= query.radius_sq()),
            );
        }
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.nodes.capacity() * size_of::<Node>()
            + self.ids.capacity() * 4
            + self.tris.capacity() * size_of::<Triangle>()
    }

    fn build_stats(&self) -> BuildStats {
        let leaves = self.nodes.iter().filter(|n| n.is_leaf()).count();
        BuildStats {
            nodes: self.nodes.len(),
            leaves,
            empty_leaves: 0,
            max_depth: self.depth(),
            prim_refs: self.ids.len(),
            valid_prims: self.tris.iter().filter(|t| t.is_valid()).count(),
            extra: vec![("sah_cost", self.sah_cost())],
        }
    }

    fn regions(&self, visit: &mut dyn FnMut(Region)) {
        self.walk(&mut |i, depth| {
            let node = &self.nodes[i as usize];
            visit(Region {
                bounds: node.bounds,
                depth: depth as u32,
                prims: node.is_leaf().then_some(node.count),
                split: None,
            });
        });
    }
}

//! The build: cut the root cube into eight equal children, recursively, depth first.
//!
//! A node holds its primitives as `(index, clipped box)` pairs: the box is the primitive's part
//! inside the node ([`Primitive::clip_bounds`], exact and rounded outwards for triangles). A pair
//! whose box lies on one side of all three mid-planes goes to that one child as it is; any other
//! is clipped against each child its box reaches (widened by a few units in the last place, see
//! [`margin`]) and goes to those it really overlaps, with the tighter box. The lists stay in
//! increasing index order, so leaves need no sort.
//!
//! A node stays a leaf when it holds at most `max_prims` primitives, lies at `max_depth`, can no
//! longer be halved in `f32`, or when cutting it would separate nothing: one child would keep all
//! of its primitives while the other seven together hold at least half as many references again.
//! That is the signature of primitives around a point or a plane (a fan of triangles around a
//! vertex, identical triangles on a mid-plane), which every level would repeat, whereas a zoom
//! into a cluster inside one octant (the other children nearly empty) goes on. Above all, the
//! tree never holds more than `max_refs_per_prim` references per primitive (and at least 2¹⁴):
//! each node has a budget of references, which its children's lists must fit, and the rest of
//! which is shared among them in proportion to their lists. So the tree is bounded whatever the
//! input, and it does not depend on threading.
//!
//! The nodes are written depth first as they are cut, each node's children in one block, so the
//! build holds only the lists of the nodes on its current paths and of their waiting siblings: at
//! most about the root's list again, 28 bytes per reference, whereas a level of a deep tree holds
//! several times that. Subtrees of large nodes are built in parallel with rayon, each into a part
//! of its own that is appended in order.

use crate::OctreeParams;
use crate::node::{Block, Node, child_box, midpoint, root_box};
use rt_core::par;
use rt_core::{Aabb, Primitive, glam::Vec3};

/// The deepest any octree goes (the root has depth 0): the traversal's fixed stack holds one
/// frame per level. A node at this depth is `2⁻²⁰` of the root's side, about 8 units in the last
/// place of an `f32` coordinate at the root's far corner.
pub const MAX_DEPTH: u32 = 20;

/// Nodes with at least this many references build their children in parallel.
const PARALLEL_MIN: usize = 4096;

/// The reference budget is never below this many references, so small scenes can always be
/// cut deep.
const MIN_REF_BUDGET: usize = 1 << 14;

/// What the builder hands to [`Octree`](crate::Octree).
#[derive(Debug)]
pub(crate) struct Built {
    pub root: Node,
    pub blocks: Vec<Block>,
    pub refs: Vec<u32>,
    pub bounds: Aabb,
    pub valid_prims: usize,
    pub depth: u32,
}

/// A primitive in a node: its index and the bounds of its part inside the node.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Item {
    pub id: u32,
    pub b: Aabb,
}

/// A tree or subtree being written: its blocks and references, depth first.
#[derive(Default)]
struct Part {
    blocks: Vec<Block>,
    refs: Vec<u32>,
    depth: u32,
}

struct Ctx<'a, P> {
    prims: &'a [P],
    max_prims: usize,
    max_depth: u32,
    parallel: bool,
    margin: Vec3,
}

pub(crate) fn build<P: Primitive>(prims: &[P], params: &OctreeParams) -> Built {
    let (ids, bounds) = rt_core::valid_primitives(prims);
    let mut out = Built {
        root: Node::leaf(0, 0),
        blocks: Vec::new(),
        refs: Vec::new(),
        bounds: Aabb::new(Vec3::ZERO, Vec3::ZERO),
        valid_prims: ids.len(),
        depth: 0,
    };
    if ids.is_empty() {
        return out;
    }
    out.bounds = root_box(&bounds);
    let ctx = Ctx {
        prims,
        max_prims: params.max_prims as usize,
        max_depth: params.max_depth.min(MAX_DEPTH),
        parallel: params.parallel,
        margin: margin(&out.bounds),
    };
    let budget = ((params.max_refs_per_prim.max(1.0) as f64 * ids.len() as f64) as usize)
        .max(MIN_REF_BUDGET);
    let items: Vec<Item> = ids
        .iter()
        .map(|&id| Item {
            id,
            b: prims[id as usize].bounds().intersection(&out.bounds),
        })
        .collect();
    drop(ids);
    let mut part = Part::default();
    out.root = node(&ctx, items, out.bounds, 0, budget, &mut part);
    out.blocks = part.blocks;
    out.refs = part.refs;
    out.depth = part.depth;
    out.blocks.shrink_to_fit();
    out.refs.shrink_to_fit();
    out
}

/// Builds the subtree of a node with box `b` at `depth` holding `items`, with at most `budget`
/// references, writing its blocks and references to `out` depth first (each node's children's
/// block, then their subtrees in order); returns the node.
///
/// The tree is built depth first, so the build holds the lists of the nodes on the current path
/// and their waiting siblings, not a whole level of the tree. The reference budget is shared out
/// down the tree: a cut is accepted if its children's references fit in the node's budget, and
/// what is left over goes to the children in proportion to their references. So the tree never
/// holds more than the root's budget, and the shares, like the tree, do not depend on threading.
fn node<P: Primitive>(
    ctx: &Ctx<'_, P>,
    items: Vec<Item>,
    b: Aabb,
    depth: u32,
    budget: usize,
    out: &mut Part,
) -> Node {
    out.depth = out.depth.max(depth);
    let n = items.len();
    if n <= ctx.max_prims || depth >= ctx.max_depth || !divisible(&b) {
        return leaf(&items, out);
    }
    let parts = split_parts(ctx, &items, &b);
    let counts: [usize; 8] = std::array::from_fn(|i| parts.iter().map(|p| p[i].len()).sum());
    let total: usize = counts.iter().sum();
    // A split that leaves one child with every primitive separates nothing. It is still worth
    // it as a zoom into a cluster that lies (nearly) inside one octant, such as a teapot in a
    // stadium cell, with little outside; but if the other children hold half as many references
    // again, the primitives surround a point or overlap around a plane (a fan of triangles
    // around a vertex, identical triangles on a mid-plane), and every level would repeat it.
    let separates = !counts.contains(&n) || 2 * (total - n) < n;
    if !separates || total > budget {
        return leaf(&items, out);
    }
    drop(items);
    let children = gather(parts, &counts);
    let slack = (budget - total) as u128;
    let budgets: [usize; 8] = std::array::from_fn(|i| {
        counts[i] + (slack * counts[i] as u128 / total.max(1) as u128) as usize
    });
    let mid = midpoint(&b);
    let block = out.blocks.len();
    out.blocks.push(Block([Node::leaf(0, 0); 8]));
    let child = |i: usize, items: Vec<Item>, out: &mut Part| {
        node(
            ctx,
            items,
            child_box(&b, mid, i),
            depth + 1,
            budgets[i],
            out,
        )
    };
    if ctx.parallel && n >= PARALLEL_MIN {
        // Each child's subtree is built into a part of its own, then appended in order, so the
        // layout is the sequential one.
        let numbered: Vec<_> = children.into_iter().enumerate().collect();
        let subtrees: Vec<(Node, Part)> = par::map_vec(numbered, |(i, items)| {
            let mut part = Part::default();
            let node = child(i, items, &mut part);
            (node, part)
        });
        out.blocks
            .reserve_exact(subtrees.iter().map(|(_, p)| p.blocks.len()).sum());
        out.refs
            .reserve_exact(subtrees.iter().map(|(_, p)| p.refs.len()).sum());
        for (i, (node, part)) in subtrees.into_iter().enumerate() {
            let (blocks, refs) = (out.blocks.len(), out.refs.len());
            out.blocks[block].0[i] = node.relocated(blocks, refs);
            out.blocks.extend(
                part.blocks
                    .iter()
                    .map(|k| Block(k.0.map(|c| c.relocated(blocks, refs)))),
            );
            out.refs.extend_from_slice(&part.refs);
            out.depth = out.depth.max(part.depth);
        }
    } else {
        for (i, items) in children.into_iter().enumerate() {
            out.blocks[block].0[i] = child(i, items, out);
        }
    }
    Node::interior(block)
}

/// A leaf listing `items`, with its references appended to `out`.
fn leaf(items: &[Item], out: &mut Part) -> Node {
    let node = Node::leaf(out.refs.len(), items.len());
    out.refs.extend(items.iter().map(|i| i.id));
    node
}

/// Whether halving `b` on every axis gives eight smaller boxes in `f32`.
pub(crate) fn divisible(b: &Aabb) -> bool {
    let mid = midpoint(b);
    b.min.cmplt(mid).all() && mid.cmplt(b.max).all()
}

/// How far a child's box is widened, per axis, for the overlap test: eight units in the last
/// place of the root's coordinates. A primitive within rounding of a mid-plane is listed on both
/// sides, and one that merely touches a node (where the clipper's rounding could go either way)
/// is listed in the neighbours it touches with room to spare.
pub(crate) fn margin(root: &Aabb) -> Vec3 {
    (root.min.abs() + root.max.abs()) * (f32::EPSILON * 8.0)
}

/// The children's lists for a node with box `b` holding `items`: each item goes to the children
/// its box reaches (widened by `margin`); where that is more than one, only to those the
/// primitive itself overlaps, with its box clipped to them. The validator rebuilds the lists with
/// this same function.
pub(crate) fn split<P: Primitive>(
    prims: &[P],
    items: &[Item],
    b: &Aabb,
    margin: Vec3,
) -> [Vec<Item>; 8] {
    let mid = midpoint(b);
    let mut out: [Vec<Item>; 8] = Default::default();
    for item in items {
        let lower = item.b.min.cmple(mid + margin).bitmask();
        let upper = item.b.max.cmpge(mid - margin).bitmask();
        if lower ^ upper == 7 {
            // One side of every mid-plane: the item's box lies in child `upper`.
            out[upper as usize].push(*item);
            continue;
        }
        for (i, list) in out.iter_mut().enumerate() {
            let i = i as u32;
            if i & !upper != 0 || !i & 7 & !lower != 0 {
                continue;
            }
            let c = child_box(b, mid, i as usize);
            let test = Aabb::new(c.min - margin, c.max + margin);
            if let Some(cb) = prims[item.id as usize].clip_bounds(&test) {
                list.push(Item { id: item.id, b: cb });
            }
        }
    }
    out
}

/// The children's lists of [`split`], as one set of lists per chunk of `items` (chunks are split
/// in parallel for large nodes); [`gather`] joins them.
fn split_parts<P: Primitive>(ctx: &Ctx<'_, P>, items: &[Item], b: &Aabb) -> Vec<[Vec<Item>; 8]> {
    let split = |chunk: &[Item]| {
        let mut lists = split(ctx.prims, chunk, b, ctx.margin);
        // The lists grew by doubling; a large node's chunks all wait for the join, so their
        // slack would add up to as much again as the lists themselves.
        lists.iter_mut().for_each(Vec::shrink_to_fit);
        lists
    };
    if !ctx.parallel || items.len() < PARALLEL_MIN {
        return vec![split(items)];
    }
    par::map_chunks(items, PARALLEL_MIN, split)
}

/// Joins the chunks' lists into the children's lists (of `counts` items), freeing each chunk's
/// list once it is copied, so the copies never hold much more than the lists themselves.
fn gather(mut parts: Vec<[Vec<Item>; 8]>, counts: &[usize; 8]) -> [Vec<Item>; 8] {
    if parts.len() == 1 {
        return parts.pop().unwrap_or_default();
    }
    std::array::from_fn(|i| {
        let mut list = Vec::with_capacity(counts[i]);
        for p in &mut parts {
            list.extend_from_slice(&p[i]);
            p[i] = Vec::new();
        }
        list
    })
}

//! The build: cut the root cube into eight equal children, recursively, then flatten.
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
//! the tree is cut one level at a time, every node of a level proposes its split, in parallel
//! with rayon, and the splits are accepted in order while the budget lasts. So the memory is
//! bounded whatever the input, and the tree does not depend on threading. It is flattened depth
//! first afterwards, each node's children in one block.

use crate::OctreeParams;
use crate::node::{Block, Node, child_box, midpoint, root_box};
use rayon::prelude::*;
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

/// A node of the tree before flattening: its list, or where its eight children start.
enum Temp {
    Leaf(Vec<u32>),
    Interior(usize),
}

/// A node of the level being cut: its place in the arena, its box and its primitives.
struct Pending {
    slot: usize,
    b: Aabb,
    items: Vec<Item>,
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
    let items = ids
        .iter()
        .map(|&id| Item {
            id,
            b: prims[id as usize].bounds().intersection(&out.bounds),
        })
        .collect();
    // The tree is cut one level at a time: every node of a level proposes its split (in
    // parallel), then the splits are accepted in order while the reference budget lasts, so the
    // tree does not depend on threading and its memory is bounded whatever the input.
    let budget = ((params.max_refs_per_prim.max(1.0) as f64 * ids.len() as f64) as usize)
        .max(MIN_REF_BUDGET);
    let mut refs = ids.len();
    let mut arena = vec![Temp::Leaf(Vec::new())];
    let mut level = vec![Pending {
        slot: 0,
        b: out.bounds,
        items,
    }];
    for depth in 0.. {
        if level.is_empty() {
            break;
        }
        let propose = |p: &Pending| propose(&ctx, p, depth);
        let proposals: Vec<Option<[Vec<Item>; 8]>> = if ctx.parallel && refs >= PARALLEL_MIN {
            level.par_iter().map(propose).collect()
        } else {
            level.iter().map(propose).collect()
        };
        let mut next = Vec::new();
        for (p, proposal) in level.into_iter().zip(proposals) {
            let n = p.items.len();
            match proposal {
                Some(children)
                    if (refs + children.iter().map(Vec::len).sum::<usize>()).saturating_sub(n)
                        <= budget =>
                {
                    refs = (refs + children.iter().map(Vec::len).sum::<usize>()).saturating_sub(n);
                    let first = arena.len();
                    arena[p.slot] = Temp::Interior(first);
                    let mid = midpoint(&p.b);
                    for (i, items) in children.into_iter().enumerate() {
                        arena.push(Temp::Leaf(Vec::new()));
                        next.push(Pending {
                            slot: first + i,
                            b: child_box(&p.b, mid, i),
                            items,
                        });
                    }
                }
                _ => arena[p.slot] = Temp::Leaf(p.items.iter().map(|i| i.id).collect()),
            }
        }
        level = next;
    }
    out.root = flatten(&mut arena, 0, 0, &mut out);
    out.blocks.shrink_to_fit();
    out.refs.shrink_to_fit();
    out
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

/// [`split`], over chunks in parallel for large nodes; the lists come out the same.
fn split_items<P: Primitive>(ctx: &Ctx<'_, P>, items: &[Item], b: &Aabb) -> [Vec<Item>; 8] {
    if !ctx.parallel || items.len() < PARALLEL_MIN {
        return split(ctx.prims, items, b, ctx.margin);
    }
    let parts: Vec<[Vec<Item>; 8]> = items
        .par_chunks(PARALLEL_MIN)
        .map(|chunk| split(ctx.prims, chunk, b, ctx.margin))
        .collect();
    std::array::from_fn(|i| parts.iter().flat_map(|p| p[i].iter().copied()).collect())
}

/// The children's lists if node `p` at `depth` is to be cut, or `None` if it stays a leaf.
fn propose<P: Primitive>(ctx: &Ctx<'_, P>, p: &Pending, depth: u32) -> Option<[Vec<Item>; 8]> {
    let n = p.items.len();
    if n <= ctx.max_prims || depth >= ctx.max_depth || !divisible(&p.b) {
        return None;
    }
    let children = split_items(ctx, &p.items, &p.b);
    // A split that leaves one child with every primitive separates nothing. It is still worth
    // it as a zoom into a cluster that lies (nearly) inside one octant, such as a teapot in a
    // stadium cell, with little outside; but if the other children hold half as many references
    // again, the primitives surround a point or overlap around a plane (a fan of triangles
    // around a vertex, identical triangles on a mid-plane), and every level would repeat it.
    let full = children.iter().position(|c| c.len() == n);
    let others: usize = children.iter().map(Vec::len).sum::<usize>() - n;
    (full.is_none() || 2 * others < n).then_some(children)
}

/// Writes the arena's node `at` (at `depth`) into `out` and returns it: a leaf appends its
/// references; an interior node appends its children's block, then their subtrees, depth first.
fn flatten(arena: &mut [Temp], at: usize, depth: u32, out: &mut Built) -> Node {
    out.depth = out.depth.max(depth);
    match &mut arena[at] {
        Temp::Leaf(ids) => {
            let node = Node::leaf(out.refs.len(), ids.len());
            out.refs.extend_from_slice(ids);
            *ids = Vec::new();
            node
        }
        &mut Temp::Interior(first) => {
            let block = out.blocks.len();
            out.blocks.push(Block([Node::leaf(0, 0); 8]));
            for i in 0..8 {
                let node = flatten(arena, first + i, depth + 1, out);
                out.blocks[block].0[i] = node;
            }
            Node::interior(block)
        }
    }
}

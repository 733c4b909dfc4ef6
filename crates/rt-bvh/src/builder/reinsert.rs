//! Reinsertion: the binned SAH tree improved by moving subtrees (Bittner, Hapala & Havran 2013,
//! "Fast insertion-based optimization of bounding volume hierarchies"; selection by area as in
//! Meister & Bittner 2022, "Performance comparison of bounding volume hierarchies for GPU ray
//! tracing").
//!
//! A top-down build decides each split from the boxes' centres alone, and a poor decision near
//! the root is never revisited: a subtree may end up under a parent whose box it stretches. The
//! optimisation takes the whole split tree, and for the subtrees of largest area (those rays
//! enter most often) removes each one, finds the place where inserting it again adds the least
//! area, and moves it there if that costs less than its removal saved. Moves keep every leaf as
//! it is, so the tree's cost changes only in its interior nodes: the sum of their areas, which
//! is what the search minimises.
//!
//! The search for a subtree `N` (Bittner et al. §4.2) is branch and bound from the root: placing
//! `N` beside node `X` adds the area of their union (the new parent), and every ancestor of `X`
//! grows by the area `N` adds to it. Nodes are expanded in order of the area their ancestors
//! already add, and a node whose ancestors alone add more than the best place found (plus the
//! least any new parent can add, the area of `N`) is not expanded.
//!
//! The split tree grows in parallel like the build; the moves run on one thread, in an order
//! fixed by the tree, so the optimised tree does not depend on the number of threads.

use super::{Bounds, Ctx, PAR_SUBTREE_MIN, Plan, Planned, PrimRef, Scratch, Set, split};
use crate::MAX_DEPTH;
use rt_core::par;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// No node: a leaf's children, the root's parent.
const NONE: u32 = u32::MAX;

/// A node of the split tree: an interior node with two children, or a leaf holding a range of
/// the references.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Bounds,
    parent: u32,
    /// `[NONE, NONE]` for a leaf.
    kids: [u32; 2],
    /// A leaf's references: `refs[range.0..range.1]`.
    range: (u32, u32),
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.kids[0] == NONE
    }
}

/// The split tree, its root, and the candidates' search queue (reused from move to move).
struct Tree {
    nodes: Vec<Node>,
    root: u32,
    queue: BinaryHeap<Reverse<(u32, u32)>>,
}

/// The share of the tree's nodes, largest first, that each pass tries to move.
const BATCH: f64 = 0.1;

/// Passes stop early once one lowers the interior area by less than this share.
const MIN_GAIN: f64 = 1e-3;

/// Builds the full split tree of `root` (planned), optimises it with up to `passes` passes, and
/// returns it as a planned set whose splits are all made, over `refs` reordered to match. The
/// tree is the unoptimised one if the moves would have made a leaf as deep as [`MAX_DEPTH`].
pub(super) fn optimized(
    ctx: &Ctx<'_>,
    refs: &mut Vec<PrimRef>,
    root: Set,
    passes: u32,
    scratch: &mut Scratch,
) -> Planned {
    let mut tree = Tree {
        nodes: Vec::with_capacity(2 * refs.len().div_ceil(ctx.block.max(1))),
        root: 0,
        queue: BinaryHeap::new(),
    };
    grow(ctx, refs, 0, root, NONE, &mut tree.nodes, scratch);
    let before = tree.nodes.clone();
    tree.optimize(passes);
    // The build keeps every depth below MAX_DEPTH (see `plan`), and so must the moves.
    if tree.depth() >= MAX_DEPTH {
        tree.nodes = before;
        tree.root = 0;
    }
    let mut ordered = Vec::with_capacity(refs.len());
    let planned = tree.planned(tree.root, refs, &mut ordered, 0);
    *refs = ordered;
    planned
}

/// Appends the split tree of `set` to `nodes`, its root's parent being `parent`; returns the
/// root's index. `refs` holds the references from absolute index `base` on.
///
/// Nodes are appended depth first, a node's left subtree before its right one. Large halves
/// grow on rayon's threads into arrays of their own, appended in that same order, so the
/// indices (and with them the optimisation's order) do not depend on threading.
fn grow(
    ctx: &Ctx<'_>,
    refs: &mut [PrimRef],
    base: usize,
    set: Set,
    parent: u32,
    nodes: &mut Vec<Node>,
    scratch: &mut Scratch,
) -> u32 {
    let index = nodes.len() as u32;
    nodes.push(Node {
        bounds: set.bounds,
        parent,
        kids: [NONE; 2],
        range: (set.start as u32, set.end as u32),
    });
    if set.plan == Plan::Leaf {
        return index;
    }
    let (left, right) = split(ctx, refs, base, &set, scratch);
    if ctx.parallel && left.len().min(right.len()) >= PAR_SUBTREE_MIN {
        let (lo, hi) = refs[set.start - base..set.end - base].split_at_mut(right.start - set.start);
        let alone = |refs: &mut [PrimRef], base: usize, s: Set| {
            let mut own = Vec::new();
            grow(ctx, refs, base, s, NONE, &mut own, &mut Scratch::new());
            own
        };
        let (l, r) = par::join(
            || alone(lo, set.start, left),
            || alone(hi, right.start, right),
        );
        let kids = [l, r].map(|part| {
            let shift = nodes.len() as u32;
            nodes.extend(part.into_iter().map(|mut n| {
                n.parent = if n.parent == NONE {
                    index
                } else {
                    n.parent + shift
                };
                if !n.is_leaf() {
                    n.kids = n.kids.map(|k| k + shift);
                }
                n
            }));
            shift
        });
        nodes[index as usize].kids = kids;
    } else {
        let l = grow(ctx, refs, base, left, index, nodes, scratch);
        let r = grow(ctx, refs, base, right, index, nodes, scratch);
        nodes[index as usize].kids = [l, r];
    }
    index
}

/// Half areas compare as their bits: they are never negative.
fn key(area: f32) -> u32 {
    area.to_bits()
}

impl Tree {
    fn area(&self, i: u32) -> f32 {
        self.nodes[i as usize].bounds.half_area()
    }

    /// The sum of the interior nodes' half areas: the part of the SAH cost moves change.
    fn interior_area(&self) -> f64 {
        self.nodes
            .iter()
            .filter(|n| !n.is_leaf())
            .map(|n| f64::from(n.bounds.half_area()))
            .sum()
    }

    fn depth(&self) -> usize {
        let mut deepest = 0;
        let mut stack = vec![(self.root, 0usize)];
        while let Some((i, d)) = stack.pop() {
            deepest = deepest.max(d);
            let n = &self.nodes[i as usize];
            if !n.is_leaf() {
                stack.extend(n.kids.map(|k| (k, d + 1)));
            }
        }
        deepest
    }

    fn optimize(&mut self, passes: u32) {
        let mut cost = self.interior_area();
        let mut order: Vec<u32> = Vec::new();
        for _ in 0..passes {
            // The nodes rays enter most often first; equal areas by index, for a fixed order.
            order.clear();
            order.extend(0..self.nodes.len() as u32);
            order.sort_unstable_by_key(|&i| (Reverse(key(self.area(i))), i));
            order.truncate(((self.nodes.len() as f64 * BATCH).ceil() as usize).max(1));
            for &n in &order {
                self.reinsert(n);
            }
            let now = self.interior_area();
            let gain = cost - now;
            cost = now;
            // Valid primitives have finite boxes, so the areas are finite.
            if gain <= MIN_GAIN * cost {
                break;
            }
        }
    }

    /// Replaces child `old` of `parent` by `new`.
    fn replace_child(&mut self, parent: u32, old: u32, new: u32) {
        let kids = &mut self.nodes[parent as usize].kids;
        let slot = usize::from(kids[1] == old);
        kids[slot] = new;
    }

    /// Recomputes the boxes from `i` up to the root, stopping where a box does not change;
    /// returns how much the half areas shrank.
    fn refit_up(&mut self, mut i: u32) -> f32 {
        let mut shrunk = 0.0;
        while i != NONE {
            let n = self.nodes[i as usize];
            let [a, b] = n.kids;
            let bounds = self.nodes[a as usize]
                .bounds
                .union(self.nodes[b as usize].bounds);
            if bounds == n.bounds {
                break;
            }
            shrunk += n.bounds.half_area() - bounds.half_area();
            self.nodes[i as usize].bounds = bounds;
            i = n.parent;
        }
        shrunk
    }

    /// Removes the subtree `n` and inserts it again where that adds the least area, if that is
    /// less than its removal saved; else puts it back.
    fn reinsert(&mut self, n: u32) {
        let p = self.nodes[n as usize].parent;
        if p == NONE {
            return;
        }
        let g = self.nodes[p as usize].parent;
        if g == NONE {
            return;
        }
        // Detach: the sibling takes the parent's place, and the parent's node is free.
        let [a, b] = self.nodes[p as usize].kids;
        let sibling = if a == n { b } else { a };
        self.replace_child(g, p, sibling);
        self.nodes[sibling as usize].parent = g;
        let saved = self.area(p) + self.refit_up(g);
        // Branch and bound over the places beside which `n` could go.
        let nb = self.nodes[n as usize].bounds;
        let least = nb.half_area();
        let mut best = (f32::INFINITY, sibling);
        self.queue.clear();
        self.queue.push(Reverse((key(0.0), self.root)));
        while let Some(Reverse((induced, x))) = self.queue.pop() {
            let induced = f32::from_bits(induced);
            if induced + least >= best.0 {
                break;
            }
            let node = self.nodes[x as usize];
            let direct = node.bounds.union(nb).half_area();
            let total = induced + direct;
            if total < best.0 {
                best = (total, x);
            }
            if !node.is_leaf() {
                let below = total - node.bounds.half_area();
                if below + least < best.0 {
                    for k in node.kids {
                        self.queue.push(Reverse((key(below), k)));
                    }
                }
            }
        }
        let x = if best.0 < saved { best.1 } else { sibling };
        // Insert: the freed node becomes the parent of `x` and `n`, in `x`'s place.
        let q = self.nodes[x as usize].parent;
        self.nodes[p as usize].kids = [x, n];
        self.nodes[p as usize].parent = q;
        self.nodes[x as usize].parent = p;
        self.nodes[n as usize].parent = p;
        if q == NONE {
            self.root = p;
        } else {
            self.replace_child(q, x, p);
        }
        // The new parent's box is computed, then its ancestors grow.
        let [a, b] = self.nodes[p as usize].kids;
        self.nodes[p as usize].bounds = self.nodes[a as usize]
            .bounds
            .union(self.nodes[b as usize].bounds);
        if q != NONE {
            self.refit_up(q);
        }
    }

    /// The planned set of node `i` at `depth`, its leaves' references appended to `ordered`.
    fn planned(
        &self,
        i: u32,
        refs: &[PrimRef],
        ordered: &mut Vec<PrimRef>,
        depth: usize,
    ) -> Planned {
        let n = &self.nodes[i as usize];
        if n.is_leaf() {
            let start = ordered.len();
            ordered.extend_from_slice(&refs[n.range.0 as usize..n.range.1 as usize]);
            return Planned::new(Set {
                start,
                end: ordered.len(),
                bounds: n.bounds,
                cbounds: n.bounds,
                depth,
                plan: Plan::Leaf,
                unique: true,
            });
        }
        // The children in the order a split gives them: along the axis on which their centres
        // lie farthest apart, the lower one first. A move leaves them in any order, and the
        // any-hit walk visits children in lane order.
        let centre = |k: u32| {
            let b = self.nodes[k as usize].bounds;
            b.min + b.max
        };
        let [a, b] = n.kids;
        let gap = centre(b) - centre(a);
        let axis = gap.abs().max_position();
        let (first, second) = if gap[axis] < 0.0 { (b, a) } else { (a, b) };
        let l = self.planned(first, refs, ordered, depth + 1);
        let r = self.planned(second, refs, ordered, depth + 1);
        Planned {
            set: Set {
                start: l.set.start,
                end: r.set.end,
                bounds: n.bounds,
                cbounds: n.bounds,
                depth,
                // Any plan but a leaf: the splits are made, in `below`.
                plan: Plan::Count,
                unique: true,
            },
            below: Some(Box::new([l, r])),
        }
    }
}

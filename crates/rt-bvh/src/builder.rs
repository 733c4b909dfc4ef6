//! Top-down construction, emitted directly into depth-first order.

use crate::{BvhParams, MAX_DEPTH, Node, SplitMethod};
use rt_core::{Aabb, Primitive, glam::Vec3};

/// What the builder needs of each primitive, computed once.
#[derive(Clone, Copy)]
struct BuildRef {
    bounds: Aabb,
    centroid: Vec3,
    id: u32,
}

/// A subtree still to be built: the reference range, its depth, and the parent whose second
/// child index must be patched when this subtree is emitted.
struct Task {
    start: usize,
    end: usize,
    depth: usize,
    patch_parent: Option<usize>,
}

/// The output of a build.
pub(crate) struct Built<P> {
    pub nodes: Vec<Node>,
    pub prims: Vec<P>,
    pub ids: Vec<u32>,
    pub max_depth: usize,
    pub leaves: usize,
}

/// Builds the tree with an explicit task stack (no recursion, so degenerate input cannot
/// overflow the call stack). Each node costs O(n) for its bounds and split, and the depth is
/// bounded by [`MAX_DEPTH`], so the build is O(N log N) for balanced splits and O(N · MAX_DEPTH)
/// at worst.
pub(crate) fn build<P: Primitive>(prims: &[P], params: &BvhParams) -> Built<P> {
    let mut refs: Vec<BuildRef> = prims
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_valid())
        .map(|(i, p)| BuildRef {
            bounds: p.bounds(),
            centroid: p.centroid(),
            id: i as u32,
        })
        .collect();
    let max_leaf = params.max_leaf_size.clamp(1, 255) as usize;
    let bins = params.bins.clamp(2, 32) as usize;

    let mut nodes: Vec<Node> = Vec::with_capacity(2 * refs.len().div_ceil(max_leaf.min(2)));
    let mut leaves = 0;
    let mut max_depth = 0;
    let mut tasks = vec![Task {
        start: 0,
        end: refs.len(),
        depth: 0,
        patch_parent: None,
    }];
    while let Some(Task {
        start,
        end,
        depth,
        patch_parent,
    }) = tasks.pop()
    {
        let index = nodes.len();
        if let Some(parent) = patch_parent {
            nodes[parent].index = index as u32;
        }
        max_depth = max_depth.max(depth);
        let range = &mut refs[start..end];
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for r in range.iter() {
            bounds = bounds.union(r.bounds);
            cbounds = cbounds.grow(r.centroid);
        }
        let n = range.len();
        // Once the remaining depth budget only just fits a balanced split, split by count: that
        // keeps every tree within MAX_DEPTH, the size of the traversal stack.
        let forced = depth + ceil_log2(n.div_ceil(max_leaf)) + 1 >= MAX_DEPTH;
        let split = if n <= 1 {
            None
        } else if forced {
            (n > max_leaf).then(|| split_by_count(range, &cbounds))
        } else {
            match params.split {
                SplitMethod::Sah => split_sah(range, &bounds, &cbounds, bins, params, max_leaf),
                SplitMethod::Median => (n > max_leaf).then(|| split_by_count(range, &cbounds)),
                SplitMethod::Middle => (n > max_leaf).then(|| split_middle(range, &cbounds)),
            }
        };
        match split {
            Some((mid, axis)) => {
                nodes.push(Node {
                    bounds,
                    index: 0,
                    count: 0,
                    axis: axis as u8,
                    pad: 0,
                });
                // Second child first: the stack is LIFO, so the first child is emitted next and
                // lands at `index + 1`.
                tasks.push(Task {
                    start: start + mid,
                    end,
                    depth: depth + 1,
                    patch_parent: Some(index),
                });
                tasks.push(Task {
                    start,
                    end: start + mid,
                    depth: depth + 1,
                    patch_parent: None,
                });
            }
            None => {
                leaves += 1;
                nodes.push(Node {
                    bounds,
                    index: start as u32,
                    count: n as u16,
                    axis: 0,
                    pad: 0,
                });
            }
        }
    }
    // An empty scene still gets one (empty, never hit) leaf so traversal needs no special case.
    if nodes.is_empty() || refs.is_empty() {
        nodes.clear();
        nodes.push(Node {
            bounds: Aabb::EMPTY,
            index: 0,
            count: 0,
            axis: 0,
            pad: 0,
        });
    }
    let prims_out = refs.iter().map(|r| prims[r.id as usize].clone()).collect();
    let ids = refs.iter().map(|r| r.id).collect();
    Built {
        nodes,
        prims: prims_out,
        ids,
        max_depth,
        leaves,
    }
}

fn ceil_log2(n: usize) -> usize {
    if n <= 1 {
        0
    } else {
        (usize::BITS - (n - 1).leading_zeros()) as usize
    }
}

/// Binned SAH (Wald 2007; pbrt-v4 §7.3): project centroids into `bins` buckets per axis,
/// evaluate the `bins - 1` planes between buckets with the cost
/// `C_trav + C_isect · (A_L·N_L + A_R·N_R) / A`, and keep the cheapest. Returns `None` for a
/// leaf: when no split beats the leaf cost `C_isect · N` and the node fits in a leaf. A node too
/// big for a leaf whose centroids all coincide is split by count.
fn split_sah(
    refs: &mut [BuildRef],
    bounds: &Aabb,
    cbounds: &Aabb,
    bins: usize,
    params: &BvhParams,
    max_leaf: usize,
) -> Option<(usize, usize)> {
    let n = refs.len();
    let extent = cbounds.extent();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, plane)
    for axis in 0..3 {
        if !(extent[axis] > 0.0) {
            continue;
        }
        let mut bin_bounds = [Aabb::EMPTY; 32];
        let mut bin_counts = [0u32; 32];
        let scale = bins as f32 / extent[axis];
        let lo = cbounds.min[axis];
        for r in refs.iter() {
            let b = bin_index(r.centroid[axis], lo, scale, bins);
            bin_counts[b] += 1;
            bin_bounds[b] = bin_bounds[b].union(r.bounds);
        }
        // Sweep from the right to get the area-weighted count right of each plane, then from
        // the left to evaluate each plane.
        let mut right_cost = [0.0f32; 32];
        let mut acc = Aabb::EMPTY;
        let mut count = 0u32;
        for b in (1..bins).rev() {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b];
            right_cost[b] = acc.half_area() * count as f32;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0u32;
        for plane in 1..bins {
            acc = acc.union(bin_bounds[plane - 1]);
            count += bin_counts[plane - 1];
            if count == 0 || count as usize == n {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_cost[plane];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, plane));
            }
        }
    }
    let Some((cost, axis, plane)) = best else {
        return (n > max_leaf).then(|| split_by_count(refs, cbounds));
    };
    let area = bounds.half_area();
    let split_cost = params.traversal_cost + params.intersection_cost * cost / area;
    let leaf_cost = params.intersection_cost * n as f32;
    if n <= max_leaf && !(split_cost < leaf_cost) {
        return None;
    }
    let scale = bins as f32 / extent[axis];
    let lo = cbounds.min[axis];
    let mid = partition(refs, |r| {
        bin_index(r.centroid[axis], lo, scale, bins) < plane
    });
    if mid == 0 || mid == n {
        // Unreachable by construction (the plane had primitives on both sides), but a count
        // split is always a safe answer.
        return Some(split_by_count(refs, cbounds));
    }
    Some((mid, axis))
}

#[inline(always)]
fn bin_index(c: f32, lo: f32, scale: f32, bins: usize) -> usize {
    (((c - lo) * scale) as usize).min(bins - 1)
}

/// Median split along the longest centroid axis by quickselect (`select_nth_unstable_by`,
/// O(n) expected): halves by count, so it always makes progress, even when centroids coincide.
fn split_by_count(refs: &mut [BuildRef], cbounds: &Aabb) -> (usize, usize) {
    let axis = cbounds.largest_axis();
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    (mid, axis)
}

/// Splits at the middle of the centroid extent along its longest axis (pbrt's `Middle`); falls
/// back to the median when every centroid lands on one side.
fn split_middle(refs: &mut [BuildRef], cbounds: &Aabb) -> (usize, usize) {
    let axis = cbounds.largest_axis();
    let middle = cbounds.center()[axis];
    let mid = partition(refs, |r| r.centroid[axis] < middle);
    if mid == 0 || mid == refs.len() {
        split_by_count(refs, cbounds)
    } else {
        (mid, axis)
    }
}

/// Moves the references satisfying `left` to the front; returns how many there are.
fn partition(refs: &mut [BuildRef], left: impl Fn(&BuildRef) -> bool) -> usize {
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        if left(&refs[i]) {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    i
}

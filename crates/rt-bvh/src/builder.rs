//! Top-down construction, emitted directly into depth-first order.

use crate::{BvhParams, MAX_DEPTH, Node, SplitMethod};
use rt_core::glam::{Vec3, Vec3A};
use rt_core::{Aabb, Primitive};

/// A box in SIMD registers for the build's inner loops.
#[derive(Clone, Copy)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Self = Self {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn union(self, o: Self) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline(always)]
    fn grow(self, p: Vec3A) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline(always)]
    fn half_area(self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    fn to_aabb(self) -> Aabb {
        Aabb::new(Vec3::from(self.min), Vec3::from(self.max))
    }
}

/// What the builder needs of each primitive, computed once.
#[derive(Clone, Copy)]
struct BuildRef {
    bounds: Bounds,
    centroid: Vec3A,
    id: u32,
}

/// A subtree still to be built: its reference range, its bounds and centroid bounds (computed
/// by the parent's split), its depth, and the parent whose second-child index must be patched
/// when the subtree is emitted.
struct Task {
    start: usize,
    end: usize,
    bounds: Bounds,
    cbounds: Bounds,
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
/// overflow the call stack). Each node costs O(n) for its split choice and partition, and the
/// depth is bounded by [`MAX_DEPTH`], so the build is O(N log N) for balanced splits and
/// O(N · MAX_DEPTH) at worst.
pub(crate) fn build<P: Primitive>(prims: &[P], params: &BvhParams) -> Built<P> {
    let mut refs: Vec<BuildRef> = prims
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_valid())
        .map(|(i, p)| {
            let b = p.bounds();
            BuildRef {
                bounds: Bounds {
                    min: b.min.into(),
                    max: b.max.into(),
                },
                centroid: p.centroid().into(),
                id: i as u32,
            }
        })
        .collect();
    let max_leaf = params.max_leaf_size.clamp(1, 255) as usize;
    let bins = params.bins.clamp(2, MAX_BINS as u32) as usize;

    if refs.is_empty() {
        // One empty, never-hit leaf, so traversal needs no special case for empty scenes.
        let empty = Node {
            bounds: Aabb::EMPTY,
            index: 0,
            count: 0,
            axis: 0,
            pad: 0,
        };
        return Built {
            nodes: vec![empty],
            prims: Vec::new(),
            ids: Vec::new(),
            max_depth: 0,
            leaves: 0,
        };
    }

    let (bounds, cbounds) = range_bounds(&refs);
    let mut nodes: Vec<Node> = Vec::with_capacity(2 * refs.len().div_ceil(2));
    let mut leaves = 0;
    let mut max_depth = 0;
    let mut scratch = Bins::new();
    let mut tasks = vec![Task {
        start: 0,
        end: refs.len(),
        bounds,
        cbounds,
        depth: 0,
        patch_parent: None,
    }];
    while let Some(Task {
        start,
        end,
        bounds,
        cbounds,
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
                SplitMethod::Sah => split_sah(
                    range,
                    &bounds,
                    &cbounds,
                    bins,
                    params,
                    max_leaf,
                    &mut scratch,
                ),
                SplitMethod::Median => (n > max_leaf).then(|| split_by_count(range, &cbounds)),
                SplitMethod::Middle => (n > max_leaf).then(|| split_middle(range, &cbounds)),
            }
        };
        match split {
            Some(Split {
                mid,
                axis,
                left,
                right,
            }) => {
                let (left, right) = match (left, right) {
                    (Some(l), Some(r)) => (l, r),
                    _ => (range_bounds(&range[..mid]), range_bounds(&range[mid..])),
                };
                nodes.push(Node {
                    bounds: bounds.to_aabb(),
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
                    bounds: right.0,
                    cbounds: right.1,
                    depth: depth + 1,
                    patch_parent: Some(index),
                });
                tasks.push(Task {
                    start,
                    end: start + mid,
                    bounds: left.0,
                    cbounds: left.1,
                    depth: depth + 1,
                    patch_parent: None,
                });
            }
            None => {
                leaves += 1;
                nodes.push(Node {
                    bounds: bounds.to_aabb(),
                    index: start as u32,
                    count: n as u16,
                    axis: 0,
                    pad: 0,
                });
            }
        }
    }
    // The node count is only known now; drop the spare capacity so the structure holds (and
    // `memory_bytes` reports) what it needs.
    nodes.shrink_to_fit();
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

const MAX_BINS: usize = 32;

/// SAH buckets per axis: their bounds and primitive counts.
struct Bins {
    bounds: [[Bounds; MAX_BINS]; 3],
    counts: [[u32; MAX_BINS]; 3],
}

impl Bins {
    fn new() -> Self {
        Self {
            bounds: [[Bounds::EMPTY; MAX_BINS]; 3],
            counts: [[0; MAX_BINS]; 3],
        }
    }
}

/// A chosen split: references `..mid` go left. The children's (bounds, centroid bounds) when
/// the split already computed them.
struct Split {
    mid: usize,
    axis: usize,
    left: Option<(Bounds, Bounds)>,
    right: Option<(Bounds, Bounds)>,
}

fn range_bounds(refs: &[BuildRef]) -> (Bounds, Bounds) {
    refs.iter()
        .fold((Bounds::EMPTY, Bounds::EMPTY), |(b, c), r| {
            (b.union(r.bounds), c.grow(r.centroid))
        })
}

fn ceil_log2(n: usize) -> usize {
    if n <= 1 {
        0
    } else {
        (usize::BITS - (n - 1).leading_zeros()) as usize
    }
}

/// Binned SAH (Wald 2007; pbrt-v4 §7.3): project centroids into `bins` buckets on all three
/// axes in one pass, evaluate the `bins - 1` planes between buckets per axis with the cost
/// `C_trav + C_isect · (A_L·N_L + A_R·N_R) / A`, and keep the cheapest. Returns `None` for a
/// leaf: when no split beats the leaf cost `C_isect · N` and the node fits in a leaf. A node too
/// big for a leaf whose centroids all coincide is split by count.
fn split_sah(
    refs: &mut [BuildRef],
    bounds: &Bounds,
    cbounds: &Bounds,
    bins: usize,
    params: &BvhParams,
    max_leaf: usize,
    scratch: &mut Bins,
) -> Option<Split> {
    let n = refs.len();
    // PERF: a node of n primitives gets min(bins, max(n, 4)) buckets; a small node needs no more
    // planes than it has primitives, and initializing and sweeping 3 × 16 buckets dominated the
    // cost of the ~38k small nodes of the bunny: SAH build 51.6 ms -> 40.1 ms with the same
    // tree quality (6.8 visits, 0.8 tests per primary ray), measured with `cargo xtask compare
    // --scene ../shared/meshes/stanford-bunny.obj --structures bvh`.
    let bins = bins.min(n.max(4));
    let extent = cbounds.max - cbounds.min;
    let bins_f = bins as f32;
    // A zero extent gives scale 0: every centroid lands in bucket 0 and no plane is evaluated.
    let scale = Vec3A::select(
        extent.cmpgt(Vec3A::ZERO),
        Vec3A::splat(bins_f) / extent,
        Vec3A::ZERO,
    );
    let lo = cbounds.min;
    let max_bin = Vec3A::splat(bins_f - 1.0);
    let bin_of = |c: Vec3A| ((c - lo) * scale).min(max_bin).max(Vec3A::ZERO);

    // PERF: the buckets live in one scratch array for the whole build and only the `bins` in use
    // are reset, instead of a fresh 3 × 32-bucket array (3 KB) per node: bunny SAH build 36.3 ->
    // 35.4 ms (`cargo bench -p rt-benches --bench trace -- build/bunny/rt-bvh/sah`).
    let Bins {
        bounds: bin_bounds,
        counts: bin_counts,
    } = scratch;
    for axis in 0..3 {
        bin_bounds[axis][..bins].fill(Bounds::EMPTY);
        bin_counts[axis][..bins].fill(0);
    }
    for r in refs.iter() {
        let b = bin_of(r.centroid);
        for axis in 0..3 {
            let k = b[axis] as usize;
            bin_counts[axis][k] += 1;
            bin_bounds[axis][k] = bin_bounds[axis][k].union(r.bounds);
        }
    }
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, plane)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let (bb, bc) = (&bin_bounds[axis], &bin_counts[axis]);
        // Sweep from the right for the area-weighted count right of each plane, then from the
        // left to evaluate each plane.
        let mut right_cost = [0.0f32; MAX_BINS];
        let mut acc = Bounds::EMPTY;
        let mut count = 0u32;
        for b in (1..bins).rev() {
            acc = acc.union(bb[b]);
            count += bc[b];
            right_cost[b] = acc.half_area() * count as f32;
        }
        let mut acc = Bounds::EMPTY;
        let mut count = 0u32;
        for plane in 1..bins {
            acc = acc.union(bb[plane - 1]);
            count += bc[plane - 1];
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
    let split_cost = params.traversal_cost + params.intersection_cost * cost / bounds.half_area();
    let leaf_cost = params.intersection_cost * n as f32;
    // A NaN cost (a zero-area node) does not pay either.
    let split_pays = split_cost < leaf_cost;
    if n <= max_leaf && !split_pays {
        return None;
    }
    // Partition, accumulating both children's bounds on the way so they need no extra pass.
    let mut left = (Bounds::EMPTY, Bounds::EMPTY);
    let mut right = (Bounds::EMPTY, Bounds::EMPTY);
    let (mut i, mut j) = (0, n);
    while i < j {
        let r = refs[i];
        if (bin_of(r.centroid)[axis] as usize) < plane {
            left = (left.0.union(r.bounds), left.1.grow(r.centroid));
            i += 1;
        } else {
            right = (right.0.union(r.bounds), right.1.grow(r.centroid));
            j -= 1;
            refs.swap(i, j);
        }
    }
    if i == 0 || i == n {
        // Unreachable by construction (the plane had primitives on both sides), but a count
        // split is always a safe answer.
        return Some(split_by_count(refs, cbounds));
    }
    Some(Split {
        mid: i,
        axis,
        left: Some(left),
        right: Some(right),
    })
}

/// Median split along the longest centroid axis by quickselect (`select_nth_unstable_by`,
/// O(n) expected): halves by count, so it always makes progress, even when centroids coincide.
fn split_by_count(refs: &mut [BuildRef], cbounds: &Bounds) -> Split {
    let axis = longest_axis(cbounds);
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    Split {
        mid,
        axis,
        left: None,
        right: None,
    }
}

/// Splits at the middle of the centroid extent along its longest axis (pbrt's `Middle`); falls
/// back to the median when every centroid lands on one side.
fn split_middle(refs: &mut [BuildRef], cbounds: &Bounds) -> Split {
    let axis = longest_axis(cbounds);
    let middle = 0.5 * (cbounds.min[axis] + cbounds.max[axis]);
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        if refs[i].centroid[axis] < middle {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    if i == 0 || i == refs.len() {
        split_by_count(refs, cbounds)
    } else {
        Split {
            mid: i,
            axis,
            left: None,
            right: None,
        }
    }
}

fn longest_axis(b: &Bounds) -> usize {
    b.to_aabb().largest_axis()
}

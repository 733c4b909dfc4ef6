//! Step 6: the surface area heuristic.
//!
//! The median split halves the triangle count whatever the geometry: on a teapot in a stadium
//! it cuts the teapot in two and leaves the stadium's big triangles in boxes that span it. The
//! SAH (Goldsmith & Salmon 1987, MacDonald & Booth 1990) asks instead what a split will cost a
//! ray. A ray that meets a node's box `B` meets a child's box `C` inside it with probability
//! about `area(C) / area(B)`, so splitting `N` triangles into `N_L` and `N_R` costs
//!
//! `C_TRAV + C_ISECT × (area(L) × N_L + area(R) × N_R) / area(B)`
//!
//! against `C_ISECT × N` for a leaf. Choose the cheapest split, and make a leaf where that is
//! cheaper still. Trying every triangle as a plane is `O(N²)` per node; binning (Wald 2007)
//! drops the centroids into [`BINS`] equal slices of the centroid box per axis, keeps a count
//! and a box per bin, and tries only the [`BINS`]` - 1` planes between bins: two sweeps, one
//! from each end, give every plane's left and right boxes and counts.

use rt_core::{Aabb, Primitive, Triangle};

/// Bins per axis.
pub const BINS: usize = 16;
/// The cost of visiting a node, relative to testing a triangle.
pub const C_TRAV: f32 = 1.0;
/// The cost of testing a triangle.
pub const C_ISECT: f32 = 1.0;

/// The SAH split of a node's triangles `ids`, whose box is `bounds` and centroids' box
/// `centroids`: tries the planes between [`BINS`] bins on each axis, and reorders `ids` so that
/// the triangles left of the cheapest plane come first, returning how many they are. Returns
/// `None` (and leaves `ids` as they were, in any order) when no plane has triangles on both
/// sides (all centroids in one bin), or when `ids.len() <= leaf_size` and a leaf costs no more
/// than the cheapest split.
pub fn sah_split(
    tris: &[Triangle],
    ids: &mut [u32],
    bounds: &Aabb,
    centroids: &Aabb,
    leaf_size: usize,
) -> Option<usize> {
    // BEGIN SOLUTION step 6: the binned SAH split
    let bin = |id: u32, axis: usize| {
        let lo = centroids.min[axis];
        let scale = BINS as f32 / (centroids.max[axis] - lo);
        let b = ((crate::centroid(&tris[id as usize])[axis] - lo) * scale) as usize;
        b.min(BINS - 1)
    };
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if centroids.max[axis] <= centroids.min[axis] {
            continue;
        }
        let mut boxes = [Aabb::EMPTY; BINS];
        let mut counts = [0usize; BINS];
        for &id in ids.iter() {
            let b = bin(id, axis);
            boxes[b] = boxes[b].union(tris[id as usize].bounds());
            counts[b] += 1;
        }
        // Right of plane k (between bins k - 1 and k): bins k.. .
        let mut right = [(0.0f32, 0usize); BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for k in (1..BINS).rev() {
            acc = acc.union(boxes[k]);
            count += counts[k];
            right[k] = (acc.half_area(), count);
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for k in 1..BINS {
            acc = acc.union(boxes[k - 1]);
            count += counts[k - 1];
            let (right_area, right_count) = right[k];
            if count == 0 || right_count == 0 {
                continue;
            }
            let cost = C_TRAV
                + C_ISECT * (acc.half_area() * count as f32 + right_area * right_count as f32)
                    / area;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, k));
            }
        }
    }
    let (cost, axis, k) = best?;
    if ids.len() <= leaf_size && cost >= C_ISECT * ids.len() as f32 {
        return None;
    }
    // Partition in place: the triangles left of the plane to the front.
    let mut mid = 0;
    for i in 0..ids.len() {
        if bin(ids[i], axis) < k {
            ids.swap(i, mid);
            mid += 1;
        }
    }
    Some(mid)
    // END SOLUTION
}

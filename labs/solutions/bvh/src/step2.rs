//! Step 2: the build, with a median split.
//!
//! Build top down: take a node's triangles, find their boxes (step 1), and either make a leaf
//! or split them in two and build each half the same way. The median split (Kay & Kajiya 1986)
//! sorts the triangles by their centroid along the axis where the centroids spread widest and
//! gives half to each child: a balanced tree, `O(N log N)` to build, but blind to where the
//! triangles are (step 6 fixes that).
//!
//! The tree goes straight into one array, depth first, as pbrt flattens its BVH: push the node,
//! build its first child right behind it, then its second child, and record where the second
//! child starts in the node's `first`. A leaf's triangles are a range of [`LabBvh::ids`]: the
//! builder only reorders `ids`, so each node's triangles are already a contiguous slice.

use crate::{BvhParams, LabBvh, Node, step1};
use rt_core::{Aabb, Primitive, Triangle};

/// Builds the BVH over the valid triangles of `tris` ([`Primitive::is_valid`]: invalid ones,
/// with a NaN vertex or no area, are in no leaf and never hit).
pub fn build(tris: &[Triangle], params: &BvhParams) -> LabBvh {
    let mut ids: Vec<u32> = (0..tris.len() as u32)
        .filter(|&i| tris[i as usize].is_valid())
        .collect();
    let mut nodes = Vec::with_capacity(2 * ids.len().div_ceil(params.leaf_size.max(1)));
    if !ids.is_empty() {
        subtree(tris, params, &mut ids, 0, 0, &mut nodes);
    }
    LabBvh {
        nodes,
        ids,
        tris: tris.to_vec(),
        params: params.clone(),
    }
}

/// Appends to `nodes` the subtree over the triangles `ids` (which start at position `offset`
/// in the finished `LabBvh::ids`), its root at depth `depth`. Ask [`crate::split`] where to
/// split: it calls your [`median_split`] (or step 6's SAH), and returns `None` for a leaf.
pub fn subtree(
    tris: &[Triangle],
    params: &BvhParams,
    ids: &mut [u32],
    offset: usize,
    depth: usize,
    nodes: &mut Vec<Node>,
) {
    // BEGIN SOLUTION step 2: one node, then its children depth first
    let (bounds, centroids) = step1::bounds(tris, ids);
    let index = nodes.len();
    match crate::split(tris, params, ids, &bounds, &centroids, depth) {
        None => nodes.push(Node {
            bounds,
            first: offset as u32,
            count: ids.len() as u32,
        }),
        Some(mid) => {
            nodes.push(Node {
                bounds,
                first: 0,
                count: 0,
            });
            let (left, right) = ids.split_at_mut(mid);
            subtree(tris, params, left, offset, depth + 1, nodes);
            nodes[index].first = nodes.len() as u32;
            subtree(tris, params, right, offset + mid, depth + 1, nodes);
        }
    }
    // END SOLUTION
}

/// The median split: reorders `ids` so that the first half has the smaller centroids along
/// the widest axis of `centroids` (the box around them), and returns the size of that half
/// (`ids.len() / 2`). A full sort works; `select_nth_unstable_by` does it in linear time.
pub fn median_split(tris: &[Triangle], ids: &mut [u32], centroids: &Aabb) -> usize {
    // BEGIN SOLUTION step 2: the median split
    let axis = centroids.largest_axis();
    let mid = ids.len() / 2;
    ids.select_nth_unstable_by(mid, |&a, &b| {
        let ca = crate::centroid(&tris[a as usize])[axis];
        let cb = crate::centroid(&tris[b as usize])[axis];
        ca.total_cmp(&cb)
    });
    mid
    // END SOLUTION
}

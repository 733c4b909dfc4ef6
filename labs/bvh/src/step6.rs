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
    todo!("step 6: the binned SAH split")
}

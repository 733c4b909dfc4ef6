//! Coherent bundles take each tree's bundle walk (closest and any hit) rather than all falling
//! back to single rays, and answer as the single rays do, bit for bit: the wide tree's and the
//! binary tree's.

use rt_bvh::{Bvh, BvhParams};
use rt_core::Triangle;

#[test]
fn the_wide_trees_coherent_bundles_walk_together() {
    rt_conformance::check_coherent_bundles::<Bvh<Triangle>>(&BvhParams::wide(), true);
}

#[test]
fn the_binary_trees_coherent_bundles_walk_together() {
    rt_conformance::check_coherent_bundles::<Bvh<Triangle>>(&BvhParams::sah(), true);
}

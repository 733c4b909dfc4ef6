//! Coherent bundles take the packet walk (closest and any hits)
//! rather than all falling back to single rays, and answer as the single rays do, bit for bit.

use rt_core::Triangle;
use rt_octree::{Octree, OctreeParams};

#[test]
fn coherent_bundles_walk_together_and_answer_as_single_rays() {
    rt_conformance::check_coherent_bundles::<Octree<Triangle>>(&OctreeParams::default(), true);
}

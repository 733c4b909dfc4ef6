//! Coherent bundles take the packet walk (closest and any hit) rather than all falling back to
//! single rays, and answer as the single rays do, bit for bit, with either single-ray traversal
//! beside them.

use rt_core::Triangle;
use rt_kdtree::{KdParams, KdTree};

#[test]
fn coherent_bundles_walk_together_and_answer_as_single_rays() {
    rt_conformance::check_coherent_bundles::<KdTree<Triangle>>(&KdParams::sah(), true);
}

#[test]
fn bundles_answer_as_the_restart_traversal_does() {
    rt_conformance::check_coherent_bundles::<KdTree<Triangle>>(&KdParams::restart(), true);
}

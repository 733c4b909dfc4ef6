//! Coherent bundles take the level-by-level slice walk (and do not all fall back to single
//! rays), and answer as the single rays do, bit for bit.

use rt_core::Triangle;
use rt_hgrid::{HGrid, HGridParams};

#[test]
fn coherent_bundles_walk_together_and_answer_as_single_rays() {
    rt_conformance::check_coherent_bundles::<HGrid<Triangle>>(&HGridParams::default(), true);
}

//! Saved and loaded trees answer as built; damaged files are refused or answer safely.

use rt_bvh::Bvh;
use rt_core::Triangle;

/// Every preset on every adversarial scene: loaded answers bit for bit as built, and no
/// truncated or hostile file panics.
#[test]
fn saved_structures_answer_as_built() {
    rt_conformance::check_saved_scenes::<Bvh<Triangle>>();
}

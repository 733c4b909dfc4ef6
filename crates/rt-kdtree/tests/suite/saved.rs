//! Saved and loaded trees answer as built; damaged files are refused or answer safely.

use rt_core::Triangle;
use rt_kdtree::KdTree;

/// Every preset on every adversarial scene: loaded answers bit for bit as built, and no
/// truncated or hostile file panics.
#[test]
fn saved_structures_answer_as_built() {
    rt_conformance::check_saved_scenes::<KdTree<Triangle>>();
}

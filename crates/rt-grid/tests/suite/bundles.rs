//! Coherent bundles take the slice-by-slice walk (and do not all fall back to single rays),
//! and answer as the single rays do, bit for bit.

use rt_conformance::same_bits;
use rt_core::{Accel, Ray, Triangle};
use rt_grid::{Grid, GridParams};

#[test]
fn coherent_bundles_walk_together_and_answer_as_single_rays() {
    rt_conformance::check_coherent_bundles::<Grid<Triangle>>(&GridParams::standard(), true);
}

/// A ray that grazes the grid's corner at its closest hit, found by proptest: its computed entry
/// into the box (`t = 1`) lies just after the hit (`t = 0.9999999`), so the bundle must start
/// one slice before the lane's first cell.
#[test]
fn a_lane_whose_hit_lies_just_before_its_entry_finds_it() {
    use rt_core::glam::Vec3;
    let tris = [Triangle::new(
        Vec3::new(0.0, 0.0, -0.5),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(-2.5, -0.5, -0.5),
    )];
    let grid = Grid::build(&tris, &GridParams::bbox_insertion());
    let r = Ray::new(
        Vec3::new(3.574154, 1.0, 1.0),
        Vec3::new(-6.074154, -1.5, -1.5),
    );
    let mut out = [None; 2];
    grid.intersect_bundle(&[r, r], &mut out);
    let single = grid.intersect(&r);
    assert!(single.is_some());
    assert!(
        out.iter().all(|&h| same_bits(h, single)),
        "{out:?} against {single:?}"
    );
}

//! Two-level scenes under `Instances`: every structure as the bottom level, one kind at a time
//! and all kinds mixed in one scene, checked by the conformance kit against the linear reference
//! and the flattened world-space triangles.

use rt_bvh::{Bvh, BvhParams, Instances};
use rt_conformance::{
    BottomBuilder, TWO_LEVEL_SCENES, check_two_level_random, check_two_level_scene,
};
use rt_core::{Accel, BruteForce, DynAccel, Triangle};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use std::sync::Arc;

type Scene = Instances<Triangle>;

fn wide(t: &[Triangle]) -> Arc<dyn DynAccel<Triangle>> {
    Arc::new(Bvh::build(t, &BvhParams::wide()))
}
fn binary(t: &[Triangle]) -> Arc<dyn DynAccel<Triangle>> {
    Arc::new(Bvh::build(t, &BvhParams::sah()))
}
fn kdtree(t: &[Triangle]) -> Arc<dyn DynAccel<Triangle>> {
    Arc::new(KdTree::build(t, &Default::default()))
}
fn grid(t: &[Triangle]) -> Arc<dyn DynAccel<Triangle>> {
    Arc::new(Grid::build(t, &Default::default()))
}
fn hgrid(t: &[Triangle]) -> Arc<dyn DynAccel<Triangle>> {
    Arc::new(HGrid::build(t, &Default::default()))
}
fn octree(t: &[Triangle]) -> Arc<dyn DynAccel<Triangle>> {
    Arc::new(Octree::build(t, &Default::default()))
}
fn brute(t: &[Triangle]) -> Arc<dyn DynAccel<Triangle>> {
    Arc::new(BruteForce::build(t, &()))
}

const MIXED: &[BottomBuilder] = &[wide, kdtree, grid, hgrid, octree, binary, brute];

macro_rules! two_level_tests {
    ($($name:ident: $bottoms:expr),* $(,)?) => {$(
        mod $name {
            use super::*;
            #[test]
            fn fixed_scenes() {
                for scene in TWO_LEVEL_SCENES {
                    check_two_level_scene::<Scene>($bottoms, scene);
                }
            }
            #[test]
            fn random_scenes() {
                check_two_level_random::<Scene>($bottoms);
            }
        }
    )*};
}

two_level_tests!(
    over_wide_bvh: &[wide],
    over_binary_bvh: &[binary],
    over_kdtree: &[kdtree],
    over_grid: &[grid],
    over_hgrid: &[hgrid],
    over_octree: &[octree],
    over_brute_force: &[brute],
    mixed: MIXED,
);

//! Coherent bundles take the slice-by-slice walk (and do not all fall back to single rays),
//! and answer as the single rays do, bit for bit, on a scene with thousands of triangles.

use rt_conformance::same_bits;
use rt_core::{Accel, Counters, Hit, Ray, Triangle};
use rt_grid::{Grid, GridParams};
use rt_scene::Camera;

/// Primary rays in 8×8 tiles over a built-in scene, and their shadow rays towards a point light.
fn scene_rays(name: &str) -> (Vec<Triangle>, Vec<Ray>, Vec<Ray>) {
    let mesh = rt_scene::scenes::builtin(name).expect("built-in scene");
    let tris = mesh.triangles();
    let bounds = rt_core::valid_bounds(&tris);
    let camera = Camera::framing(&bounds, 256, 192);
    let (primary, _) = camera.tiled_rays(256, 192, (8, 8));
    let grid = Grid::build(&tris, &GridParams::standard());
    let light = bounds.max + bounds.extent();
    let shadow = primary
        .iter()
        .filter_map(|r| {
            let h = grid.intersect(r)?;
            let p = r.at(h.t);
            let to = light - p;
            Some(Ray::with_interval(p, to, 1e-3, 1.0))
        })
        .collect();
    (tris, primary, shadow)
}

#[test]
fn coherent_bundles_walk_together_and_answer_as_single_rays() {
    for name in ["sphereflake", "teapot-in-stadium"] {
        let (tris, primary, shadow) = scene_rays(name);
        let grid = Grid::build(&tris, &GridParams::standard());
        let single: Vec<Option<Hit>> = primary.iter().map(|r| grid.intersect(r)).collect();
        let mut hits = vec![None; primary.len()];
        let mut c = Counters::default();
        grid.intersect_bundle_with(&primary, &mut hits, &mut c);
        for (i, (a, b)) in hits.iter().zip(&single).enumerate() {
            assert!(
                same_bits(*a, *b),
                "{name}: ray {i}: bundle {a:?}, single {b:?}"
            );
        }
        // Most rays travel in bundles: few finish alone.
        assert!(c.lane_slots > 0, "{name}: no bundle step at all: {c:?}");
        assert!(
            c.single_rays * 4 < primary.len() as u64,
            "{name}: {} of {} primary rays finished alone",
            c.single_rays,
            primary.len()
        );
        let blocked: Vec<bool> = shadow.iter().map(|r| grid.occluded(r)).collect();
        let mut got = vec![false; shadow.len()];
        let mut c = Counters::default();
        grid.occluded_bundle_with(&shadow, &mut got, &mut c);
        assert_eq!(got, blocked, "{name}: shadow rays");
        assert!(
            c.lane_slots > 0,
            "{name}: no shadow bundle step at all: {c:?}"
        );
    }
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

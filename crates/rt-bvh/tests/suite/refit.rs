//! Refitting: every preset follows moving triangles exactly like brute force (the refit kit),
//! keeps its invariants, refuses what it cannot follow, and reports its SAH drift.

use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, MtTriangle, Refit, RefitError, Triangle};
use rt_scene::motion::explode;

fn presets() -> Vec<(&'static str, BvhParams)> {
    let mut all = Bvh::<Triangle>::presets();
    all.push((
        "wide-sequential",
        BvhParams {
            parallel: false,
            ..BvhParams::wide()
        },
    ));
    all
}

#[test]
fn every_preset_passes_the_refit_kit_on_every_scene() {
    for (_, params) in presets() {
        rt_conformance::check_refit_scenes::<Bvh<Triangle>>(&params);
    }
}

#[test]
fn moller_trumbore_packs_are_refitted_as_a_fresh_build_packs_them() {
    let tris = rt_scene::scenes::builtin("sphereflake:20k")
        .expect("built-in scene")
        .triangles();
    let mt = |t: &[Triangle]| t.iter().map(|&t| MtTriangle(t)).collect::<Vec<_>>();
    let moved = explode(&tris, 0.02, 4);
    let mut bvh = Bvh::build(&mt(&tris), &BvhParams::wide());
    bvh.refit(&mt(&moved)).unwrap();
    let rays = rt_conformance::rays_into_cube(9, 2000);
    let reference = rt_core::BruteForce::build(&mt(&moved), &());
    rt_conformance::compare_rays(&bvh, &reference, &rays).unwrap();
    bvh.validate().unwrap();
}

#[test]
fn random_refits_agree_with_brute_force() {
    rt_conformance::check_refit_random::<Bvh<Triangle>>(&BvhParams::wide());
    rt_conformance::check_refit_random::<Bvh<Triangle>>(&BvhParams::sah());
}

#[test]
fn a_refitted_tree_validates_and_matches_a_fresh_build_of_the_same_shape() {
    let tris = rt_scene::scenes::builtin("sphereflake:20k")
        .expect("built-in scene")
        .triangles();
    for (name, params) in presets() {
        let mut bvh = Bvh::build(&tris, &params);
        let before = bvh.sah_cost();
        assert_eq!(before, bvh.built_sah_cost(), "{name}");
        let moved = explode(&tris, 0.02, 1);
        bvh.refit(&moved).unwrap();
        bvh.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            bvh.build_stats(),
            Bvh::build(&tris, &params).build_stats(),
            "{name}: a refit keeps the shape"
        );
        // Refitting back restores every box exactly, and so the cost.
        bvh.refit(&tris).unwrap();
        assert_eq!(bvh.sah_cost(), before, "{name}");
        // Bytes, not `==`: unused pack lanes hold NaN.
        let fresh = Bvh::build(&tris, &params);
        let bytes = |b: &Bvh<Triangle>| {
            let wide: &[u8] = rt_core::bytemuck::cast_slice(b.wide_nodes());
            let binary: &[u8] = rt_core::bytemuck::cast_slice(b.nodes());
            let packs: &[u8] = rt_core::bytemuck::cast_slice(b.packs());
            [wide.to_vec(), binary.to_vec(), packs.to_vec()]
        };
        assert!(
            bytes(&bvh) == bytes(&fresh),
            "{name}: refitted back, the tree is the fresh one"
        );
        assert_eq!(bvh.primitives(), fresh.primitives(), "{name}");
    }
}

#[test]
fn an_explosion_makes_the_refitted_tree_costlier_than_a_fresh_one() {
    let tris = rt_scene::scenes::builtin("teapot")
        .expect("built-in scene")
        .triangles();
    let mut bvh = Bvh::build(&tris, &BvhParams::wide());
    let moved = explode(&tris, 1.0, 2);
    bvh.refit(&moved).unwrap();
    let fresh = Bvh::build(&moved, &BvhParams::wide());
    assert!(
        bvh.sah_cost() > 2.0 * fresh.sah_cost(),
        "refitted {} against fresh {}",
        bvh.sah_cost(),
        fresh.sah_cost()
    );
}

#[test]
fn copies_that_part_ways_ask_for_a_rebuild() {
    let t = Triangle::new(
        rt_core::glam::Vec3::ZERO,
        rt_core::glam::Vec3::X,
        rt_core::glam::Vec3::Y,
    );
    let tris = vec![t; 50];
    for (name, params) in presets() {
        let mut bvh = Bvh::build(&tris, &params);
        assert_eq!(bvh.build_stats().prim_refs, 1, "{name}: copies stored once");
        let mut moved = tris.clone();
        moved[20].v0.z = 0.5;
        assert_eq!(
            bvh.refit(&moved),
            Err(RefitError::CopiesDiverged {
                prim: 20,
                copy_of: 0
            }),
            "{name}"
        );
        let moved: Vec<Triangle> = tris
            .iter()
            .map(|t| Triangle {
                v0: t.v0 + 1.0,
                ..*t
            })
            .collect();
        assert_eq!(bvh.refit(&moved), Ok(()), "{name}: copies moving together");
        assert_eq!(
            bvh.intersect(&rt_core::Ray::new(
                rt_core::glam::Vec3::new(0.9, 0.2, -1.0),
                rt_core::glam::Vec3::Z
            ))
            .map(|h| h.prim),
            Some(0),
            "{name}"
        );
    }
}

#[test]
fn large_refits_name_the_primitive_that_cannot_be_followed() {
    // 20k triangles: the parallel check.
    let tris = rt_scene::scenes::builtin("sphereflake:20k")
        .expect("built-in scene")
        .triangles();
    let mut bvh = Bvh::build(&tris, &BvhParams::wide());
    let mut broken = tris.clone();
    broken[12_345].v2 = rt_core::glam::Vec3::splat(f32::INFINITY);
    assert_eq!(
        bvh.refit(&broken),
        Err(RefitError::ValidityChanged { prim: 12_345 })
    );
    // A primitive of another kind than its pack's.
    let shapes: Vec<rt_core::Shape> = tris.iter().map(|&t| rt_core::Shape::Triangle(t)).collect();
    let mut bvh = Bvh::build(&shapes, &BvhParams::wide());
    assert!(!bvh.packs().is_empty());
    let mut changed = shapes.clone();
    changed[777] = rt_core::Shape::Sphere(rt_core::Sphere {
        center: rt_core::glam::Vec3::ZERO,
        radius: 0.1,
    });
    assert_eq!(
        bvh.refit(&changed),
        Err(RefitError::KindChanged { prim: 777 })
    );
    assert_eq!(bvh.refit(&shapes), Ok(()));
}

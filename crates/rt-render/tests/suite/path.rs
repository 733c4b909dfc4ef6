//! The path tracer: single rays and batches render the same bytes through every structure, the
//! bounce depths count every ray, and a structure that misses a primitive shows in the picture.

use crate::pictures::{Singles, structures};
use rt_core::{Accel, BruteForce, DynAccel, Shape};
use rt_render::{PathOptions, PathRender, RenderScene, Tracing, render_path};

const OPTIONS: PathOptions = PathOptions {
    width: 40,
    height: 30,
    samples: 2,
    bounces: 3,
    seed: 7,
};

fn path(scene: &RenderScene, tracer: &dyn DynAccel<Shape>, tracing: Tracing) -> PathRender {
    render_path(
        scene,
        &scene.shapes(),
        tracer,
        &OPTIONS,
        tracing,
        &|_, _| {},
    )
    .unwrap()
}

fn differing(a: &PathRender, b: &PathRender) -> usize {
    let (a, b) = (&a.image.pixels, &b.image.pixels);
    a.iter().zip(b).filter(|(a, b)| a != b).count()
}

/// Brute force's picture, with single rays, against every structure's with single rays, with
/// batches and with both paired: the same bytes, and the same rays at every depth; paired, no
/// batch answer differs from its single ray's.
#[test]
fn every_structure_renders_the_same_bytes_with_single_rays_and_batches() {
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    let brute = BruteForce::build(&shapes, &());
    let reference = path(&scene, &brute, Tracing::Single);
    for (name, tracer) in structures(&shapes) {
        for tracing in [Tracing::Single, Tracing::Batch, Tracing::Paired] {
            let run = path(&scene, tracer.as_ref(), tracing);
            let differ = differing(&reference, &run);
            assert_eq!(differ, 0, "{name} {tracing:?}: {differ} pixels differ");
            let rays = |r: &PathRender| -> Vec<_> {
                r.depths
                    .iter()
                    .map(|d| (d.rays, d.hits, d.shadow_rays, d.blocked))
                    .collect()
            };
            assert_eq!(rays(&run), rays(&reference), "{name} {tracing:?}");
            let paired: Vec<_> = run.depths.iter().map(|d| d.paired).collect();
            if tracing == Tracing::Paired {
                assert!(
                    paired.iter().all(|p| p.is_some_and(|p| p.differences == 0)),
                    "{name}: {paired:?}"
                );
            } else {
                assert!(paired.iter().all(Option::is_none), "{name} {tracing:?}");
            }
        }
    }
}

/// Depth 0 traces one primary ray per path; each deeper depth at most one ray per hit of the
/// one before; each hit plans at most one shadow ray per light; the last depth is `bounces`.
#[test]
fn the_depths_count_every_ray() {
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    let bvh = rt_bvh::Bvh::build(&shapes, &Default::default());
    let run = path(&scene, &bvh, Tracing::Batch);
    let d = &run.depths;
    assert_eq!(d.len(), OPTIONS.bounces as usize + 1);
    assert_eq!(
        d[0].rays,
        u64::from(OPTIONS.width * OPTIONS.height * OPTIONS.samples)
    );
    // The floor fills the lower part of the view and the sky the upper.
    assert!(d[0].hits > 0 && d[0].hits < d[0].rays, "{:?}", d[0]);
    for (a, b) in d.iter().zip(&d[1..]) {
        assert!(b.rays <= a.hits, "{a:?} then {b:?}");
    }
    for s in d {
        assert!(s.shadow_rays <= s.hits * scene.lights.len() as u64, "{s:?}");
        assert!(s.blocked <= s.shadow_rays, "{s:?}");
    }
    // Some bounces leave the floor toward the teapot, some shadow rays are blocked.
    assert!(d.iter().all(|s| s.rays > 0));
    assert!(d.iter().any(|s| s.blocked > 0));
}

/// The comparison above can fail: a structure that misses one primitive (it was built without
/// the mirror sphere) renders other bytes.
#[test]
fn a_structure_that_misses_a_primitive_renders_other_bytes() {
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    let bvh = rt_bvh::Bvh::build(&shapes, &Default::default());
    let short = rt_bvh::Bvh::build(&shapes[..shapes.len() - 1], &Default::default());
    let reference = path(&scene, &bvh, Tracing::Single);
    assert!(differing(&reference, &path(&scene, &short, Tracing::Single)) > 0);
}

/// Paired tracing counts the batch answers that differ from their single rays': a structure
/// whose closest-hit batches lose a hit is caught at every depth it traced a hit, and renders
/// other bytes.
#[test]
fn paired_tracing_counts_batches_that_lose_a_hit() {
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    let bvh = rt_bvh::Bvh::build(&shapes, &Default::default());
    let right = path(&scene, &Singles::<false>(&bvh), Tracing::Paired);
    let wrong = path(&scene, &Singles::<true>(&bvh), Tracing::Paired);
    let counted = |r: &PathRender| -> Vec<u64> {
        r.depths
            .iter()
            .map(|d| d.paired.unwrap().differences)
            .collect()
    };
    assert!(
        counted(&right).iter().all(|&n| n == 0),
        "{:?}",
        counted(&right)
    );
    assert!(counted(&wrong)[0] > 0, "{:?}", counted(&wrong));
    assert!(differing(&right, &wrong) > 0);
}

//! Secondary rays never hit the surface they leave, at any scale: no shadow acne.
//!
//! A shadow ray towards a light on the front side of a triangle or a sphere can never hit that
//! primitive (a plane, a convex surface), and neither can a mirror ray leaving a triangle; any
//! such hit is a self-intersection from rounding. The check runs on every lit pixel of the
//! bunny and the built-in scenes, each also scaled by 10⁻³ and 10³, and proves it can fail: the
//! same rays started at the hit point itself, without the offset, do hit their own surface.

use rt_bvh::Bvh;
use rt_conformance::shared_meshes_dir;
use rt_core::{Accel, Primitive, Ray, Shape};
use rt_render::{RenderOptions, RenderScene, render};

const SCALES: [f32; 3] = [1e-3, 1.0, 1e3];
const SIZE: (u32, u32) = (200, 150);

#[derive(Debug, Default)]
struct Tally {
    /// Shadow and mirror rays checked.
    rays: usize,
    /// Of those, rays that hit their own primitive.
    self_hits: usize,
    /// The same rays started without the offset that hit their own primitive.
    naive_self_hits: usize,
}

fn check(scene: &RenderScene) -> Tally {
    let shapes = scene.shapes();
    let bvh = Bvh::build(&shapes, &Default::default());
    let raster = scene.camera.raster(SIZE.0, SIZE.1);
    let mut tally = Tally::default();
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let ray = raster.ray(x as f32 + 0.5, y as f32 + 0.5);
            let Some(hit) = bvh.intersect(&ray) else {
                continue;
            };
            let shape = &shapes[hit.prim as usize];
            let s = shape.surface(&ray, hit.t, hit.u, hit.v);
            let front = if s.normal.dot(ray.dir()) < 0.0 {
                s.normal
            } else {
                -s.normal
            };
            let mut outgoing: Vec<(Ray, Ray)> = Vec::new();
            for light in &scene.lights {
                if front.dot(light.position - s.point) > 0.0 {
                    let naive = Ray::with_interval(s.point, light.position - s.point, 0.0, 1.0);
                    outgoing.push((s.spawn_ray_to(light.position), naive));
                }
            }
            if let Shape::Triangle(_) = shape {
                let d = ray.dir();
                let r = d - 2.0 * d.dot(front) * front;
                outgoing.push((s.spawn_ray(r), Ray::new(s.point, r)));
            }
            for (spawned, naive) in outgoing {
                tally.rays += 1;
                if bvh.intersect(&spawned).is_some_and(|h| h.prim == hit.prim) {
                    tally.self_hits += 1;
                }
                if bvh.intersect(&naive).is_some_and(|h| h.prim == hit.prim) {
                    tally.naive_self_hits += 1;
                }
            }
        }
    }
    tally
}

fn scenes() -> Vec<(String, RenderScene)> {
    let mut out = vec![("whitted".to_string(), RenderScene::whitted())];
    for name in ["sphereflake", "teapot-in-stadium"] {
        out.push((
            name.to_string(),
            rt_render::scene(name, SIZE.0, SIZE.1).unwrap(),
        ));
    }
    if let Some(dir) = shared_meshes_dir() {
        let bunny = dir.join("stanford-bunny.obj");
        out.push((
            "bunny".to_string(),
            rt_render::scene(bunny.to_str().unwrap(), SIZE.0, SIZE.1).unwrap(),
        ));
    }
    out
}

#[test]
fn no_secondary_ray_hits_its_own_surface_at_any_scale() {
    let mut naive_total = 0;
    for (name, scene) in scenes() {
        for scale in SCALES {
            let t = check(&scene.clone().scaled(scale));
            eprintln!("{name} × {scale}: {t:?}");
            assert!(t.rays > 10_000, "{name} × {scale}: only {} rays", t.rays);
            assert_eq!(
                t.self_hits, 0,
                "{name} × {scale}: {} of {} rays hit their own surface",
                t.self_hits, t.rays
            );
            naive_total += t.naive_self_hits;
            if name == "bunny" && scale == 1.0 {
                // The measurement: without an offset, a large share of the bunny's
                // shadow rays hit their own triangle.
                assert!(
                    t.naive_self_hits * 3 > t.rays,
                    "bunny: only {} of {} naive rays self-hit",
                    t.naive_self_hits,
                    t.rays
                );
            }
        }
    }
    assert!(
        naive_total > 0,
        "the check never saw acne, so it could not catch it"
    );
}

/// The Whitted scene scaled by 10⁻³ and 10³ renders the picture it renders at scale 1, up to
/// rounding at silhouettes and checker borders: acne or light leaks would change whole regions.
#[test]
fn scaled_scenes_render_the_same_picture() {
    let options = RenderOptions {
        width: SIZE.0,
        height: SIZE.1,
        depth: 5,
    };
    let image = |scale: f32| {
        let scene = RenderScene::whitted().scaled(scale);
        let shapes = scene.shapes();
        let bvh = Bvh::build(&shapes, &Default::default());
        render(&scene, &shapes, &bvh, &options, &|_, _| {}).unwrap()
    };
    let reference = image(1.0);
    for scale in [1e-3, 1e3] {
        let other = image(scale);
        let differ = reference
            .pixels
            .iter()
            .zip(&other.pixels)
            .filter(|(a, b)| {
                a.iter()
                    .zip(b.iter())
                    .any(|(&p, &q)| (p as i32 - q as i32).abs() > 8)
            })
            .count();
        let share = differ as f64 / reference.pixels.len() as f64;
        assert!(share < 0.01, "scale {scale}: {differ} pixels differ");
    }
    // The scene's lights really are moved with it: the key light stays above the floor.
    let scene = RenderScene::whitted().scaled(1e-3);
    assert!(scene.lights[0].position.y > 0.0 && scene.lights[0].position.length() < 1.0);
}

//! The rendered picture as a cross-check: every structure renders the same bytes, and the
//! picture shows what the scene holds (a mirror reflects the floor, shadows are darker).

use rt_bvh::{Bvh, BvhParams};
use rt_core::glam::Vec3;
use rt_core::{
    Aabb, Accel, BallQuery, BuildStats, Counters, DynAccel, Hit, PointHit, Primitive, Ray, Region,
    Shape, Trace,
};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_render::{Image, RenderOptions, RenderScene, render};

const OPTIONS: RenderOptions = RenderOptions {
    width: 160,
    height: 120,
    depth: 5,
};

fn picture(scene: &RenderScene, tracer: &dyn DynAccel<Shape>) -> Image {
    render(scene, &scene.shapes(), tracer, &OPTIONS, &|_, _| {}).unwrap()
}

/// Every structure with its default parameters, and the binary BVH, over `shapes`.
pub fn structures(shapes: &[Shape]) -> Vec<(&'static str, Box<dyn DynAccel<Shape>>)> {
    vec![
        ("bvh", Box::new(Bvh::build(shapes, &Default::default()))),
        (
            "bvh-binary",
            Box::new(Bvh::build(shapes, &BvhParams::sah())),
        ),
        (
            "kdtree",
            Box::new(KdTree::build(shapes, &Default::default())),
        ),
        ("grid", Box::new(Grid::build(shapes, &Default::default()))),
        ("hgrid", Box::new(HGrid::build(shapes, &Default::default()))),
        (
            "octree",
            Box::new(Octree::build(shapes, &Default::default())),
        ),
    ]
}

#[test]
fn every_structure_renders_the_same_bytes() {
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    let all = structures(&shapes);
    let reference = picture(&scene, all[0].1.as_ref());
    for (name, tracer) in &all[1..] {
        let image = picture(&scene, tracer.as_ref());
        let differ = reference
            .pixels
            .iter()
            .zip(&image.pixels)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differ, 0,
            "{name} renders {differ} pixels differently from bvh"
        );
    }
}

/// A structure seen without its bundle traversals: every query goes to it, but its bundle queries
/// trace each ray alone, as `DynAccel`'s defaults do; with `LOSES`, its closest-hit batches lose
/// their first hit (a wrong batch, for the checks that must catch one).
pub(crate) struct Singles<'a, const LOSES: bool = false>(pub &'a dyn DynAccel<Shape>);

impl<const LOSES: bool> DynAccel<Shape> for Singles<'_, LOSES> {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn bounds_dyn(&self) -> Aabb {
        self.0.bounds_dyn()
    }
    fn memory_bytes_dyn(&self) -> usize {
        self.0.memory_bytes_dyn()
    }
    fn build_stats_dyn(&self) -> BuildStats {
        self.0.build_stats_dyn()
    }
    fn regions_dyn(&self) -> Vec<Region> {
        self.0.regions_dyn()
    }
    fn intersect_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> Option<Hit> {
        self.0.intersect_dyn(ray, counters)
    }
    fn occluded_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> bool {
        self.0.occluded_dyn(ray, counters)
    }
    fn ball_query_dyn(&self, query: &mut dyn BallQuery<Shape>, counters: Option<&mut Counters>) {
        self.0.ball_query_dyn(query, counters);
    }
    fn trace_dyn(&self, ray: &Ray, any: bool) -> (Option<Hit>, Trace) {
        self.0.trace_dyn(ray, any)
    }
    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        self.0.intersect_all(rays, out, counters);
    }
    fn occluded_all(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        self.0.occluded_all(rays, out, counters);
    }
    fn intersect_bundle_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        self.0.intersect_all(rays, out, counters);
        if let Some(first) = out.iter_mut().find(|h| h.is_some()).filter(|_| LOSES) {
            *first = None;
        }
    }
    fn closest_points_all(
        &self,
        points: &[(Vec3, f32)],
        out: &mut [Option<PointHit>],
        counters: Option<&mut Counters>,
    ) {
        self.0.closest_points_all(points, out, counters);
    }
}

/// The picture [`render`] makes by tracing bundles, against the one the same structure makes
/// with single rays: the same bytes, for every structure (a wrong pairing of rays and answers,
/// or a lane answered differently, changes pixels).
#[test]
fn bundles_render_the_single_rays_bytes() {
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    for (name, tracer) in structures(&shapes) {
        let bundled = picture(&scene, tracer.as_ref());
        let single = picture(&scene, &Singles::<false>(tracer.as_ref()));
        let differ = single
            .pixels
            .iter()
            .zip(&bundled.pixels)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(differ, 0, "{name}: {differ} pixels differ from single rays");
    }
}

/// The primary ray of pixel `(x, y)`.
fn primary(scene: &RenderScene, x: u32, y: u32) -> Ray {
    scene
        .camera
        .raster(OPTIONS.width, OPTIONS.height)
        .ray(x as f32 + 0.5, y as f32 + 0.5)
}

#[test]
fn the_picture_shows_the_scene() {
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    let bvh = Bvh::build(&shapes, &Default::default());
    let image = picture(&scene, &bvh);
    assert_eq!(
        image.pixels.len(),
        (OPTIONS.width * OPTIONS.height) as usize
    );
    let first = image.pixels[0];
    assert!(image.pixels.iter().any(|&p| p != first), "a constant image");

    let triangles = scene.mesh.triangle_count();
    let mirror = triangles + 1;
    let floor = [0usize, 1];
    let floor_material = &scene.materials[0];
    let red = floor_material.checker.unwrap();
    // Which checker colour the floor has at a point (the renderer's rule).
    let is_red = |p: rt_core::glam::Vec3| {
        let s = floor_material.checker_size;
        ((p.x / s).floor() as i64 + (p.z / s).floor() as i64).rem_euclid(2) != 0
    };
    let lum = |p: [u8; 3]| p.iter().map(|&c| c as u32).sum::<u32>();

    // A pixel on the mirror sphere that sees the floor shows the checker colour found there.
    let mut checked_mirror = [0usize; 2];
    for y in 0..OPTIONS.height {
        for x in 0..OPTIONS.width {
            let ray = primary(&scene, x, y);
            let Some(hit) = bvh.intersect(&ray) else {
                continue;
            };
            if hit.prim as usize != mirror {
                continue;
            }
            let s = shapes[mirror].surface(&ray, hit.t, hit.u, hit.v);
            let d = ray.dir();
            let reflected = s.spawn_ray(d - 2.0 * d.dot(s.normal) * s.normal);
            let Some(seen) = bvh.intersect(&reflected) else {
                continue;
            };
            if !floor.contains(&(seen.prim as usize)) {
                continue;
            }
            let p = image.pixel(x, y).map(|c| c as i32);
            let spot = reflected.at(seen.t);
            // Stay clear of square borders, where the pixel centre and the hit can disagree.
            let s = floor_material.checker_size;
            let frac = |v: f32| (v / s - (v / s).floor() - 0.5).abs();
            if frac(spot.x) > 0.4 || frac(spot.z) > 0.4 {
                continue;
            }
            // Red dominates on the red squares, lit or in shadow; the light squares are grey.
            if is_red(spot) {
                assert!(
                    p[0] * 10 > p[1] * 13 && p[0] * 10 > p[2] * 13,
                    "mirror pixel ({x}, {y}) should show red {red}, is {p:?}"
                );
                checked_mirror[0] += 1;
            } else {
                assert!(
                    p[0] * 10 < p[1] * 12 && p[1] > 40,
                    "mirror pixel ({x}, {y}) should show the light squares, is {p:?}"
                );
                checked_mirror[1] += 1;
            }
        }
    }
    assert!(
        checked_mirror.iter().all(|&n| n > 5),
        "too few mirror pixels checked: {checked_mirror:?}"
    );

    // A floor pixel in the key light's shadow is darker than a lit neighbour on the same colour.
    let key = scene.lights[0].position;
    let mut checked_shadow = 0;
    for y in 0..OPTIONS.height {
        for x in 0..OPTIONS.width - 4 {
            let state = |x: u32| {
                let ray = primary(&scene, x, y);
                let hit = bvh.intersect(&ray)?;
                if !floor.contains(&(hit.prim as usize)) {
                    return None;
                }
                let s = shapes[hit.prim as usize].surface(&ray, hit.t, hit.u, hit.v);
                let shadowed = scene
                    .lights
                    .iter()
                    .map(|l| bvh.occluded(&s.spawn_ray_to(l.position)))
                    .collect::<Vec<_>>();
                Some((is_red(s.point), shadowed))
            };
            let (Some((red_a, a)), Some((red_b, b))) = (state(x), state(x + 4)) else {
                continue;
            };
            if red_a == red_b && a[0] && !a[1] && !b[0] && !b[1] {
                let (dark, lit) = (lum(image.pixel(x, y)), lum(image.pixel(x + 4, y)));
                assert!(
                    dark + 30 < lit,
                    "shadow ({x}, {y}) {dark} vs lit {lit}, light {key}"
                );
                checked_shadow += 1;
            }
        }
    }
    assert!(
        checked_shadow > 10,
        "only {checked_shadow} shadow edges checked"
    );
}

//! Render time of the built-in Whitted scene (glass and mirror spheres, a checkerboard floor and
//! the 44k-triangle teapot) at 1024×768, depth 5, through each structure, on all threads.
//!
//! ```sh
//! cargo bench -p rt-benches --bench render                      # 5 passes each
//! cargo bench -p rt-benches --bench render -- --passes 3 --width 512 --height 384
//! ```
//!
//! Method: each structure is built once (build time: the median of `--passes` builds); one
//! untimed pass counts the rays a picture takes (primary, shadow, mirror and refracted); then
//! the structures render in turn, `--passes` rounds interleaved (A B C A B C ...) after one
//! warm-up round, and the median is reported with its ratio to the BVH's. Every picture is
//! compared with the BVH's: the run panics if any byte differs.

use rt_bvh::Bvh;
use rt_core::glam::Vec3;
use rt_core::{
    Aabb, Accel, BallQuery, BuildStats, Counters, DynAccel, Hit, PointHit, Ray, Region, Shape,
    Trace,
};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_render::{Image, RenderOptions, RenderScene, render};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

struct Options {
    passes: usize,
    width: u32,
    height: u32,
    depth: u32,
}

fn options() -> Options {
    let mut o = Options {
        passes: 5,
        width: 1024,
        height: 768,
        depth: 5,
    };
    for (flag, value) in rt_benches::flag_values() {
        let number = |what: &str| -> u32 { value.parse().unwrap_or_else(|_| panic!("{what} N")) };
        match flag.as_str() {
            "--passes" => o.passes = number("--passes") as usize,
            "--width" => o.width = number("--width"),
            "--height" => o.height = number("--height"),
            "--depth" => o.depth = number("--depth"),
            _ => panic!("unknown flag {flag}"),
        }
    }
    o.passes = o.passes.max(1);
    o
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Counts the queries a render makes (only in the untimed pass: the shared counters would
/// slow the timed ones). Single and bundle queries are counted per ray; the others forward as they are.
struct Counting<'a> {
    inner: &'a dyn DynAccel<Shape>,
    closest: AtomicU64,
    any: AtomicU64,
}

impl DynAccel<Shape> for Counting<'_> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn bounds_dyn(&self) -> Aabb {
        self.inner.bounds_dyn()
    }
    fn memory_bytes_dyn(&self) -> usize {
        self.inner.memory_bytes_dyn()
    }
    fn build_stats_dyn(&self) -> BuildStats {
        self.inner.build_stats_dyn()
    }
    fn regions_dyn(&self) -> Vec<Region> {
        self.inner.regions_dyn()
    }
    fn intersect_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> Option<Hit> {
        self.closest.fetch_add(1, Ordering::Relaxed);
        self.inner.intersect_dyn(ray, counters)
    }
    fn occluded_dyn(&self, ray: &Ray, counters: Option<&mut Counters>) -> bool {
        self.any.fetch_add(1, Ordering::Relaxed);
        self.inner.occluded_dyn(ray, counters)
    }
    fn ball_query_dyn(&self, query: &mut dyn BallQuery<Shape>, counters: Option<&mut Counters>) {
        self.inner.ball_query_dyn(query, counters);
    }
    fn trace_dyn(&self, ray: &Ray, any: bool) -> (Option<Hit>, Trace) {
        self.inner.trace_dyn(ray, any)
    }
    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        self.inner.intersect_all(rays, out, counters);
    }
    fn occluded_all(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        self.inner.occluded_all(rays, out, counters);
    }
    fn intersect_bundle_dyn(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        counters: Option<&mut Counters>,
    ) {
        self.closest.fetch_add(rays.len() as u64, Ordering::Relaxed);
        self.inner.intersect_bundle_dyn(rays, out, counters);
    }
    fn occluded_bundle_dyn(&self, rays: &[Ray], out: &mut [bool], counters: Option<&mut Counters>) {
        self.any.fetch_add(rays.len() as u64, Ordering::Relaxed);
        self.inner.occluded_bundle_dyn(rays, out, counters);
    }
    fn closest_points_all(
        &self,
        points: &[(Vec3, f32)],
        out: &mut [Option<PointHit>],
        counters: Option<&mut Counters>,
    ) {
        self.inner.closest_points_all(points, out, counters);
    }
}

type Build = fn(&[Shape]) -> Box<dyn DynAccel<Shape>>;

fn boxed<A: Accel<Prim = Shape> + 'static>(shapes: &[Shape]) -> Box<dyn DynAccel<Shape>> {
    Box::new(A::build(shapes, &Default::default()))
}

fn main() {
    let o = options();
    let scene = RenderScene::whitted();
    let shapes = scene.shapes();
    let structures: [(&str, Build); 5] = [
        ("bvh", boxed::<Bvh<Shape>>),
        ("kdtree", boxed::<KdTree<Shape>>),
        ("grid", boxed::<Grid<Shape>>),
        ("hgrid", boxed::<HGrid<Shape>>),
        ("octree", boxed::<Octree<Shape>>),
    ];
    let options = RenderOptions {
        width: o.width,
        height: o.height,
        depth: o.depth,
    };
    let threads = rayon::current_num_threads();
    println!(
        "render: whitted ({} primitives), {}×{}, depth {}, {threads} threads, median of {} passes",
        shapes.len(),
        o.width,
        o.height,
        o.depth,
        o.passes
    );
    let picture =
        |t: &dyn DynAccel<Shape>| render(&scene, &shapes, t, &options, &|_, _| {}).unwrap();

    let mut built = Vec::new();
    for (name, build) in structures {
        let mut times = Vec::new();
        let mut tracer = None;
        for _ in 0..o.passes {
            let start = Instant::now();
            tracer = Some(build(&shapes));
            times.push(start.elapsed().as_secs_f64());
        }
        built.push((name, tracer.expect("at least one pass"), median(times)));
    }

    let reference: Image = picture(built[0].1.as_ref());
    let counting = Counting {
        inner: built[0].1.as_ref(),
        closest: AtomicU64::new(0),
        any: AtomicU64::new(0),
    };
    picture(&counting);
    let (closest, any) = (counting.closest.into_inner(), counting.any.into_inner());

    let mut times = vec![Vec::new(); built.len()];
    for round in 0..=o.passes {
        for (k, (name, tracer, _)) in built.iter().enumerate() {
            let start = Instant::now();
            let image = picture(tracer.as_ref());
            let seconds = start.elapsed().as_secs_f64();
            assert!(image == reference, "{name} renders different bytes");
            if round > 0 {
                times[k].push(seconds);
            }
        }
    }
    println!(
        "rays per picture: {closest} closest-hit (primary, mirror, refracted), {any} shadow; {:.2} per pixel",
        (closest + any) as f64 / (o.width as f64 * o.height as f64)
    );
    println!(
        "{:<8} {:>10} {:>10} {:>10} {:>8}",
        "", "build ms", "render s", "Mrays/s", "÷ bvh"
    );
    let bvh = median(times[0].clone());
    for ((name, _, build), t) in built.iter().zip(times) {
        let t = median(t);
        println!(
            "{name:<8} {:>10.1} {:>10.3} {:>10.2} {:>8.2}",
            build * 1e3,
            t,
            (closest + any) as f64 / t / 1e6,
            t / bvh
        );
    }
}

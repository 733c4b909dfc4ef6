//! What a bundle of one ray costs over a single-ray call, for every structure: each primary ray
//! of a filled view traced by `intersect` and by `intersect_bundle` with a slice of one ray, the
//! passes interleaved (A B A B ...), the median pass reported, with the ratio and its geometric
//! mean over the scenes. A renderer that hands over whatever rays it has, one at a time when
//! it has one, must not pay for the bundle path (the target: at most 2% more).
//!
//! ```sh
//! cargo bench -p rt-benches --bench bundle_of_one            # 5 passes
//! cargo bench -p rt-benches --bench bundle_of_one -- --passes 9
//! ```

use rt_benches::{BenchScene, peer_scenes};
use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, Hit, Ray, Triangle};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_scene::scenes::{View, camera_for_view};
use std::hint::black_box;
use std::time::{Duration, Instant};

const WIDTH: u32 = 512;
const HEIGHT: u32 = 384;

/// Median seconds of a single-ray pass and of a one-ray-bundle pass of `accel` over `rays`,
/// `passes` each, interleaved; panics if any answer differs.
fn measure<A: Accel>(accel: &A, rays: &[Ray], passes: usize) -> (f64, f64) {
    let single = |rays: &[Ray]| {
        rays.iter()
            .map(|r| accel.intersect(black_box(r)))
            .collect::<Vec<_>>()
    };
    let one = |rays: &[Ray]| {
        rays.iter()
            .map(|r| {
                let mut out: [Option<Hit>; 1] = [None];
                accel.intersect_bundle(std::slice::from_ref(black_box(r)), &mut out);
                out[0]
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (single(rays), one(rays));
    assert!(
        a.iter()
            .zip(&b)
            .all(|(x, y)| x.map(|h| (h.prim, h.t.to_bits())) == y.map(|h| (h.prim, h.t.to_bits()))),
        "{}: a bundle of one answered differently",
        A::NAME
    );
    let (mut ts, mut tb) = (Vec::new(), Vec::new());
    for _ in 0..passes {
        let t = Instant::now();
        black_box(single(rays));
        ts.push(t.elapsed());
        let t = Instant::now();
        black_box(one(rays));
        tb.push(t.elapsed());
    }
    let median = |v: &mut Vec<Duration>| {
        v.sort();
        v[v.len() / 2].as_secs_f64()
    };
    (median(&mut ts), median(&mut tb))
}

fn rows(scene: &BenchScene, passes: usize) -> Vec<(&'static str, f64, f64)> {
    let tris: &[Triangle] = &scene.triangles;
    let camera = camera_for_view(&scene.spec, &scene.bounds(), WIDTH, HEIGHT, View::Filled);
    let rays = camera.primary_rays(WIDTH, HEIGHT);
    let row = |name, (s, b): (f64, f64)| (name, s, b);
    vec![
        row(
            "bvh",
            measure(&Bvh::build(tris, &BvhParams::wide()), &rays, passes),
        ),
        row(
            "bvh-binary",
            measure(&Bvh::build(tris, &BvhParams::sah()), &rays, passes),
        ),
        row(
            "kdtree",
            measure(&KdTree::build(tris, &Default::default()), &rays, passes),
        ),
        row(
            "grid",
            measure(&Grid::build(tris, &Default::default()), &rays, passes),
        ),
        row(
            "hgrid",
            measure(&HGrid::build(tris, &Default::default()), &rays, passes),
        ),
        row(
            "octree",
            measure(&Octree::build(tris, &Default::default()), &rays, passes),
        ),
    ]
}

fn main() {
    let passes = rt_benches::passes_flag(5);
    println!(
        "One-ray bundles against single-ray calls: primary rays of the filled view, {WIDTH}×{HEIGHT}, \
         one thread, median of {passes} interleaved passes; ms per pass and bundle ÷ single\n"
    );
    println!("| scene | structure | single ms | bundle of one ms | ratio |");
    println!("| --- | --- | ---: | ---: | ---: |");
    let mut ratios: Vec<(&'static str, Vec<f64>)> = Vec::new();
    for scene in peer_scenes() {
        for (name, s, b) in rows(&scene, passes) {
            println!(
                "| {} | {name} | {:.1} | {:.1} | {:.3} |",
                scene.name,
                1e3 * s,
                1e3 * b,
                b / s
            );
            match ratios.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => v.push(b / s),
                None => ratios.push((name, vec![b / s])),
            }
        }
    }
    println!("\n| structure | geometric mean of bundle ÷ single |\n| --- | ---: |");
    for (name, v) in ratios {
        let mean = (v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp();
        println!("| {name} | {mean:.3} |");
    }
}

//! How fast is a signed distance field, and how much faster than brute force? For every
//! structure, the signed distance (`rt_sdf::SignedDistance::signed_distance`: the structure's closest point,
//! signed by the fast winding number of one shared [`WindingTree`]) at every sample of an
//! `N × N × N` grid over the mesh's box grown by a tenth on every side, on all threads. Brute
//! force (its closest point, signed by the exact winding number over every triangle) answers a
//! spread of about 2,000 of the same samples (every 1,021st), on the same threads; the speedup
//! is its time per sample over the structure's, and every structure's answers on those samples
//! are checked against it. The closest point alone and the sign alone are timed on the BVH, to
//! show where the time goes.
//!
//! The Stanford bunny at 128³ is the case the issue names; the rocker arm, the Beetle and the
//! fandisk (none of them tuned on) at 64³.
//!
//! ```sh
//! cargo bench -p rt-benches --bench sdf
//! cargo bench -p rt-benches --bench sdf -- --resolution 96   # every mesh at 96³
//! ```

use rayon::prelude::*;
use rt_benches::{BenchScene, flag_values, shared};
use rt_bvh::Bvh;
use rt_core::{Accel, BruteForce, DynAccel, PointHit, Triangle, glam::Vec3};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_sdf::{SignedPoint, WindingTree, winding_number_exact};
use std::time::Instant;

/// Brute force answers every `STRIDE`-th sample.
const STRIDE: usize = 1021;

/// The samples of an `n³` grid over `tris`' box grown by a tenth.
fn grid(tris: &[Triangle], n: usize) -> Vec<Vec3> {
    let b = rt_core::valid_bounds(tris);
    let margin = b.extent() * 0.1;
    let (lo, size) = (b.min - margin, b.extent() + 2.0 * margin);
    let step = size / (n - 1) as f32;
    (0..n * n * n)
        .map(|i| lo + step * Vec3::new((i % n) as f32, ((i / n) % n) as f32, (i / (n * n)) as f32))
        .collect()
}

/// Seconds for `f` over every point on all threads, and its answers.
fn timed<T: Send>(points: &[Vec3], f: impl Fn(Vec3) -> T + Sync) -> (f64, Vec<T>) {
    let t = Instant::now();
    let out: Vec<T> = points.par_iter().map(|&p| f(p)).collect();
    (t.elapsed().as_secs_f64(), out)
}

/// Whether a structure's answer is brute force's: the same closest point, and the sign of the
/// exact winding number `w` unless it is within rounding of ½.
fn agrees(got: Option<SignedPoint>, expected: Option<SignedPoint>, w: f64) -> bool {
    PointHit::agree(got.map(|s| s.near), expected.map(|s| s.near))
        && ((w - 0.5).abs() <= 1e-6 || got.map(|s| s.inside) == Some(w > 0.5))
}

fn main() {
    let forced = flag_values()
        .into_iter()
        .rev()
        .find(|(f, _)| f == "--resolution")
        .map(|(_, v)| {
            v.parse::<usize>()
                .ok()
                .filter(|&n| (2..=1024).contains(&n))
                .expect("--resolution takes 2 to 1024")
        });
    let meshes: Vec<(BenchScene, usize)> = [
        ("bunny", "stanford-bunny.obj", 128),
        ("rocker-arm", "rocker-arm.obj", 64),
        ("beetle", "beetle-alt.obj", 64),
        ("fandisk", "fandisk.obj", 64),
    ]
    .into_iter()
    .filter_map(|(name, file, n)| shared(name, file).map(|s| (s, forced.unwrap_or(n))))
    .collect();
    if meshes.is_empty() {
        eprintln!("the shared meshes are not at ../shared/meshes: nothing to measure");
        return;
    }
    println!(
        "{:<11} {:>5} {:>7} {:<8} {:>9} {:>12} {:>13} {:>9} {:>10}",
        "mesh",
        "grid",
        "inside",
        "row",
        "total s",
        "µs/sample",
        "brute µs",
        "speedup",
        "mismatches"
    );
    for (scene, n) in meshes {
        let tris = &scene.triangles;
        let points = grid(tris, n);
        let sample: Vec<Vec3> = points.iter().step_by(STRIDE).copied().collect();
        let threads = rayon::current_num_threads() as f64;
        let per = |secs: f64, count: usize| secs * 1e6 * threads / count as f64;

        let sign = WindingTree::build(tris).expect("meshes hold triangles");
        let brute = BruteForce::build(tris, &());
        let (brute_s, expected) = timed(&sample, |p| {
            let w = winding_number_exact(tris, p).expect("meshes hold triangles");
            let near = brute.closest_point(p, f32::INFINITY);
            (near.map(|near| SignedPoint::signed(near, w > 0.5)), w)
        });
        let brute_us = per(brute_s, sample.len());
        let inside = expected
            .iter()
            .filter(|(s, _)| s.is_some_and(|s| s.inside))
            .count();
        let label = format!("{n}³");
        let share = format!("{:.1}%", 100.0 * inside as f64 / sample.len() as f64);
        let rows: Vec<(&str, Box<dyn DynAccel<Triangle>>)> = vec![
            ("bvh", Box::new(Bvh::build(tris, &Default::default()))),
            ("kdtree", Box::new(KdTree::build(tris, &Default::default()))),
            ("grid", Box::new(Grid::build(tris, &Default::default()))),
            ("hgrid", Box::new(HGrid::build(tris, &Default::default()))),
            ("octree", Box::new(Octree::build(tris, &Default::default()))),
        ];
        for (name, accel) in &rows {
            let one = |p: Vec3| {
                let mut out = [None];
                rt_sdf::signed_distances(&**accel, &sign, &[(p, f32::INFINITY)], &mut out, None);
                out[0]
            };
            let (secs, _) = timed(&points, one);
            let (_, got) = timed(&sample, one);
            let mismatches = got
                .iter()
                .zip(&expected)
                .filter(|(g, (e, w))| !agrees(**g, *e, *w))
                .count();
            let us = per(secs, points.len());
            println!(
                "{:<11} {:>5} {:>7} {:<8} {:>9.2} {:>12.2} {:>13.0} {:>8.0}x {:>10}",
                scene.name,
                label,
                share,
                name,
                secs,
                us,
                brute_us,
                brute_us / us,
                mismatches
            );
        }
        // Where the BVH's time goes: its closest point alone, the sign alone.
        let bvh = Bvh::build(tris, &Default::default());
        let (closest_s, _) = timed(&points, |p| bvh.closest_point(p, f32::INFINITY));
        let (sign_s, _) = timed(&points, |p| sign.is_inside(p));
        println!(
            "{:<11} {:>5} {:>7} {:<8} {:>9.2} {:>12.2}   (the BVH's closest point alone)",
            scene.name,
            label,
            share,
            "closest",
            closest_s,
            per(closest_s, points.len())
        );
        println!(
            "{:<11} {:>5} {:>7} {:<8} {:>9.2} {:>12.2}   (the winding tree's sign alone; tree {:.2} MiB)",
            scene.name,
            label,
            share,
            "sign",
            sign_s,
            per(sign_s, points.len()),
            sign.memory_bytes() as f64 / (1024.0 * 1024.0)
        );
    }
}

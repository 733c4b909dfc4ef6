//! What an invalid ray costs: every shootout row traces the same primary rays twice, once as
//! they are and once made invalid in the six ways `Ray::is_valid` rejects (a NaN origin, an
//! origin beyond `Ray::MAX_ORIGIN`, a NaN direction, an infinite direction, a zero direction, an
//! empty interval), single-threaded, in interleaved passes. It prints the median nanoseconds per
//! ray of each and their ratio. The bar (Embree's verification suite uses the same one): an
//! invalid ray costs at most 2.5 times a valid one, because a structure answers it at once
//! instead of walking its nodes. Rows above the bar are marked and the run exits with status 1.
//!
//! `cargo bench -p rt-benches --bench invalid [-- --passes 7 --width 512 --height 384]`

use rt_benches::{flag_values, scenes};
use rt_core::Ray;
use rt_core::glam::Vec3;
use rt_core::{DynAccel, Triangle};
use rt_shootout::structures::{self, Query};
use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

/// The most an invalid ray may cost, as a multiple of a valid ray.
const BAR: f64 = 2.5;

/// Each ray made invalid in one of six ways, in turn.
fn invalid(rays: &[Ray]) -> Vec<Ray> {
    rays.iter()
        .enumerate()
        .map(|(i, r)| {
            let (o, d) = (r.origin, r.dir());
            match i % 6 {
                0 => Ray::new(Vec3::new(f32::NAN, o.y, o.z), d),
                1 => Ray::new(Vec3::new(o.x, Ray::MAX_ORIGIN * 4.0, o.z), d),
                2 => Ray::new(o, Vec3::new(d.x, f32::NAN, d.z)),
                3 => Ray::new(o, Vec3::new(d.x, d.y, f32::INFINITY)),
                4 => Ray::new(o, Vec3::ZERO),
                _ => Ray::with_interval(o, d, 2.0, 1.0),
            }
        })
        .collect()
}

/// Nanoseconds per ray of one single-threaded pass.
fn pass(s: &dyn DynAccel<Triangle>, rays: &[Ray]) -> f64 {
    let start = Instant::now();
    black_box(structures::trace_timed(s, black_box(rays), Query::Closest));
    start.elapsed().as_nanos() as f64 / rays.len() as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> ExitCode {
    let mut passes = 5;
    let (mut width, mut height) = (512, 384);
    for (flag, value) in flag_values() {
        let n: usize = value
            .parse()
            .unwrap_or_else(|_| panic!("{flag} needs a number"));
        match flag.as_str() {
            "--passes" => passes = n.max(1),
            "--width" => width = n as u32,
            "--height" => height = n as u32,
            _ => panic!("unknown flag {flag}; flags: --passes --width --height"),
        }
    }
    // Single-threaded, so that the figures are per ray and not per core.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    let mut over = 0;
    for scene in scenes() {
        let valid = scene.primary_rays(width, height);
        let bad = invalid(&valid);
        assert!(valid.iter().all(Ray::is_valid) && !bad.iter().any(Ray::is_valid));
        println!(
            "{}: {} triangles, {} rays, median of {passes} interleaved passes",
            scene.name,
            scene.triangles.len(),
            valid.len()
        );
        println!(
            "{:<22} {:>12} {:>14} {:>8}",
            "structure", "valid ns/ray", "invalid ns/ray", "ratio"
        );
        for row in structures::all() {
            let built = pool.install(|| (row.build)(&scene.triangles));
            let (mut good, mut poor) = (Vec::new(), Vec::new());
            for _ in 0..passes {
                good.push(pool.install(|| pass(built.as_ref(), &valid)));
                poor.push(pool.install(|| pass(built.as_ref(), &bad)));
            }
            let (good, poor) = (median(good), median(poor));
            let ratio = poor / good;
            let mark = if ratio > BAR {
                over += 1;
                "  over the bar"
            } else {
                ""
            };
            println!(
                "{:<22} {good:>12.1} {poor:>14.2} {ratio:>8.3}{mark}",
                row.name
            );
        }
        println!();
    }
    if over > 0 {
        println!("{over} rows over the {BAR}x bar");
        ExitCode::FAILURE
    } else {
        println!("every row: an invalid ray costs at most {BAR}x a valid one");
        ExitCode::SUCCESS
    }
}

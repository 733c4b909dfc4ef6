//! Builds rt-bvh's presets over large height fields and reports, per size: build time on one
//! thread and on all threads, the structure's size, and the most memory the build itself held on
//! top of its input (the process's peak resident memory during the build, read from Linux's
//! `/proc/self/status` after resetting the peak, minus what was resident before; elsewhere this
//! column is left empty).
//!
//! ```sh
//! cargo run --release -p rt-bvh --example large                      # 1, 2.5 and 10 million
//! cargo run --release -p rt-bvh --example large -- 1000000 4000000  # chosen sizes
//! ```
//!
//! Time per triangle that grows with log N, and peak memory that stays a constant number of
//! bytes per triangle, are what O(N log N) with bounded scratch memory look like.

use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, Hit, Ray, Rng, Triangle, glam::Vec3, scenes};
use std::time::Instant;

/// A line of `/proc/self/status` in KiB.
fn status_kib(key: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Resets the peak resident memory to the current one (Linux: `5` in `clear_refs`).
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn mib(bytes: f64) -> f64 {
    bytes / (1024.0 * 1024.0)
}

fn main() {
    let sizes: Vec<usize> = {
        let args: Vec<usize> = std::env::args()
            .skip(1)
            .map(|a| {
                a.parse().unwrap_or_else(|_| {
                    eprintln!("error: `{a}` is not a triangle count");
                    std::process::exit(2)
                })
            })
            .collect();
        if args.is_empty() {
            vec![1_000_000, 2_500_000, 10_000_000]
        } else {
            args
        }
    };
    let threads = rayon::current_num_threads();
    println!(
        "| triangles | preset | build, 1 thread (ns/triangle) | build, {threads} threads | speed-up | structure MiB (bytes/triangle) | peak during build, MiB (bytes/triangle) |"
    );
    println!("| ---: | --- | ---: | ---: | ---: | ---: | ---: |");
    for &n in &sizes {
        let tris = scenes::height_field(n).triangles();
        let n = tris.len();
        let mut trees: Vec<Bvh<Triangle>> = Vec::new();
        for (preset, params) in [("wide", BvhParams::wide()), ("binary", BvhParams::sah())] {
            let sequential = BvhParams {
                parallel: false,
                ..params.clone()
            };
            let t = Instant::now();
            drop(Bvh::build(&tris, &sequential));
            let one = t.elapsed().as_secs_f64();
            let before = status_kib("VmRSS:");
            let peak_known = reset_peak();
            let t = Instant::now();
            let bvh = Bvh::build(&tris, &params);
            let all = t.elapsed().as_secs_f64();
            let peak = match (peak_known, before, status_kib("VmHWM:")) {
                (true, Some(b), Some(p)) => {
                    let extra = p.saturating_sub(b) as f64 * 1024.0;
                    format!("{:.0} ({:.0})", mib(extra), extra / n as f64)
                }
                _ => String::new(),
            };
            let bytes = bvh.memory_bytes() as f64;
            println!(
                "| {n} | {preset} | {:.0} ms ({:.0}) | {:.0} ms | {:.2}x | {:.0} ({:.0}) | {peak} |",
                one * 1e3,
                one * 1e9 / n as f64,
                all * 1e3,
                one / all,
                mib(bytes),
                bytes / n as f64,
            );
            assert_eq!(bvh.validate(), Ok(()), "{preset} on {n} triangles");
            trees.push(bvh);
        }
        // The two layouts must agree (brute force would take too long at this size).
        let mut rng = Rng::new(n as u64);
        let disagree = (0..100_000)
            .filter(|_| {
                let o = Vec3::new(rng.f32(), 0.5, rng.f32());
                let target = Vec3::new(rng.f32(), 0.0, rng.f32());
                let ray = Ray::new(o, target - o);
                !Hit::agree(trees[0].intersect(&ray), trees[1].intersect(&ray))
            })
            .count();
        assert_eq!(disagree, 0, "wide and binary disagree on {n} triangles");
    }
}

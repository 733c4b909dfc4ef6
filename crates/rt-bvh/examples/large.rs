//! Builds rt-bvh's presets over large height fields and reports, per size: build time on one
//! thread and on all threads, the structure's size, and the most memory the build itself held on
//! top of its input (the peak resident memory during the build, read from Linux's
//! `/proc/self/status` after resetting the peak, minus what was resident before; elsewhere this
//! column is left empty). Each peak is read in a fresh process of its own that builds once: in a
//! process that has built before, the allocator's retained pages would hide part of the peak.
//!
//! ```sh
//! cargo run --release -p rt-bvh --example large                      # 1, 2.5 and 10 million
//! cargo run --release -p rt-bvh --example large -- 1000000 4000000  # chosen sizes
//! ```
//!
//! Time per triangle that grows with log N, and peak memory that stays a constant number of
//! bytes per triangle, are what O(N log N) with bounded scratch memory look like.
//!
//! Last, a million copies of one triangle: the build time, and what one closest-hit ray costs.

use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, Hit, Ray, Rng, Triangle, glam::Vec3};
use rt_scene::scenes;
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

/// Seconds taken by `f`.
fn time(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

fn mib(bytes: f64) -> f64 {
    bytes / (1024.0 * 1024.0)
}

/// The environment variable that makes this example a child measuring one build's peak memory:
/// `N PRESET`.
const PEAK_CHILD: &str = "RT_BVH_LARGE_PEAK";

fn params_of(preset: &str) -> BvhParams {
    if preset == "wide" {
        BvhParams::wide()
    } else {
        BvhParams::sah()
    }
}

/// In a child process: builds once and prints the peak memory above what was resident before,
/// in bytes; prints nothing where that cannot be read.
fn peak_child(spec: &str) {
    let mut it = spec.split_whitespace();
    let (Some(n), Some(preset)) = (it.next().and_then(|n| n.parse().ok()), it.next()) else {
        return;
    };
    let tris = scenes::height_field(n).triangles();
    let before = status_kib("VmRSS:");
    let peak_known = reset_peak();
    let bvh = Bvh::build(&tris, &params_of(preset));
    if let (true, Some(b), Some(p)) = (peak_known, before, status_kib("VmHWM:")) {
        println!("{}", p.saturating_sub(b) * 1024);
    }
    drop(bvh);
}

/// The peak memory one build of `n` triangles holds above its input, measured in a new process.
fn peak_bytes(n: usize, preset: &str) -> Option<f64> {
    let out = std::process::Command::new(std::env::current_exe().ok()?)
        .env(PEAK_CHILD, format!("{n} {preset}"))
        .output()
        .ok()?;
    String::from_utf8(out.stdout).ok()?.trim().parse().ok()
}

fn main() {
    if let Ok(spec) = std::env::var(PEAK_CHILD) {
        peak_child(&spec);
        return;
    }
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
    for &asked in &sizes {
        let tris = scenes::height_field(asked).triangles();
        let n = tris.len();
        let mut trees: Vec<Bvh<Triangle>> = Vec::new();
        for preset in ["wide", "binary"] {
            let params = params_of(preset);
            let sequential = BvhParams {
                parallel: false,
                ..params.clone()
            };
            // Single builds on a shared host vary by tens of percent: each time is the fastest
            // of three builds, alternating one thread and all threads.
            let (mut one, mut all) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..3 {
                one = one.min(time(|| drop(Bvh::build(&tris, &sequential))));
                all = all.min(time(|| drop(Bvh::build(&tris, &params))));
            }
            let bvh = Bvh::build(&tris, &params);
            let peak = peak_bytes(asked, preset).map_or(String::new(), |extra| {
                format!("{:.0} ({:.0})", mib(extra), extra / n as f64)
            });
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
    coincident();
}

/// A million copies of one triangle: the tie rule (smallest `t`, then smallest index) once made
/// a closest-hit ray test every copy to find the smallest index. Bit-identical copies are stored
/// once, so one ray now costs a few visits and one test.
fn coincident() {
    const COPIES: usize = 1_000_000;
    let tri = Triangle::new(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.5),
        Vec3::new(0.0, 1.0, 0.2),
    );
    let tris = vec![tri; COPIES];
    let ray = Ray::new(Vec3::new(0.1, 0.0, 3.0), Vec3::new(0.01, 0.02, -1.0));
    println!();
    println!("{COPIES} copies of one triangle, one closest-hit ray:");
    println!("| preset | build ms | hit | visits | tests | trace µs | structure KiB |");
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: |");
    for (preset, params) in [("wide", BvhParams::wide()), ("binary", BvhParams::sah())] {
        let t = Instant::now();
        let bvh = Bvh::build(&tris, &params);
        let build = t.elapsed().as_secs_f64();
        let mut counters = rt_core::Counters::default();
        let hit = bvh.intersect_with(&ray, &mut counters);
        // One query is too short to time reliably once: the fastest of five.
        let trace = (0..5)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(bvh.intersect(std::hint::black_box(&ray)));
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min);
        assert_eq!(
            hit.map(|h| h.prim),
            Some(0),
            "{preset}: the smallest index must win"
        );
        println!(
            "| {preset} | {:.0} | {} | {} | {} | {:.2} | {:.2} |",
            build * 1e3,
            hit.map_or(-1, |h| h.prim as i64),
            counters.node_visits,
            counters.prim_tests,
            trace * 1e6,
            bvh.memory_bytes() as f64 / 1024.0,
        );
    }
}

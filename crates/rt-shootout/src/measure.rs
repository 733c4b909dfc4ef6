//! Single-threaded measurement of one structure on one set of rays, for the parameter-sweep
//! examples: the best build time of a few builds, the counted traversal events, and the best
//! trace time. (`cargo xtask compare` measures in parallel, with its own cross-checks.)

use rt_core::{Accel, Counters, Ray};
use std::time::Instant;

/// A structure built and traced by [`measure`].
#[derive(Debug)]
pub struct Measurement<A> {
    /// The structure, from the last build.
    pub accel: A,
    /// The fastest build, in milliseconds.
    pub build_ms: f64,
    /// Events of one closest-hit pass over the rays.
    pub counters: Counters,
    /// The fastest closest-hit pass over the rays, in seconds.
    pub trace_s: f64,
    /// How many rays were traced per pass.
    pub rays: usize,
}

impl<A> Measurement<A> {
    /// A count divided by the number of rays.
    pub fn per_ray(&self, count: u64) -> f64 {
        count as f64 / self.rays as f64
    }

    /// Millions of rays per second in the fastest pass.
    pub fn mrays_per_s(&self) -> f64 {
        self.rays as f64 / self.trace_s / 1e6
    }
}

/// Builds `A` over `prims` with `params` `repeats` times (at least once) and traces `rays` for
/// closest hits once with [`Counters`] and `repeats` times without, all on the calling thread.
/// Times are the fastest of the repeats, so compare them only within one run.
pub fn measure<A: Accel>(
    prims: &[A::Prim],
    params: &A::Params,
    rays: &[Ray],
    repeats: usize,
) -> Measurement<A> {
    let repeats = repeats.max(1);
    let mut build_ms = f64::INFINITY;
    let mut accel = None;
    for _ in 0..repeats {
        let start = Instant::now();
        let built = A::build(prims, params);
        build_ms = build_ms.min(start.elapsed().as_secs_f64() * 1e3);
        accel = Some(built);
    }
    let accel = accel.expect("built at least once");
    let mut counters = Counters::default();
    for r in rays {
        accel.intersect_with(r, &mut counters);
    }
    let mut trace_s = f64::INFINITY;
    for _ in 0..repeats {
        let start = Instant::now();
        let hits = rays.iter().filter(|r| accel.intersect(r).is_some()).count();
        trace_s = trace_s.min(start.elapsed().as_secs_f64());
        std::hint::black_box(hits);
    }
    Measurement {
        accel,
        build_ms,
        counters,
        trace_s,
        rays: rays.len(),
    }
}

/// The CPU's model name (from `/proc/cpuinfo` on Linux), else the architecture: what a
/// measurement's stamp names.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

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

/// A kind of machine, as the results pages are kept: one page per kind, so that a run on one
/// CPU never overwrites the figures of another.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MachineKind {
    /// A file name for the kind: `amd-zen4`, `amd-zen5`, `intel-emerald-rapids`, ...
    pub slug: String,
    /// The kind in words, with the CPU family and model it was told by.
    pub name: String,
}

/// The kind of this machine's CPU, from the vendor, family and model in `/proc/cpuinfo`
/// ([`machine_kind_of`]); the architecture where there is no such file.
pub fn machine_kind() -> MachineKind {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |name: &str| {
        info.lines()
            .find(|l| l.split(':').next().is_some_and(|k| k.trim() == name))
            .and_then(|l| l.split(':').nth(1))
            .map(|v| v.trim().to_string())
    };
    let number = |name: &str| field(name).and_then(|v| v.parse::<u32>().ok());
    match (field("vendor_id"), number("cpu family"), number("model")) {
        (Some(vendor), Some(family), Some(model)) => machine_kind_of(&vendor, family, model),
        _ => {
            let arch = std::env::consts::ARCH;
            MachineKind {
                slug: arch.replace('_', "-"),
                name: arch.to_string(),
            }
        }
    }
}

/// The kind of a CPU by its vendor (`vendor_id`), family and model: AMD's Zen generations
/// (family 23: Zen 1 and 2; family 25: Zen 3 and 4 by model range; family 26: Zen 5) and
/// Intel's Xeon server generations (family 6), else the vendor with the family and model.
pub fn machine_kind_of(vendor: &str, family: u32, model: u32) -> MachineKind {
    let generation = match (vendor, family) {
        ("AuthenticAMD", 23) if model >= 0x30 => Some(("amd-zen2", "AMD Zen 2")),
        ("AuthenticAMD", 23) => Some(("amd-zen1", "AMD Zen 1")),
        ("AuthenticAMD", 25) => Some(match model {
            0x10..=0x1f | 0x60..=0x7f | 0xa0..=0xaf => ("amd-zen4", "AMD Zen 4"),
            _ => ("amd-zen3", "AMD Zen 3"),
        }),
        ("AuthenticAMD", 26) => Some(("amd-zen5", "AMD Zen 5")),
        ("GenuineIntel", 6) => match model {
            0x55 => Some(("intel-skylake-sp", "Intel Skylake-SP or Cascade Lake")),
            0x6a | 0x6c => Some(("intel-ice-lake-sp", "Intel Ice Lake-SP")),
            0x8f => Some(("intel-sapphire-rapids", "Intel Sapphire Rapids")),
            0xcf => Some(("intel-emerald-rapids", "Intel Emerald Rapids")),
            0xad | 0xae => Some(("intel-granite-rapids", "Intel Granite Rapids")),
            _ => None,
        },
        _ => None,
    };
    let numbers = format!("family {family}, model {model}");
    match generation {
        Some((slug, name)) => MachineKind {
            slug: slug.to_string(),
            name: format!("{name} ({numbers})"),
        },
        None => {
            let short = match vendor {
                "AuthenticAMD" => "amd",
                "GenuineIntel" => "intel",
                other => other,
            };
            let slug: String = format!("{short}-family{family}-model{model}")
                .to_lowercase()
                .chars()
                .filter(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            MachineKind {
                slug,
                name: format!("{vendor} ({numbers})"),
            }
        }
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

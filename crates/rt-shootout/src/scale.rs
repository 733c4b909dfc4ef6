//! The scale ladder: each structure built and traced on one built-in scene at sizes from
//! thousands to millions of triangles, so that an `O(N log N)` build, a logarithmic trace and a
//! super-linear one can be told apart. A scene file gives a ladder of its own: the first `n` of
//! its triangles, in the file's order (a growing part of the surface, at the file's density), up
//! to all of them.
//!
//! Per size and row: build time per triangle, trace time per primary ray, the structure's bytes
//! per triangle ([`Accel::memory_bytes`](rt_core::Accel::memory_bytes)), and the heap peak of the
//! build (with [`crate::memory::Counting`] installed as the global allocator; `cargo xtask scale`
//! installs it). The peak is split into the finished structure and the build's scratch: the
//! ratio `scratch / (structure + input)` is at most 1 for a build whose temporary memory stays
//! within what it produces and what it was given. Answers are checked against the first row on
//! a sample of the rays (brute force is too slow at millions of triangles).

use crate::memory;
use crate::structures::{self, Entry, Query};
use rt_core::{Hit, Triangle};
use rt_scene::scenes;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Flags of `cargo xtask scale`.
#[derive(clap::Args, Debug, Clone)]
pub struct ScaleArgs {
    /// The built-in scene kind the ladder sizes (`terrain`, `random-soup`, `sphereflake`,
    /// `teapot-in-stadium`, ...), or a scene file (OBJ, PLY, glTF), whose first triangles make
    /// the smaller sizes.
    #[arg(long, default_value = "terrain")]
    pub scene: String,
    /// Comma-separated rows (as `compare` names them) [default: bvh,kdtree,grid,hgrid,octree].
    #[arg(short, long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// The smallest size, in triangles (`10k`, `1M`, ...).
    #[arg(long, default_value = "10k", value_parser = crate::cli::count)]
    pub min: usize,
    /// The largest size: the ladder goes up by 1, 3, 10, 30, ... times a power of ten to here
    /// (for a file, at most its triangle count).
    #[arg(long, default_value = "1M", value_parser = crate::cli::count)]
    pub max: usize,
    /// Primary rays per size: width.
    #[arg(long, default_value_t = 256)]
    pub width: u32,
    /// Primary rays per size: height.
    #[arg(long, default_value_t = 192)]
    pub height: u32,
    /// Threads for building and tracing [default: all cores].
    #[arg(short = 'j', long)]
    pub threads: Option<usize>,
    /// Also write the four curves (build, trace, bytes, peak memory against size) as an SVG
    /// chart to this file.
    #[arg(short, long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// One row at one size.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The row's name.
    pub structure: String,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Build time, milliseconds.
    pub build_ms: f64,
    /// Trace time per primary ray, nanoseconds (wall time on all threads).
    pub trace_ns_per_ray: f64,
    /// The structure's bytes.
    pub structure_bytes: usize,
    /// The heap peak during the build, above what was in use before it; `None` without the
    /// counting allocator.
    pub peak_build_bytes: Option<usize>,
    /// Rays of the sample whose answer differs from the first row's.
    pub disagreements: usize,
}

impl Point {
    /// Build nanoseconds per triangle.
    pub fn build_ns_per_triangle(&self) -> f64 {
        self.build_ms * 1e6 / self.triangles as f64
    }

    /// Structure bytes per triangle.
    pub fn bytes_per_triangle(&self) -> f64 {
        self.structure_bytes as f64 / self.triangles as f64
    }

    /// The build's scratch memory (peak minus the finished structure) over structure plus input
    /// (the triangles, 36 bytes each): at most 1 when the build stays within that bound.
    pub fn scratch_ratio(&self) -> Option<f64> {
        let input = self.triangles * size_of::<Triangle>();
        self.peak_build_bytes.map(|peak| {
            peak.saturating_sub(self.structure_bytes) as f64 / (self.structure_bytes + input) as f64
        })
    }
}

/// The whole ladder.
#[derive(Clone, Debug)]
pub struct ScaleReport {
    /// The scene kind.
    pub scene: String,
    /// Threads used.
    pub threads: usize,
    /// Primary rays traced per size.
    pub rays: usize,
    /// Every row at every size, smallest size first.
    pub points: Vec<Point>,
}

/// The sizes from `min` to `max`: 1 and 3 times each power of ten in between, and `max`.
pub fn ladder(min: usize, max: usize) -> Vec<usize> {
    let mut out: Vec<usize> = std::iter::successors(Some(1usize), |d| d.checked_mul(10))
        .take_while(|&d| d <= max)
        .flat_map(|d| [d, d.saturating_mul(3)])
        .filter(|n| (min..max).contains(n))
        .collect();
    out.push(max);
    out
}

/// What the ladder sizes: a built-in scene kind, made at each size, or a file's triangles, whose
/// first `n` make size `n`.
enum Source {
    Builtin(&'static scenes::BuiltinScene),
    File(Vec<Triangle>),
}

impl Source {
    fn new(spec: &str) -> Result<Self, String> {
        if let Some(kind) = scenes::find(spec) {
            if spec.contains(':') {
                return Err(format!(
                    "--scene {spec}: scale sizes the scene itself; give the kind alone                      (`{}`) and the sizes with --min and --max",
                    kind.name
                ));
            }
            return Ok(Self::Builtin(kind));
        }
        let (_, triangles) = crate::scene::load_scene(spec)?;
        Ok(Self::File(triangles))
    }

    /// The largest size there is: any, or the file's triangle count.
    fn largest(&self) -> usize {
        match self {
            Self::Builtin(_) => usize::MAX,
            Self::File(t) => t.len(),
        }
    }

    /// The scene at size `n`, and the camera its primary rays come from.
    fn at(&self, n: usize, width: u32, height: u32) -> (Vec<Triangle>, rt_scene::Camera) {
        let (tris, bounds, kind) = match self {
            Self::Builtin(kind) => {
                let mesh = kind.make(n);
                (mesh.triangles(), mesh.bounds(), Some(kind))
            }
            Self::File(all) => {
                let tris = all[..n.min(all.len())].to_vec();
                let bounds = rt_core::valid_bounds(tris.iter());
                (tris, bounds, None)
            }
        };
        let camera = match kind {
            Some(kind) => kind.camera(&bounds, width, height),
            None => rt_scene::Camera::framing(&bounds, width, height),
        };
        (tris, camera)
    }
}

/// How many rays of each size are checked against the first row.
const CHECKED: usize = 2000;

/// Runs the ladder over `entries`.
///
/// # Errors
/// A one-line description of a bad flag (unknown scene or row, malformed size).
pub fn scale(args: &ScaleArgs, entries: &[Entry]) -> Result<ScaleReport, String> {
    let source = Source::new(&args.scene)?;
    let (min, max) = (args.min, args.max.min(source.largest()));
    if min == 0 || max == 0 {
        return Err("--min and --max must be at least 1 triangle".into());
    }
    if min > max {
        return Err(match source {
            Source::File(_) => format!(
                "--min {} is above the {max} triangles of {}",
                args.min, args.scene
            ),
            Source::Builtin(_) => format!("--min {} is above --max {}", args.min, args.max),
        });
    }
    if args.width == 0 || args.height == 0 || args.width > 1 << 13 || args.height > 1 << 13 {
        return Err(format!(
            "--width {} --height {}: each must be 1 to 8192",
            args.width, args.height
        ));
    }
    let rows: Vec<Entry> = crate::cli::rows_or(&args.structures, crate::cli::MAIN_ROWS)
        .iter()
        .map(|name| structures::find(entries, name.trim()))
        .collect::<Result<_, _>>()?;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(t) = args.threads {
        pool = pool.num_threads(t.max(1));
    }
    let pool = pool.build().map_err(|e| format!("thread pool: {e}"))?;
    let mut points = Vec::new();
    for n in ladder(min, max) {
        let (tris, camera) = source.at(n, args.width, args.height);
        let rays = camera.primary_rays(args.width, args.height);
        let sample: Vec<_> = rays
            .iter()
            .step_by((rays.len() / CHECKED).max(1))
            .copied()
            .collect();
        let mut reference: Option<Vec<Option<Hit>>> = None;
        for row in &rows {
            let before = memory::reset_peak();
            let start = Instant::now();
            let built = pool.install(|| (row.build)(&tris));
            let build_ms = start.elapsed().as_secs_f64() * 1e3;
            let peak = memory::peak().zip(before).map(|(p, b)| p.saturating_sub(b));
            // The checked sample first: it also warms the caches and the pool's threads.
            let (answers, _) =
                pool.install(|| structures::trace_counted(&*built, &sample, Query::Closest));
            let start = Instant::now();
            std::hint::black_box(
                pool.install(|| structures::trace_timed(&*built, &rays, Query::Closest)),
            );
            let trace_ns_per_ray = start.elapsed().as_secs_f64() * 1e9 / rays.len() as f64;
            let disagreements = match &reference {
                None => {
                    reference = Some(answers);
                    0
                }
                Some(r) => r
                    .iter()
                    .zip(&answers)
                    .filter(|(a, b)| !Hit::agree(**a, **b))
                    .count(),
            };
            points.push(Point {
                structure: row.name.clone(),
                triangles: tris.len(),
                build_ms,
                trace_ns_per_ray,
                structure_bytes: built.memory_bytes_dyn(),
                peak_build_bytes: peak,
                disagreements,
            });
        }
    }
    Ok(ScaleReport {
        scene: match source {
            Source::Builtin(kind) => kind.name.to_string(),
            Source::File(_) => args.scene.clone(),
        },
        threads: pool.current_num_threads(),
        rays: (args.width * args.height) as usize,
        points,
    })
}

fn mib(bytes: usize) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

impl ScaleReport {
    /// The ladder as a table, one line per row and size.
    pub fn table(&self) -> String {
        let mut s = format!(
            "scale ladder on {} ({} threads, {} primary rays per size; answers checked against \
             the first row on {CHECKED} of them)\n",
            self.scene, self.threads, self.rays
        );
        let _ = writeln!(
            s,
            "{:>10} {:<12} {:>9} {:>8} {:>9} {:>9} {:>10} {:>10} {:>9} {:>6}",
            "triangles",
            "structure",
            "build ms",
            "ns/tri",
            "ns/ray",
            "bytes/tri",
            "struct MiB",
            "peak MiB",
            "scratch×",
            "differ"
        );
        for p in &self.points {
            let peak = p
                .peak_build_bytes
                .map_or("n/a".to_string(), |b| format!("{:.1}", mib(b)));
            let scratch = p
                .scratch_ratio()
                .map_or("n/a".to_string(), |r| format!("{r:.2}"));
            let _ = writeln!(
                s,
                "{:>10} {:<12} {:>9.1} {:>8.1} {:>9.1} {:>9.1} {:>10.1} {:>10} {:>9} {:>6}",
                p.triangles,
                p.structure,
                p.build_ms,
                p.build_ns_per_triangle(),
                p.trace_ns_per_ray,
                p.bytes_per_triangle(),
                mib(p.structure_bytes),
                peak,
                scratch,
                p.disagreements
            );
        }
        s.push_str(
            "scratch× = (peak - structure) / (structure + input triangles): at most 1 when the \
             build's temporary memory stays within what it produces and what it is given\n",
        );
        s
    }

    /// The ladder as one JSON object.
    pub fn json(&self) -> String {
        let points: Vec<serde_json::Value> = self
            .points
            .iter()
            .map(|p| {
                serde_json::json!({
                    "structure": p.structure,
                    "triangles": p.triangles,
                    "build_ms": p.build_ms,
                    "build_ns_per_triangle": p.build_ns_per_triangle(),
                    "trace_ns_per_ray": p.trace_ns_per_ray,
                    "structure_bytes": p.structure_bytes,
                    "bytes_per_triangle": p.bytes_per_triangle(),
                    "peak_build_bytes": p.peak_build_bytes,
                    "scratch_ratio": p.scratch_ratio(),
                    "disagreements": p.disagreements,
                })
            })
            .collect();
        serde_json::json!({
            "scene": self.scene,
            "threads": self.threads,
            "rays": self.rays,
            "points": points,
        })
        .to_string()
    }

    /// The total of rays, over every size and row after the first, whose answer differed from
    /// the first row's.
    pub fn disagreements(&self) -> usize {
        self.points.iter().map(|p| p.disagreements).sum()
    }

    /// Writes the four curves against size, log-log, one line per row, as SVG.
    ///
    /// # Errors
    /// A one-line description of a file that cannot be written.
    pub fn svg(&self, path: &Path) -> Result<(), String> {
        crate::report::scale_chart(path, self)
    }
}

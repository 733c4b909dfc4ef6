//! Dynamic scenes: each structure follows a built-in animation frame by frame, by refitting
//! (structures that implement [`rt_core::Refit`]) and by rebuilding (all of them), so the cost
//! of each update, the trace time it leaves, and where refitting stops paying can be read side
//! by side.
//!
//! Per row, strategy and frame: the update time (the refit, or the build), the trace time of
//! the same primary rays (on all threads), their sum, and the SAH's predicted cost per ray
//! ([`rt_core::predicted_cost`]: expected nodes entered plus primitives tested), which shows a
//! refitted tree drifting from a rebuilt one as its primitives move apart. Every frame, every
//! strategy's answers are checked against brute force over that frame's triangles on a subset
//! of the rays.

use crate::structures::{self, Entry, Query};
use rt_core::DynAccel;
use rt_core::{Accel, BruteForce, Hit, Primitive, Ray, Triangle, predicted_cost};
use rt_scene::motion::Animation;
use rt_scene::scenes;
use std::fmt::Write as _;
use std::time::Instant;

/// Flags of `cargo xtask animate`.
#[derive(clap::Args, Debug, Clone)]
pub struct AnimateArgs {
    /// A built-in scene (optionally sized, `teapot:50k`) or a scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// The animation.
    #[arg(long, value_enum, default_value_t = AnimationKind::Explode)]
    pub animation: AnimationKind,
    /// Frames after the first (the first is the scene as loaded, which every row builds on).
    #[arg(long, default_value = "10", value_parser = crate::cli::count)]
    pub frames: usize,
    /// Comma-separated rows (as `compare` names them) [default: bvh,kdtree,grid,hgrid,octree].
    /// Rows that can refit (`bvh`, `bvh-binary`, ...) run twice: refitted and rebuilt.
    #[arg(short, long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// Primary rays per frame: width.
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    /// Primary rays per frame: height.
    #[arg(long, default_value_t = 384)]
    pub height: u32,
    /// Rays per frame whose answers are checked against brute force.
    #[arg(long, default_value = "2000", value_parser = crate::cli::count)]
    pub check_rays: usize,
    /// Update and trace each frame this many times and keep the fastest.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Threads for building and tracing [default: all cores].
    #[arg(short = 'j', long)]
    pub threads: Option<usize>,
    /// Print one JSON object instead of the tables.
    #[arg(long)]
    pub json: bool,
}

/// The built-in animations, as `--animation` names them.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimationKind {
    /// A wave travels through the mesh, one period over the frames.
    Wave,
    /// Every triangle flies outwards, spinning, to about twice the scene's size.
    Explode,
}

impl AnimationKind {
    /// The animation itself.
    pub fn animation(self) -> Animation {
        match self {
            AnimationKind::Wave => Animation::Wave,
            AnimationKind::Explode => Animation::Explode,
        }
    }

    /// Its name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            AnimationKind::Wave => "wave",
            AnimationKind::Explode => "explode",
        }
    }
}

/// How a row follows the animation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// The structure built on the first frame, refitted to each later one.
    Refit,
    /// A new structure built on every frame.
    Rebuild,
}

impl Strategy {
    /// `"refit"` or `"rebuild"`.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Refit => "refit",
            Strategy::Rebuild => "rebuild",
        }
    }
}

/// One row, strategy and frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// 0 for the first frame (the build every strategy starts from).
    pub frame: usize,
    /// The refit or the build, milliseconds (the fastest of the repeats).
    pub update_ms: f64,
    /// All primary rays, milliseconds (the fastest of the repeats).
    pub trace_ms: f64,
    /// The SAH's expected nodes entered plus primitives tested per ray through the root's box;
    /// `None` for a structure that does not describe its regions.
    pub sah: Option<f64>,
    /// Checked rays whose answer differs from brute force's.
    pub mismatches: usize,
}

impl Frame {
    /// Update plus trace, milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.update_ms + self.trace_ms
    }
}

/// One row followed with one strategy over every frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// The row's name.
    pub structure: String,
    /// Refit or rebuild.
    pub strategy: Strategy,
    /// Frame 0 first.
    pub frames: Vec<Frame>,
}

/// What `animate` measured.
#[derive(Clone, Debug)]
pub struct AnimateReport {
    /// The scene as given.
    pub scene: String,
    /// The animation's name.
    pub animation: String,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Primary rays traced per frame.
    pub rays: usize,
    /// Rays per frame checked against brute force.
    pub checked: usize,
    /// Threads used.
    pub threads: usize,
    /// Every row and strategy, in the order of `--structures`, refit before rebuild.
    pub tracks: Vec<Track>,
}

/// Runs the animation over `entries`.
///
/// # Errors
/// A one-line description of a bad flag, a scene that cannot be loaded, or a refit a
/// structure refused.
pub fn animate(args: &AnimateArgs, entries: &[Entry]) -> Result<AnimateReport, String> {
    let animation = args.animation.animation();
    if !(1..=1000).contains(&args.frames) {
        return Err(format!("--frames {}: expected 1 to 1000", args.frames));
    }
    if args.width == 0 || args.height == 0 || args.width > 1 << 13 || args.height > 1 << 13 {
        return Err(format!(
            "--width {} --height {}: each must be 1 to 8192",
            args.width, args.height
        ));
    }
    if !(1..=100).contains(&args.repeats) {
        return Err(format!("--repeats {}: expected 1 to 100", args.repeats));
    }
    let rows: Vec<Entry> = crate::cli::rows_or(&args.structures, crate::cli::MAIN_ROWS)
        .iter()
        .map(|name| structures::find(entries, name.trim()))
        .collect::<Result<_, _>>()?;
    let (_, tris) = crate::scene::load_scene(&args.scene)?;
    if !tris.iter().any(|t| t.is_valid()) {
        return Err(format!(
            "--scene {}: no valid triangle to animate",
            args.scene
        ));
    }
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(t) = args.threads {
        pool = pool.num_threads(t.max(1));
    }
    let pool = pool.build().map_err(|e| format!("thread pool: {e}"))?;

    let frames: Vec<Vec<Triangle>> = (0..=args.frames)
        .map(|f| animation.frame(&tris, f, args.frames))
        .collect();
    // One camera for every frame, framing the whole animation, so each frame traces the same
    // rays and the times compare.
    let bounds = rt_core::valid_bounds(frames.iter().flatten());
    let rays = scenes::camera_for(&args.scene, &bounds, args.width, args.height)
        .primary_rays(args.width, args.height);
    let checked: Vec<Ray> = rays
        .iter()
        .step_by((rays.len() / args.check_rays.max(1)).max(1))
        .take(args.check_rays)
        .copied()
        .collect();
    let expected: Vec<Vec<Option<Hit>>> = frames
        .iter()
        .map(|f| {
            let reference = BruteForce::build(f, &());
            pool.install(|| reference_answers(&reference, &checked))
        })
        .collect();

    let check = |s: &dyn DynAccel<Triangle>, f: usize, update_ms: f64| {
        measure(&pool, s, f, update_ms, &rays, &checked, &expected[f], args)
    };
    let mut tracks = Vec::new();
    for row in &rows {
        if let Some(build) = &row.build_refittable {
            let mut s = pool.install(|| build(&frames[0]));
            let mut track = Vec::new();
            for (f, frame) in frames.iter().enumerate() {
                let update_ms = fastest_ms(args.repeats, || {
                    if f == 0 {
                        s = pool.install(|| build(frame));
                        return Ok(());
                    }
                    s.refit(frame).map_err(|e| {
                        format!(
                            "{} refused frame {f} of {}: {e}",
                            row.name,
                            args.animation.name()
                        )
                    })
                })?;
                track.push(check(&*s, f, update_ms));
            }
            tracks.push(Track {
                structure: row.name.clone(),
                strategy: Strategy::Refit,
                frames: track,
            });
        }
        let mut track = Vec::new();
        for (f, frame) in frames.iter().enumerate() {
            let mut s = None;
            let update_ms = fastest_ms(args.repeats, || {
                s = Some(pool.install(|| (row.build)(frame)));
                Ok(())
            })?;
            let s = s.expect("at least one repeat");
            track.push(check(&*s, f, update_ms));
        }
        tracks.push(Track {
            structure: row.name.clone(),
            strategy: Strategy::Rebuild,
            frames: track,
        });
    }
    Ok(AnimateReport {
        scene: args.scene.clone(),
        animation: args.animation.name().to_owned(),
        triangles: tris.len(),
        rays: rays.len(),
        checked: checked.len(),
        threads: pool.current_num_threads(),
        tracks,
    })
}

/// The fastest of `repeats` runs of `step`, in milliseconds.
fn fastest_ms(repeats: usize, mut step: impl FnMut() -> Result<(), String>) -> Result<f64, String> {
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let start = Instant::now();
        step()?;
        best = best.min(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(best)
}

/// Brute force's closest hits, on the current pool.
fn reference_answers(reference: &BruteForce<Triangle>, rays: &[Ray]) -> Vec<Option<Hit>> {
    use rayon::prelude::*;
    rays.par_iter().map(|r| reference.intersect(r)).collect()
}

/// Traces frame `f` through `s` (fastest of the repeats), checks it and predicts its cost.
#[allow(clippy::too_many_arguments)]
fn measure(
    pool: &rayon::ThreadPool,
    s: &dyn DynAccel<Triangle>,
    f: usize,
    update_ms: f64,
    rays: &[Ray],
    checked: &[Ray],
    expected: &[Option<Hit>],
    args: &AnimateArgs,
) -> Frame {
    let (answers, _) = pool.install(|| structures::trace_counted(&*s, checked, Query::Closest));
    let mismatches = answers
        .iter()
        .zip(expected)
        .filter(|(a, b)| !Hit::agree(**a, **b))
        .count();
    let trace_ms = fastest_ms(args.repeats, || {
        std::hint::black_box(pool.install(|| structures::trace_timed(&*s, rays, Query::Closest)));
        Ok(())
    })
    .unwrap_or(f64::INFINITY);
    let sah = predicted_cost(&s.regions_dyn()).map(|c| c.visits + c.tests);
    Frame {
        frame: f,
        update_ms,
        trace_ms,
        sah,
        mismatches,
    }
}

impl AnimateReport {
    /// Checked rays, over every row, strategy and frame, whose answer differed from brute
    /// force's.
    pub fn mismatches(&self) -> usize {
        self.tracks
            .iter()
            .flat_map(|t| &t.frames)
            .map(|f| f.mismatches)
            .sum()
    }

    /// The rebuilt track of the row `structure`.
    fn rebuilt(&self, structure: &str) -> Option<&Track> {
        self.tracks
            .iter()
            .find(|t| t.structure == structure && t.strategy == Strategy::Rebuild)
    }

    /// For a refitted track: the first frame after the first whose update plus trace took
    /// longer than rebuilding's did, if any.
    pub fn refit_stops_paying(&self, track: &Track) -> Option<usize> {
        let rebuilt = self.rebuilt(&track.structure)?;
        track
            .frames
            .iter()
            .zip(&rebuilt.frames)
            .skip(1)
            .find(|(r, b)| r.total_ms() > b.total_ms())
            .map(|(r, _)| r.frame)
    }

    /// One table per row: each strategy's update, trace, total and SAH per frame, and for a
    /// refitted row its SAH over the rebuilt one's.
    pub fn table(&self) -> String {
        let mut s = format!(
            "animate: {} on {} ({} triangles), {} frames after the first, {} primary rays per \
             frame, {} threads; every frame checked against brute force on {} rays\n",
            self.animation,
            self.scene,
            self.triangles,
            self.tracks.first().map_or(0, |t| t.frames.len() - 1),
            self.rays,
            self.threads,
            self.checked
        );
        let sah = |f: &Frame| f.sah.map_or("n/a".to_string(), |c| format!("{c:.1}"));
        for track in &self.tracks {
            let refit = track.strategy == Strategy::Refit;
            if !refit
                && self
                    .tracks
                    .iter()
                    .any(|t| t.structure == track.structure && t.strategy == Strategy::Refit)
            {
                continue; // printed beside its refitted track
            }
            let _ = writeln!(s, "\n{}", track.structure);
            let rebuilt = if refit {
                self.rebuilt(&track.structure)
            } else {
                None
            };
            let _ = write!(
                s,
                "{:>5} | {:>9} {:>9} {:>9} {:>7}",
                "frame",
                format!("{} ms", track.strategy.name()),
                "trace ms",
                "total ms",
                "SAH"
            );
            if rebuilt.is_some() {
                let _ = write!(
                    s,
                    " | {:>10} {:>9} {:>9} {:>7} | {:>9}",
                    "rebuild ms", "trace ms", "total ms", "SAH", "SAH ratio"
                );
            }
            let _ = writeln!(s, " | {:>6}", "differ");
            for (i, f) in track.frames.iter().enumerate() {
                let _ = write!(
                    s,
                    "{:>5} | {:>9.2} {:>9.2} {:>9.2} {:>7}",
                    f.frame,
                    f.update_ms,
                    f.trace_ms,
                    f.total_ms(),
                    sah(f)
                );
                let mut differ = f.mismatches;
                if let Some(b) = rebuilt.map(|r| &r.frames[i]) {
                    let ratio = f
                        .sah
                        .zip(b.sah)
                        .map_or("n/a".to_string(), |(a, b)| format!("{:.2}", a / b));
                    let _ = write!(
                        s,
                        " | {:>10.2} {:>9.2} {:>9.2} {:>7} | {:>9}",
                        b.update_ms,
                        b.trace_ms,
                        b.total_ms(),
                        sah(b),
                        ratio
                    );
                    differ += b.mismatches;
                }
                let _ = writeln!(s, " | {differ:>6}");
            }
            if refit {
                let _ = match self.refit_stops_paying(track) {
                    Some(f) => writeln!(
                        s,
                        "refitting pays until frame {f}, where refit and trace first take longer than a rebuild and its trace"
                    ),
                    None => writeln!(s, "refitting pays in every frame"),
                };
            }
        }
        s
    }

    /// The report as one JSON object.
    pub fn json(&self) -> String {
        let tracks: Vec<serde_json::Value> = self
            .tracks
            .iter()
            .map(|t| {
                let frames: Vec<serde_json::Value> = t
                    .frames
                    .iter()
                    .map(|f| {
                        serde_json::json!({
                            "frame": f.frame,
                            "update_ms": f.update_ms,
                            "trace_ms": f.trace_ms,
                            "total_ms": f.total_ms(),
                            "sah": f.sah,
                            "mismatches": f.mismatches,
                        })
                    })
                    .collect();
                serde_json::json!({
                    "structure": t.structure,
                    "strategy": t.strategy.name(),
                    "refit_stops_paying": (t.strategy == Strategy::Refit)
                        .then(|| self.refit_stops_paying(t))
                        .flatten(),
                    "frames": frames,
                })
            })
            .collect();
        serde_json::json!({
            "scene": self.scene,
            "animation": self.animation,
            "triangles": self.triangles,
            "rays": self.rays,
            "checked": self.checked,
            "threads": self.threads,
            "mismatches": self.mismatches(),
            "tracks": tracks,
        })
        .to_string()
    }
}

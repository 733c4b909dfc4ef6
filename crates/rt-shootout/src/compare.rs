//! `cargo xtask compare`: the structure shootout.
//!
//! Builds every selected structure on one scene, traces the same rays through each, and checks
//! every answer: against brute force on a random subset of the rays (all of them when there are
//! few), and against each other on all rays, with brute force settling every ray on which the
//! structures disagree. Reports build time, memory, tree shape, traversal cost per ray and
//! speed, with brute force as the baseline row.

use crate::structures::{self, Query};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rt_bvh::Bvh;
use rt_core::DynAccel;
use rt_core::{Aabb, Hit, PredictedCost, Primitive, Ray, Rng, Triangle, predicted_cost};
use rt_scene::raygen;
use rt_scene::scenes::{self, BUILTIN_SCENES};
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

mod points;

/// Which query `compare` measures.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum QueryKind {
    /// Rays (`--rays` says which).
    #[default]
    Rays,
    /// Closest-point queries: the primitive nearest to each of `--points` points.
    ClosestPoint,
}

/// Which rays to trace.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// One ray per pixel from a pinhole camera framing the scene.
    Primary,
    /// Random origins inside the scene box, random directions.
    Incoherent,
    /// Occlusion rays from the primary hits to a point light (any-hit queries).
    Shadow,
}

#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// A built-in scene name (listed below) or the path of an .obj, .ply, .gltf or .glb file; repeat the flag to run
    /// several scenes in turn.
    #[arg(long = "scene", default_value = "sphereflake", value_name = "SCENE")]
    pub scenes: Vec<String>,
    /// The scene being measured (one of `scenes`, set by `run`).
    #[arg(skip)]
    pub scene: String,
    /// Also write a report into DIR: `report.md` with SVG charts of every scene's figures and a
    /// heatmap strip per scene (with `--grade`: `grade.md` and `grade.json`).
    #[arg(short, long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Grade this row instead: run the conformance kit on it (every scene passed or failed, the
    /// first failing ray of each), then the shootout against `--structures` (default bvh,
    /// kdtree, grid), and write `grade.json` and `grade.md` into `--out DIR` (default `grade`).
    #[arg(long, value_name = "ROW")]
    pub grade: Option<String>,
    /// Which query to measure: rays, or closest points (nearest primitive to a point).
    #[arg(long, value_enum, default_value_t = QueryKind::Rays)]
    pub query: QueryKind,
    /// Closest-point queries: how many points (half uniform in the scene box grown by a quarter
    /// on every side, half within 2% of its diagonal from the surface).
    #[arg(long, default_value = "100k", value_parser = crate::cli::count)]
    pub points: usize,
    /// Closest-point queries: the largest distance searched [default: no limit].
    #[arg(long, value_name = "D")]
    pub max_distance: Option<f32>,
    /// Trace a field of N instances of the scene instead (on a square grid, each rotated,
    /// scaled unevenly, every seventh mirrored): a two-level scene. Each row's structure is
    /// built once over the mesh and instanced under rt-bvh's `Instances`; brute force visits
    /// every instance. Rays only.
    #[arg(long, value_name = "N", value_parser = crate::cli::count)]
    pub instances: Option<usize>,
    /// Which rays to trace [default: primary].
    #[arg(long, value_enum)]
    pub rays: Option<RayKind>,
    /// Image width for primary and shadow rays (incoherent: width × height rays).
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Image height for primary and shadow rays.
    #[arg(long, default_value_t = 768)]
    pub height: u32,
    /// Comma-separated rows to run (listed below); brute force is always the baseline.
    /// [default: every row]
    #[arg(short, long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// Threads for building and tracing [default: all cores]; structures that build in parallel
    /// use them.
    #[arg(short = 'j', long)]
    pub threads: Option<usize>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Replay rays from a file, one per line: `ox oy oz dx dy dz [tmin tmax]` (`#` comments).
    /// Closest-hit queries, or any-hit with `--rays shadow`. The JSON then carries every answer.
    #[arg(long)]
    pub rays_file: Option<PathBuf>,
    /// How many rays brute force checks (a random subset; all rays if there are fewer).
    /// [default: 20,000; 1,000 with --instances, where one brute-force ray tests every
    /// triangle of each instance whose box it enters]
    #[arg(long, value_parser = crate::cli::count)]
    pub check_rays: Option<usize>,
    /// Seed for incoherent rays and for the checked subset.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Timed builds and trace passes per structure, the fastest reported (brute force: its one
    /// counted pass).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
}

/// The text after `--help`: built-in scenes and structure rows.
pub fn after_help(entries: &[structures::Entry]) -> String {
    let mut s = String::from(
        "Built-in scenes (add a size for about that many triangles: `random-soup:10M`, \
         `terrain:500k`):\n",
    );
    for b in BUILTIN_SCENES {
        let _ = writeln!(s, "  {:<14} {}", b.name, b.description);
    }
    s.push_str("\nStructure rows:\n");
    for e in entries {
        let _ = writeln!(s, "  {}", e.name);
    }
    s.push_str("\nExit status: 0 when every answer agrees, 1 on any mismatch, 2 on bad input.");
    s
}

/// One row of the report.
#[derive(Debug)]
pub struct Row {
    pub name: String,
    pub build_ms: f64,
    pub memory_bytes: usize,
    pub nodes: usize,
    pub leaves: usize,
    pub empty_leaves: usize,
    pub max_depth: usize,
    pub avg_leaf_prims: f64,
    pub prim_refs: usize,
    pub duplication: f64,
    pub rays_traced: usize,
    pub hits: usize,
    pub mismatches: usize,
    pub avg_visits: f64,
    pub avg_prim_tests: f64,
    /// Primitive tests a mailbox skipped, per ray (0 for structures without one).
    pub avg_mailbox_skips: f64,
    /// The structure's own named figures ([`BuildStats::extra`](rt_core::BuildStats::extra)).
    pub extra: Vec<(&'static str, f64)>,
    pub mrays_per_s: f64,
    pub speedup: f64,
    /// The SAH's expected visits and tests per traced ray (see [`predicted_per_ray`]), for
    /// structures that describe their regions.
    pub predicted: Option<PredictedCost>,
    answers: Vec<Option<Hit>>,
}

/// The cost the surface area heuristic predicts per traced ray: its expectation for a line
/// through the structure's box ([`predicted_cost`]), times the share of `rays` that enter the
/// scene box (`bounds`), so that it compares with the measured averages over all rays.
pub fn predicted_per_ray(
    s: &dyn DynAccel<Triangle>,
    rays: &[Ray],
    bounds: &Aabb,
) -> Option<PredictedCost> {
    let per_line = predicted_cost(&s.regions_dyn())?;
    let entering = rays
        .iter()
        .filter(|r| bounds.intersect(r, r.t_max).is_some())
        .count() as f64
        / rays.len().max(1) as f64;
    Some(PredictedCost {
        visits: per_line.visits * entering,
        tests: per_line.tests * entering,
    })
}

/// A ray on which a structure disagreed with brute force.
#[derive(Debug)]
pub struct Disagreement {
    pub structure: String,
    pub ray_index: usize,
    pub ray: Ray,
    pub expected: Option<Hit>,
    pub got: Option<Hit>,
}

/// Everything `compare` measured.
#[derive(Debug)]
pub struct Report {
    pub scene: String,
    pub triangles: usize,
    pub valid_triangles: usize,
    pub ray_kind: &'static str,
    pub rays: usize,
    pub threads: usize,
    pub checked_rays: usize,
    pub rows: Vec<Row>,
    pub disagreements: Vec<Disagreement>,
    /// Closest-point queries on which a row disagreed with brute force (the first few).
    pub point_disagreements: Vec<points::PointDisagreement>,
    pub per_ray_answers: bool,
}

impl Report {
    /// Mismatches over every row.
    pub fn total_mismatches(&self) -> usize {
        self.rows.iter().map(|r| r.mismatches).sum()
    }

    /// The share of the rays that hit the scene (any-hit rays: that are occluded), from the first
    /// row that traced them all (brute force traces only the checked ones); `None` for
    /// closest-point queries or when no row traced. A view where most rays miss times little but
    /// the call, so the share belongs beside every speed.
    pub fn hit_share(&self) -> Option<f64> {
        if self.ray_kind == points::KIND {
            return None;
        }
        self.rows
            .iter()
            .find(|row| row.rays_traced == self.rays && row.rays_traced > 0)
            .map(|row| row.hits as f64 / row.rays_traced as f64)
    }
}

/// Runs the comparison of the rows among `entries` that `args` selects (all by default) on each
/// scene, and prints the report (table or JSON) to stdout; disagreements go to stderr.
///
/// # Errors
/// One line describing bad input: unknown scene or structure, unreadable or malformed file,
/// a scene without valid triangles.
pub fn run(args: &Args, entries: &[structures::Entry]) -> Result<Vec<Report>, String> {
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err("--threads must be at least 1".into());
    }
    if let Some(dir) = &args.out {
        if args.query == QueryKind::ClosestPoint {
            return Err(
                "--out writes a report of ray queries only; leave it out with --query closest-point".into(),
            );
        }
        crate::report::prepare(dir)?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
    // Every scene is loaded before any is measured, so a bad one fails at once.
    for scene in &args.scenes {
        load_scene(scene)?;
    }
    let mut reports = Vec::new();
    for scene in &args.scenes {
        let args = Args {
            scene: scene.clone(),
            ..args.clone()
        };
        let entries = select_entries(entries, &args.structures)?;
        let report = match args.query {
            QueryKind::Rays => pool.install(|| measure(&args, threads, entries))?,
            QueryKind::ClosestPoint => pool.install(|| points::measure(&args, threads, entries))?,
        };
        if args.json {
            println!("{}", to_json(&report));
        } else {
            if !reports.is_empty() {
                println!();
            }
            print!("{}", to_table(&report));
        }
        if !report.disagreements.is_empty() || !report.point_disagreements.is_empty() {
            eprint!("{}", describe_disagreements(&report, &args));
        }
        reports.push(report);
    }
    if let Some(dir) = &args.out {
        let written = pool.install(|| crate::report::write(dir, &reports, args, entries))?;
        if !args.json {
            println!("\nwrote {}", written.display());
        }
    }
    Ok(reports)
}

fn select_entries(
    entries: &[structures::Entry],
    names: &[String],
) -> Result<Vec<structures::Entry>, String> {
    let all = entries.to_vec();
    if names.is_empty() || names.iter().any(|n| n == "all") {
        return Ok(all);
    }
    let known: Vec<String> = all.iter().map(|e| e.name.clone()).collect();
    let mut all: Vec<Option<structures::Entry>> = all.into_iter().map(Some).collect();
    let mut out = Vec::new();
    for name in names {
        if name == "brute-force" {
            continue;
        }
        let Some(i) = known.iter().position(|k| k == name) else {
            return Err(format!(
                "unknown structure `{name}` (known: {}, all)",
                known.join(", ")
            ));
        };
        if let Some(e) = all[i].take() {
            out.push(e);
        }
    }
    Ok(out)
}

/// The triangles of a built-in scene or a scene file (OBJ, PLY, glTF), or a one-line error.
pub fn load_scene(spec: &str) -> Result<(String, Vec<Triangle>), String> {
    if let Some((scene, size)) = scenes::resolve(spec)? {
        return Ok((spec.to_string(), scene.make(size).triangles()));
    }
    let path = Path::new(spec);
    if !path.exists() && !spec.contains(['/', '\\', '.']) {
        let names: Vec<&str> = BUILTIN_SCENES.iter().map(|s| s.name).collect();
        return Err(format!(
            "no built-in scene or file named `{spec}` (built-in scenes: {}; any of them with a \
             size, such as `random-soup:1M`)",
            names.join(", ")
        ));
    }
    let mesh = rt_scene::load_mesh(path).map_err(|e| e.to_string())?;
    Ok((spec.to_string(), mesh.triangles()))
}

struct Progress(ProgressBar);

impl Progress {
    fn new(steps: u64, visible: bool) -> Self {
        let bar = ProgressBar::with_draw_target(
            Some(steps),
            if visible {
                ProgressDrawTarget::stderr()
            } else {
                ProgressDrawTarget::hidden()
            },
        );
        if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} ({elapsed})") {
            bar.set_style(style);
        }
        if visible {
            // Brute force can take seconds in one step; keep the elapsed time moving.
            bar.enable_steady_tick(Duration::from_millis(250));
        }
        Self(bar)
    }
    fn step(&self, msg: String) {
        self.0.set_message(msg);
        self.0.tick();
    }
    fn done(&self) {
        self.0.inc(1);
    }
}

fn measure(args: &Args, threads: usize, entries: Vec<structures::Entry>) -> Result<Report, String> {
    let source = Source::load(args)?;
    let scene = source.label.clone();
    if source.valid == 0 {
        return Err(format!(
            "{scene}: no valid triangles (all {} are degenerate or non-finite)",
            source.mesh.len()
        ));
    }
    let bounds = source.bounds;
    if args.width == 0 || args.height == 0 {
        return Err("--width and --height must be at least 1".into());
    }

    let (rays, ray_kind, query) = make_rays(args, &source)?;
    if rays.is_empty() {
        return Err(format!("no rays to trace ({ray_kind} rays on {scene})"));
    }
    let progress = Progress::new(
        2 * entries.len() as u64 + 2, // build and trace per row, brute force, cross-check
        std::io::stdout().is_terminal() && !args.json,
    );

    let check = args.check_rays.unwrap_or(if source.field.is_some() {
        1_000
    } else {
        20_000
    });
    let subset = checked_subset(rays.len(), check, args.seed);
    let subset_rays: Vec<Ray> = subset.iter().map(|&i| rays[i]).collect();

    let mut rows = Vec::new();
    let mut built: Vec<Arc<dyn DynAccel<Triangle>>> = Vec::new();
    for entry in &entries {
        progress.step(format!("building {}", entry.name));
        let (s, build_ms) = build_fastest(|| source.build(entry), args.repeats)?;
        progress.done();
        progress.step(format!("tracing {}", entry.name));
        let mut row = trace_row(
            &entry.name,
            s.as_ref(),
            build_ms,
            &rays,
            query,
            args.repeats,
        );
        row.predicted = predicted_per_ray(s.as_ref(), &rays, &bounds);
        rows.push(row);
        built.push(s);
        progress.done();
    }

    progress.step(format!("brute force on {} rays", subset_rays.len()));
    let brute_entry = structures::brute_force();
    let t = Instant::now();
    let brute = source.build(&brute_entry)?;
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    // One pass for brute force: its counters cost nothing next to N primitive tests per ray, so
    // the counted pass is also the timed one.
    let mut brute_row = trace_row(
        &brute_entry.name,
        brute.as_ref(),
        build_ms,
        &subset_rays,
        query,
        0,
    );
    progress.done();

    progress.step("cross-checking".into());
    let agree = |a: Option<Hit>, b: Option<Hit>| match query {
        Query::Closest => Hit::agree(a, b),
        Query::Any => a.is_some() == b.is_some(),
    };
    let mut disagreements = Vec::new();
    let mut record = |rows: &mut [Row], ray_index: usize, expected: Option<Hit>| {
        for row in rows.iter_mut() {
            let got = row.answers[ray_index];
            if !agree(expected, got) {
                row.mismatches += 1;
                if disagreements.len() < 8 {
                    disagreements.push(Disagreement {
                        structure: row.name.clone(),
                        ray_index,
                        ray: rays[ray_index],
                        expected,
                        got,
                    });
                }
            }
        }
    };
    let mut in_subset = vec![false; rays.len()];
    for (k, &i) in subset.iter().enumerate() {
        in_subset[i] = true;
        record(&mut rows, i, brute_row.answers[k]);
    }
    // Outside the subset, brute force settles every ray on which the structures disagree.
    let mut settled = 0;
    for i in (0..rays.len()).filter(|&i| !in_subset[i]) {
        let first = rows.first().map(|r| r.answers[i]);
        if rows
            .iter()
            .any(|r| first.is_some_and(|f| !agree(f, r.answers[i])))
        {
            settled += 1;
            record(&mut rows, i, structures::answer(&*brute, &rays[i], query));
        }
    }
    progress.done();
    progress.0.finish_and_clear();

    let base = brute_row.mrays_per_s;
    brute_row.speedup = 1.0;
    for r in &mut rows {
        r.speedup = r.mrays_per_s / base;
    }
    let mut all_rows = vec![brute_row];
    all_rows.extend(rows);
    Ok(Report {
        scene,
        triangles: source.triangles,
        valid_triangles: source.valid,
        ray_kind,
        rays: rays.len(),
        threads,
        checked_rays: subset.len() + settled,
        rows: all_rows,
        disagreements,
        point_disagreements: Vec::new(),
        per_ray_answers: args.rays_file.is_some(),
    })
}

/// Builds a row `repeats` times (at least once) with `build` and keeps the last structure with
/// the fastest build's time in milliseconds. Builds are timed like traces, since a single build
/// on a shared host can be 20% off (the structure is the same every time).
fn build_fastest(
    build: impl Fn() -> Result<Arc<dyn DynAccel<Triangle>>, String>,
    repeats: u32,
) -> Result<(Arc<dyn DynAccel<Triangle>>, f64), String> {
    let mut build_ms = f64::INFINITY;
    let mut s = None;
    for _ in 0..repeats.max(1) {
        drop(s.take());
        let t = Instant::now();
        let built = build()?;
        build_ms = build_ms.min(t.elapsed().as_secs_f64() * 1e3);
        s = Some(built);
    }
    Ok((s.expect("built at least once"), build_ms))
}

/// What the rows are built over: a scene's triangles, or a field of instances of them
/// (`--instances`).
pub(crate) struct Source {
    /// The scene's name as the report shows it.
    pub label: String,
    /// The scene's triangles (the one mesh every instance shares, for a field).
    pub mesh: std::sync::Arc<[Triangle]>,
    /// The field's transforms, if it is one.
    pub field: Option<Vec<rt_core::glam::Affine3A>>,
    /// Triangles in the scene, every instance counted.
    pub triangles: usize,
    /// Valid triangles, every instance counted.
    pub valid: usize,
    /// The box around the valid triangles (in the world).
    pub bounds: Aabb,
}

impl Source {
    /// The scene `args.scene`, fielded if `args.instances` asks for it.
    pub(crate) fn load(args: &Args) -> Result<Self, String> {
        let (scene, tris) = load_scene(&args.scene)?;
        let valid = tris.iter().filter(|t| t.is_valid()).count();
        let bounds = tris
            .iter()
            .filter(|t| t.is_valid())
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let mesh: std::sync::Arc<[Triangle]> = tris.into();
        let Some(count) = args.instances else {
            return Ok(Self {
                label: scene,
                triangles: mesh.len(),
                mesh,
                field: None,
                valid,
                bounds,
            });
        };
        if !(1..=1_000_000).contains(&count) {
            return Err(format!(
                "--instances must be from 1 to 1000000, not {count}"
            ));
        }
        let field = scenes::instance_field(&bounds, count, args.seed);
        let mut world = Aabb::EMPTY;
        for xf in &field {
            let t = rt_core::InstanceTransform::new(*xf).map_err(|e| e.to_string())?;
            world = world.union(t.world_bounds(&bounds).0);
        }
        Ok(Self {
            label: format!("{scene} × {count}"),
            triangles: mesh.len() * count,
            valid: valid * count,
            mesh,
            field: Some(field),
            bounds: world,
        })
    }

    /// `entry`'s structure over the scene: built over the triangles, or built once over the mesh
    /// and instanced under rt-bvh's `Instances` (brute force: the linear reference, which
    /// visits every instance).
    pub(crate) fn build(
        &self,
        entry: &structures::Entry,
    ) -> Result<Arc<dyn DynAccel<Triangle>>, String> {
        let Some(field) = &self.field else {
            return Ok((entry.build)(&self.mesh));
        };
        Ok(if entry.name == "brute-force" {
            Arc::new(
                structures::Field::<rt_core::LinearInstances<Triangle>>::new(
                    self.mesh.clone(),
                    field,
                    &entry.build,
                )?,
            )
        } else {
            Arc::new(structures::Field::<rt_bvh::Instances<Triangle>>::new(
                self.mesh.clone(),
                field,
                &entry.build,
            )?)
        })
    }

    /// The world-space triangle a row's hit names (`instance · mesh length + primitive` in a
    /// field).
    fn world_triangle(&self, prim: u32) -> Triangle {
        let n = self.mesh.len();
        match &self.field {
            None => self.mesh[prim as usize],
            Some(field) => {
                let (k, i) = (prim as usize / n, prim as usize % n);
                let t = self.mesh[i];
                let w = |v| field[k].transform_point3(v);
                Triangle::new(w(t.v0), w(t.v1), w(t.v2))
            }
        }
    }
}

/// The queries brute force checks: every one when there are at most `check`, else a
/// reproducible random sample of `check`, in increasing order.
fn checked_subset(len: usize, check: usize, seed: u64) -> Vec<usize> {
    if len <= check {
        return (0..len).collect();
    }
    let mut idx: Vec<usize> = (0..len).collect();
    let mut rng = Rng::new(seed ^ 0x5eed_c4ec);
    for i in 0..check {
        let j = i + rng.below((len - i) as u32) as usize;
        idx.swap(i, j);
    }
    idx.truncate(check);
    idx.sort_unstable();
    idx
}

fn make_rays(args: &Args, source: &Source) -> Result<(Vec<Ray>, &'static str, Query), String> {
    let kind = args.rays.unwrap_or(RayKind::Primary);
    let query = if kind == RayKind::Shadow {
        Query::Any
    } else {
        Query::Closest
    };
    if let Some(path) = &args.rays_file {
        let rays = raygen::read_rays_file(path).map_err(|e| e.to_string())?;
        return Ok((rays, "file", query));
    }
    let bounds = &source.bounds;
    let camera = if source.field.is_some() {
        // A field lies flat on the ground: seen from above at 45°, it fills the picture.
        rt_scene::Camera::framing_from(
            bounds,
            rt_core::glam::Vec3::new(0.3, 1.5, 1.0),
            args.width,
            args.height,
        )
    } else {
        scenes::camera_for(&args.scene, bounds, args.width, args.height)
    };
    let shared_kind = match kind {
        RayKind::Primary => raygen::RayKind::Primary,
        RayKind::Incoherent => raygen::RayKind::Incoherent,
        RayKind::Shadow => raygen::RayKind::Shadow,
    };
    // Shadow rays start at the primary hits, found by a SAH BVH (any correct structure finds
    // the same ones); they need only the triangles hit, in the world.
    let rays = match shared_kind {
        raygen::RayKind::Shadow => {
            let primary = camera.primary_rays(args.width, args.height);
            let entry = structures::entries_of::<Bvh<Triangle>, Bvh<rt_core::Shape>>()
                .into_iter()
                .find(|e| e.name == "bvh-binary")
                .expect("rt-bvh has a binary preset");
            let s = source.build(&entry)?;
            let mut hit_tris = Vec::new();
            let hits: Vec<Option<Hit>> = primary
                .iter()
                .map(|r| {
                    structures::answer(&*s, r, Query::Closest).map(|h| {
                        hit_tris.push(source.world_triangle(h.prim));
                        Hit {
                            prim: hit_tris.len() as u32 - 1,
                            ..h
                        }
                    })
                })
                .collect();
            raygen::shadow_rays(&primary, &hits, &hit_tris, raygen::default_light(bounds))
        }
        raygen::RayKind::Primary => camera.primary_rays(args.width, args.height),
        raygen::RayKind::Incoherent => raygen::incoherent_rays(
            bounds,
            args.width as usize * args.height as usize,
            args.seed,
        ),
    };
    Ok((rays, shared_kind.name(), query))
}

fn trace_row(
    name: &str,
    s: &dyn DynAccel<Triangle>,
    build_ms: f64,
    rays: &[Ray],
    query: Query,
    repeats: u32,
) -> Row {
    let t = Instant::now();
    let (answers, counters) = structures::trace_counted(s, rays, query);
    let mut best = t.elapsed();
    let mut hits = answers.iter().filter(|a| a.is_some()).count();
    if repeats > 0 {
        best = Duration::MAX;
    }
    for _ in 0..repeats {
        let t = Instant::now();
        hits = structures::trace_timed(s, rays, query);
        best = best.min(t.elapsed());
    }
    let mut row = Row::measured(name, s, build_ms, rays.len(), hits, counters, best);
    row.answers = answers;
    row
}

impl Row {
    /// A row's figures from its counted pass (`counters`, `hits` answers found) and its best
    /// time over `queries` queries; the answers are left for the caller.
    fn measured(
        name: &str,
        s: &dyn DynAccel<Triangle>,
        build_ms: f64,
        queries: usize,
        hits: usize,
        counters: rt_core::Counters,
        best: Duration,
    ) -> Self {
        let stats = s.build_stats_dyn();
        let n = queries.max(1) as f64;
        Row {
            name: name.to_string(),
            build_ms,
            memory_bytes: s.memory_bytes_dyn(),
            nodes: stats.nodes,
            leaves: stats.leaves,
            empty_leaves: stats.empty_leaves,
            max_depth: stats.max_depth,
            avg_leaf_prims: stats.avg_prims_per_leaf(),
            prim_refs: stats.prim_refs,
            duplication: stats.duplication(),
            rays_traced: queries,
            hits,
            mismatches: 0,
            avg_visits: counters.node_visits as f64 / n,
            avg_prim_tests: counters.prim_tests as f64 / n,
            avg_mailbox_skips: counters.mailbox_skips as f64 / n,
            extra: stats.extra,
            mrays_per_s: queries as f64 / best.as_secs_f64().max(1e-9) / 1e6,
            speedup: 0.0,
            predicted: None,
            answers: Vec::new(),
        }
    }
}

fn to_table(r: &Report) -> String {
    let mut s = String::new();
    let (unit, units) = if r.ray_kind == points::KIND {
        ("query", "closest-point queries")
    } else {
        ("ray", "rays")
    };
    if r.ray_kind == points::KIND {
        let _ = writeln!(
            s,
            "scene {} ({} triangles, {} valid), {} {units}, {} threads; {} checked against brute force",
            r.scene, r.triangles, r.valid_triangles, r.rays, r.threads, r.checked_rays
        );
    } else {
        let hits = r
            .hit_share()
            .map_or(String::new(), |h| format!(" ({:.1}% hit)", 100.0 * h));
        let _ = writeln!(
            s,
            "scene {} ({} triangles, {} valid), {} {} rays{hits}, {} threads; {} rays checked against brute force",
            r.scene, r.triangles, r.valid_triangles, r.rays, r.ray_kind, r.threads, r.checked_rays
        );
    }
    let _ = writeln!(
        s,
        "\nCost and speed: build time, memory kept, and per {unit} the nodes or cells entered and the \
         primitives tested; speedup over brute force"
    );
    // The name column fits the longest row name.
    let w = r
        .rows
        .iter()
        .map(|row| row.name.len())
        .max()
        .unwrap_or(0)
        .max("structure".len());
    let _ = writeln!(
        s,
        "{:<w$} {:>9} {:>11} {:>12} {:>12} {:>11} {:>9} {:>10}",
        "structure",
        "build ms",
        "memory MiB",
        format!("visits/{unit}"),
        format!("tests/{unit}"),
        if unit == "ray" {
            "Mrays/s"
        } else {
            "Mqueries/s"
        },
        "speedup",
        "mismatches"
    );
    for row in &r.rows {
        let _ = writeln!(
            s,
            "{:<w$} {:>9.1} {:>11.2} {:>12.1} {:>12} {:>11} {:>8.0}x {:>10}",
            row.name,
            row.build_ms,
            row.memory_bytes as f64 / (1024.0 * 1024.0),
            row.avg_visits,
            // Three digits, since structures a user compares may differ by a few percent.
            three_digits(row.avg_prim_tests),
            three_digits(row.mrays_per_s),
            row.speedup,
            row.mismatches
        );
    }
    // The shape of each structure: what the build produced, independent of the rays.
    let _ = writeln!(
        s,
        "\nShape: nodes, depth, leaves and the share empty, primitives per non-empty leaf, \
         references per primitive, and the tests a mailbox skipped per {unit}"
    );
    let _ = writeln!(
        s,
        "{:<w$} {:>9} {:>5} {:>9} {:>7} {:>10} {:>9} {:>11}  other figures",
        "structure",
        "nodes",
        "depth",
        "leaves",
        "empty",
        "prims/leaf",
        "refs/prim",
        format!("skips/{unit}"),
    );
    for row in r.rows.iter().filter(|row| row.leaves > 0) {
        let _ = writeln!(
            s,
            "{:<w$} {:>9} {:>5} {:>9} {:>6.1}% {:>10.2} {:>9.2} {:>11}  {}",
            row.name,
            row.nodes,
            row.max_depth,
            row.leaves,
            100.0 * row.empty_leaves as f64 / row.leaves as f64,
            row.avg_leaf_prims,
            row.duplication,
            // Mailbox skips: tests a mailbox saved, so `tests/ray` plus this is what the
            // structure would test without one.
            three_digits(row.avg_mailbox_skips),
            row.extra
                .iter()
                .map(|(k, v)| format!("{k} {}", three_digits(*v)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    // What the SAH predicts for lines spread uniformly over the scene box, beside what these
    // rays did: how far the builders' cost model holds.
    let modelled: Vec<&Row> = r
        .rows
        .iter()
        .filter(|row| row.predicted.is_some())
        .collect();
    if !modelled.is_empty() {
        let _ = writeln!(
            s,
            "\nThe SAH's prediction against these {units}: expected visits and tests per ray for \
             lines spread uniformly over the scene box (scaled by the share that enter it), beside \
             what the {units} did; ratio = measured / predicted"
        );
        let _ = writeln!(
            s,
            "{:<w$} {:>14} {:>14} {:>7} {:>14} {:>14} {:>7}",
            "structure",
            "visits (SAH)",
            "visits (rays)",
            "ratio",
            "tests (SAH)",
            "tests (rays)",
            "ratio"
        );
        for row in modelled {
            let p = row.predicted.expect("filtered");
            let ratio = |m: f64, p: f64| if p > 0.0 { m / p } else { f64::NAN };
            let _ = writeln!(
                s,
                "{:<w$} {:>14} {:>14} {:>7.2} {:>14} {:>14} {:>7.2}",
                row.name,
                three_digits(p.visits),
                three_digits(row.avg_visits),
                ratio(row.avg_visits, p.visits),
                three_digits(p.tests),
                three_digits(row.avg_prim_tests),
                ratio(row.avg_prim_tests, p.tests)
            );
        }
    }
    if r.rows.len() > 1 && r.total_mismatches() == 0 {
        let _ = writeln!(s, "all answers agree");
    }
    s
}

/// Three significant digits, so that brute force's 0.000823 and a BVH's 25.5 both read well.
fn three_digits(x: f64) -> String {
    if x >= 100.0 || x == 0.0 {
        format!("{x:.0}")
    } else {
        let decimals = (2 - x.log10().floor() as i32).clamp(0, 8) as usize;
        format!("{x:.decimals$}")
    }
}

fn hit_json(h: Option<Hit>, query_any: bool) -> serde_json::Value {
    match h {
        None if query_any => serde_json::Value::Bool(false),
        Some(_) if query_any => serde_json::Value::Bool(true),
        None => serde_json::Value::Null,
        Some(h) => serde_json::json!({ "prim": h.prim, "t": h.t, "u": h.u, "v": h.v }),
    }
}

fn to_json(r: &Report) -> String {
    let any = r
        .rows
        .iter()
        .flat_map(|row| row.answers.iter())
        .flatten()
        .any(|h| h.prim == u32::MAX);
    let results: Vec<serde_json::Value> = r
        .rows
        .iter()
        .map(|row| {
            let mut v = serde_json::json!({
                "structure": row.name,
                "build_ms": row.build_ms,
                "memory_bytes": row.memory_bytes,
                "nodes": row.nodes,
                "max_depth": row.max_depth,
                "hits": row.hits,
                "mismatches": row.mismatches,
                "avg_visits": row.avg_visits,
                "avg_prim_tests": row.avg_prim_tests,
                "avg_mailbox_skips": row.avg_mailbox_skips,
                "extra": row.extra.iter().map(|(k, v)| ((*k).to_string(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
                "mrays_per_s": row.mrays_per_s,
                "speedup": row.speedup,
                "leaves": row.leaves,
                "empty_leaves": row.empty_leaves,
                "avg_leaf_prims": row.avg_leaf_prims,
                "prim_refs": row.prim_refs,
                "duplication": row.duplication,
                "rays_traced": row.rays_traced,
                "predicted_visits": row.predicted.map(|p| p.visits),
                "predicted_tests": row.predicted.map(|p| p.tests),
            });
            if r.per_ray_answers {
                v["ray_hits"] = row.answers.iter().map(|&h| hit_json(h, any)).collect();
            }
            v
        })
        .collect();
    serde_json::json!({
        "scene": r.scene,
        "triangles": r.triangles,
        "valid_triangles": r.valid_triangles,
        "query": if r.ray_kind == points::KIND { "closest-point" } else { "rays" },
        "ray_kind": r.ray_kind,
        "rays": r.rays,
        "hit_share": r.hit_share(),
        "threads": r.threads,
        "checked_rays": r.checked_rays,
        "results": results,
    })
    .to_string()
}

fn describe_disagreements(r: &Report, args: &Args) -> String {
    let mut s = if r.point_disagreements.is_empty() {
        format!(
            "error: {} mismatches. First disagreeing rays (save the rays-file lines to a file and replay with \
             `cargo xtask compare --scene {} --rays-file FILE`, or paste the Rust into a test):\n",
            r.total_mismatches(),
            args.scene
        )
    } else {
        format!(
            "error: {} mismatches. First disagreeing closest-point queries (paste the Rust into a \
             test on the scene {}):\n",
            r.total_mismatches(),
            args.scene
        )
    };
    for d in &r.point_disagreements {
        let _ = writeln!(s, "  {} on query {}:", d.structure, d.index);
        let p = d.point;
        let _ = writeln!(
            s,
            "    rust:      closest_point(Vec3::new({:?}, {:?}, {:?}), {:?})",
            p.x, p.y, p.z, d.max_distance
        );
        let _ = writeln!(s, "    brute-force: {:?}", d.expected);
        let _ = writeln!(s, "    {}: {:?}", d.structure, d.got);
    }
    for d in &r.disagreements {
        let _ = writeln!(s, "  {} on ray {}:", d.structure, d.ray_index);
        let _ = writeln!(s, "    rays-file: {}", d.ray.to_line());
        let _ = writeln!(s, "    rust:      {}", d.ray.to_rust());
        let _ = writeln!(s, "    brute-force: {:?}", d.expected);
        let _ = writeln!(s, "    {}: {:?}", d.structure, d.got);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use rt_bvh::BvhParams;
    use rt_core::{Accel, BuildStats, Stats};

    /// A structure that is wrong on purpose: it loses every hit on an even primitive.
    #[derive(Debug)]
    struct LosesEvenHits<P: rt_core::Primitive>(Bvh<P>);

    impl<P: rt_core::Primitive> Accel for LosesEvenHits<P> {
        type Prim = P;
        type Params = ();
        const NAME: &'static str = "broken";
        fn presets() -> Vec<(&'static str, ())> {
            vec![("default", ())]
        }
        fn build(prims: &[P], _: &()) -> Self {
            Self(Bvh::build(prims, &BvhParams::sah()))
        }
        fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<Hit> {
            self.0
                .intersect_with(ray, stats)
                .filter(|h| h.prim % 2 == 1)
        }
        fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
            self.intersect_with(ray, stats).is_some()
        }
        fn bounds(&self) -> Aabb {
            self.0.bounds()
        }
        /// Loses even primitives here too.
        fn ball_query<Q: rt_core::BallQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
            self.0.ball_query(&mut OddOnly(query), stats);
        }
        fn memory_bytes(&self) -> usize {
            self.0.memory_bytes()
        }
        fn build_stats(&self) -> BuildStats {
            self.0.build_stats()
        }
    }

    /// Passes on only the odd primitives offered to it.
    struct OddOnly<'a, Q>(&'a mut Q);

    impl<P, Q: rt_core::BallQuery<P>> rt_core::BallQuery<P> for OddOnly<'_, Q> {
        fn center(&self) -> rt_core::glam::Vec3 {
            self.0.center()
        }
        fn radius_sq(&self) -> f32 {
            self.0.radius_sq()
        }
        fn test(&mut self, prim: &P, id: u32) {
            if id % 2 == 1 {
                self.0.test(prim, id);
            }
        }
        fn test_triangle(
            &mut self,
            v0: rt_core::glam::Vec3,
            e1: rt_core::glam::Vec3,
            e2: rt_core::glam::Vec3,
            id: u32,
        ) {
            if id % 2 == 1 {
                self.0.test_triangle(v0, e1, e2, id);
            }
        }
    }

    fn args(extra: &[&str]) -> Args {
        #[derive(clap::Parser)]
        struct Wrap {
            #[command(flatten)]
            args: Args,
        }
        let mut v = vec!["compare"];
        v.extend_from_slice(extra);
        let mut args = Wrap::parse_from(v).args;
        args.scene = args.scenes[0].clone();
        args
    }

    #[test]
    fn a_field_of_instances_agrees_on_every_row_and_every_ray_kind() {
        // Forty teapots of about 1,000 triangles, every row's structure under the instances.
        for kind in ["primary", "incoherent", "shadow"] {
            let a = args(&[
                "--scene",
                "teapot:1000",
                "--instances",
                "40",
                "--rays",
                kind,
                "--width",
                "96",
                "--height",
                "64",
                "--repeats",
                "1",
                "--check-rays",
                "6144",
            ]);
            let report = measure(&a, 1, structures::all()).expect("the field runs");
            let one = load_scene("teapot:1000").unwrap().1.len();
            assert_eq!(
                report.triangles,
                40 * one,
                "every instance's triangles counted"
            );
            assert_eq!(
                report.checked_rays, report.rays,
                "every ray checked by brute force"
            );
            assert!(report.rows.len() > 5);
            let hits = report.rows[1].hits;
            if kind == "primary" {
                assert!(
                    hits > report.rays / 20,
                    "the field fills the view ({hits} hits)"
                );
            }
            assert!(hits > 0, "{kind}: some rays hit");
            for row in &report.rows {
                assert_eq!(row.mismatches, 0, "{kind}: {} disagrees", row.name);
                assert_eq!(row.hits, hits, "{kind}: {}", row.name);
            }
        }
    }

    #[test]
    fn a_field_rejects_bad_counts_and_closest_points_in_one_line() {
        let bad = measure(
            &args(&["--scene", "teapot:1000", "--instances", "0"]),
            1,
            structures::all(),
        );
        assert_eq!(
            bad.unwrap_err(),
            "--instances must be from 1 to 1000000, not 0"
        );
        let points = args(&[
            "--scene",
            "teapot:1000",
            "--instances",
            "4",
            "--query",
            "closest-point",
        ]);
        let err = points::measure(&points, 1, structures::all()).unwrap_err();
        assert!(err.starts_with("--query closest-point runs on one mesh") && !err.contains('\n'));
    }

    #[test]
    fn a_wrong_structure_is_caught_on_and_off_the_checked_subset() {
        // 2,000 rays checked by brute force out of 3,072: disagreements outside the subset must
        // be found by the cross-check against the other structures.
        let a = args(&[
            "--scene",
            "random-soup",
            "--width",
            "64",
            "--height",
            "48",
            "--check-rays",
            "2000",
            "--repeats",
            "1",
        ]);
        let mut entries = structures::all();
        entries.push(structures::entry_of::<
            LosesEvenHits<Triangle>,
            LosesEvenHits<rt_core::Shape>,
        >());
        let report = measure(&a, 1, entries).unwrap();
        let broken = report.rows.iter().find(|r| r.name == "broken").unwrap();
        let bvh = report.rows.iter().find(|r| r.name == "bvh").unwrap();
        assert_eq!(bvh.mismatches, 0);
        // The broken row loses exactly the rays whose true answer is an even primitive.
        let expected = bvh
            .answers
            .iter()
            .filter(|a| a.is_some_and(|h| h.prim % 2 == 0))
            .count();
        assert!(
            expected > 100,
            "the test scene must exercise the broken path"
        );
        assert_eq!(broken.mismatches, expected);
        assert!(
            report.checked_rays > 2000,
            "rays outside the subset were settled by brute force"
        );
        assert!(!report.disagreements.is_empty());
    }

    #[test]
    fn a_wrong_closest_point_query_is_caught_on_and_off_the_checked_subset() {
        // 1,000 of 3,000 points checked by brute force; the rest by the cross-check.
        let a = args(&[
            "--scene",
            "random-soup",
            "--query",
            "closest-point",
            "--points",
            "3000",
            "--check-rays",
            "1000",
            "--repeats",
            "1",
        ]);
        let mut entries = structures::all();
        entries.retain(|e| ["bvh", "kdtree", "grid", "hgrid", "octree"].contains(&e.name.as_str()));
        entries.push(structures::entry_of::<
            LosesEvenHits<Triangle>,
            LosesEvenHits<rt_core::Shape>,
        >());
        let report = points::measure(&a, 1, entries).unwrap();
        assert_eq!(report.ray_kind, points::KIND);
        for row in &report.rows {
            let expect_wrong = row.name == "broken";
            assert_eq!(
                row.mismatches > 0,
                expect_wrong,
                "{}: {}",
                row.name,
                row.mismatches
            );
        }
        let broken = report.rows.iter().find(|r| r.name == "broken").unwrap();
        // About half the answers are even primitives, and every one of them is caught.
        assert!(broken.mismatches > 1000, "{}", broken.mismatches);
        assert!(
            report.checked_rays > 1000,
            "points outside the subset were settled"
        );
        let d = &report.point_disagreements[0];
        assert_eq!(d.structure, "broken");
        assert!(d.expected.is_some_and(|h| h.prim % 2 == 0), "{d:?}");
        let table = to_table(&report);
        assert!(
            table.contains("Mqueries/s") && table.contains("3000 closest-point queries"),
            "{table}"
        );
    }
}

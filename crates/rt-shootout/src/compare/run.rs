//! Running the shootout: the scene, the rays, each row built and traced (counted and timed),
//! and every answer cross-checked.

use super::output::{describe_disagreements, to_json, to_table};
use super::{Args, QueryKind, RayKind, ViewKind, points};
use crate::data::{BundleRow, Disagreement, Report, Row, predicted_per_ray};
use crate::scene::load_scene;
use crate::structures::{self, Pass, Query};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rt_bvh::Bvh;
use rt_core::DynAccel;
use rt_core::{Aabb, Hit, Primitive, Ray, Rng, Triangle};
use rt_scene::raygen;
use rt_scene::scenes;
use std::io::IsTerminal;
use std::sync::Arc;
use std::time::{Duration, Instant};

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
        if args.query != QueryKind::Rays {
            return Err(format!(
                "--out writes a report of ray queries only; leave it out with --query {}",
                args.query.name()
            ));
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
            QueryKind::Overlap => {
                pool.install(|| points::measure_overlap(&args, threads, entries))?
            }
            QueryKind::AllHits => {
                pool.install(|| points::measure_all_hits(&args, threads, entries))?
            }
            QueryKind::Filtered => {
                pool.install(|| points::measure_filtered(&args, threads, entries))?
            }
            QueryKind::SignedDistance => {
                pool.install(|| points::measure_signed(&args, threads, entries))?
            }
        };
        if args.json {
            println!("{}", to_json(&report));
        } else {
            if !reports.is_empty() {
                println!();
            }
            print!("{}", to_table(&report));
        }
        if !report.disagreements.is_empty() || !report.query_disagreements.is_empty() {
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
            args.bundle.is_some(),
            args.stream,
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
    // Brute force's row is its single-ray query, the reference the speedup column divides by,
    // timed in one counted pass (its counters cost nothing next to N primitive tests per ray)
    // over the first BRUTE_TIMED checked rays: each of its rays costs about the same. The
    // answers for every checked ray come from its bundle query, which tests each triangle
    // against many rays in vector steps and gives each ray its single-ray answer, bit for bit
    // (the conformance kit checks that of brute force as of every structure; the timed rays
    // check it again here).
    // PERF: with all 20,000 checked rays traced singly, brute force was 92% of the samples of
    // the README's bunny shootout (69,451 triangles, 320×240, five structures, release build),
    // which took 17.5 s; with its bundle query, 3.45 s.
    let timed = &subset_rays[..subset_rays.len().min(BRUTE_TIMED)];
    let mut brute_row = trace_row(
        &brute_entry.name,
        brute.as_ref(),
        build_ms,
        timed,
        query,
        0,
        false,
        false,
    );
    let (answers, _) =
        structures::trace_counted_as(brute.as_ref(), &subset_rays, query, Pass::Bundles);
    if let Some(i) =
        (0..timed.len()).find(|&i| !rt_conformance::same_bits(answers[i], brute_row.answers[i]))
    {
        return Err(format!(
            "brute force's bundle query answers {:?} where its single-ray query answers {:?}, \
             for ray {}",
            answers[i],
            brute_row.answers[i],
            timed[i].to_rust()
        ));
    }
    brute_row.rays_traced = subset_rays.len();
    brute_row.hits = answers.iter().filter(|a| a.is_some()).count();
    brute_row.answers = answers;
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
        view: match (ray_kind, args.view) {
            ("primary" | "shadow", ViewKind::Filled) => "filled",
            ("primary" | "shadow", ViewKind::Sparse) => "sparse",
            _ => "",
        },
        rays: rays.len(),
        threads,
        checked_rays: subset.len() + settled,
        rows: all_rows,
        disagreements,
        query_disagreements: Vec::new(),
        per_ray_answers: args.rays_file.is_some(),
        note: String::new(),
    })
}

/// Builds a row `repeats` times (at least once) with `build` and keeps the last structure with
/// the fastest build's time in milliseconds. Builds are timed like traces, since a single build
/// on a shared host can be 20% off (the structure is the same every time).
pub(crate) fn build_fastest(
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
        let bounds = rt_core::valid_bounds(tris.iter());
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
            let t = rt_instance::InstanceTransform::new(*xf).map_err(|e| e.to_string())?;
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
                structures::Field::<rt_instance::LinearInstances<Triangle>>::new(
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
pub(crate) fn checked_subset(len: usize, check: usize, seed: u64) -> Vec<usize> {
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

pub(super) fn make_rays(
    args: &Args,
    source: &Source,
) -> Result<(Vec<Ray>, &'static str, Query), String> {
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
    // A kit scene comes with the rays the kit checks it with, unless other rays are asked for.
    if args.rays.is_none()
        && let Some(kit) = crate::scene::kit_scene(&args.scene)?
    {
        return Ok((kit.rays, "kit", query));
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
        scenes::camera_for_view(
            &args.scene,
            bounds,
            args.width,
            args.height,
            args.view.into(),
        )
    };
    let shared_kind = match kind {
        RayKind::Primary => raygen::RayKind::Primary,
        RayKind::Incoherent => raygen::RayKind::Incoherent,
        RayKind::Shadow => raygen::RayKind::Shadow,
        RayKind::Diffuse => raygen::RayKind::Diffuse,
    };
    // With `--bundle`, in tiles, so that neighbouring rays come side by side.
    let primary = || match args.bundle {
        Some(tile) => camera.tiled_rays(args.width, args.height, tile).0,
        None => camera.primary_rays(args.width, args.height),
    };
    // Shadow rays and diffuse bounces start at the primary hits, found by a SAH BVH (any
    // correct structure finds the same ones); they need only the triangles hit, in the world.
    let primary_hits = || {
        let primary = primary();
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
        Ok::<_, String>((primary, hits, hit_tris))
    };
    let rays = match shared_kind {
        raygen::RayKind::Shadow => {
            let (primary, hits, tris) = primary_hits()?;
            raygen::shadow_rays(&primary, &hits, &tris, raygen::default_light(bounds))
        }
        raygen::RayKind::Diffuse => {
            let (primary, hits, tris) = primary_hits()?;
            raygen::diffuse_rays(&primary, &hits, &tris, args.seed)
        }
        raygen::RayKind::Primary => primary(),
        raygen::RayKind::Incoherent => raygen::incoherent_rays(
            bounds,
            args.width as usize * args.height as usize,
            args.seed,
        ),
    };
    Ok((rays, shared_kind.name(), query))
}

/// Checked rays that brute force's single-ray query is timed on (see [`measure`]).
const BRUTE_TIMED: usize = 1_000;

/// A row's counted pass and its best timed pass over `repeats`; with `bundles` and
/// `streams`, the same for the bundle and stream queries, each pass timed right after a single
/// one, and every answer compared with the single answer bit for bit.
#[allow(clippy::too_many_arguments)]
fn trace_row(
    name: &str,
    s: &dyn DynAccel<Triangle>,
    build_ms: f64,
    rays: &[Ray],
    query: Query,
    repeats: u32,
    bundles: bool,
    streams: bool,
) -> Row {
    let t = Instant::now();
    let (answers, counters) = structures::trace_counted(s, rays, query);
    let mut best = t.elapsed();
    let mut hits = answers.iter().filter(|a| a.is_some()).count();
    // Each batch pass: its answers and counters from a counted pass, and its best time.
    let mut batches: Vec<(Pass, Vec<Option<Hit>>, rt_core::Counters, Duration)> =
        [(bundles, Pass::Bundles), (streams, Pass::Streams)]
            .into_iter()
            .filter(|&(on, _)| on)
            .map(|(_, pass)| {
                let t = Instant::now();
                let (got, counters) = structures::trace_counted_as(s, rays, query, pass);
                (pass, got, counters, t.elapsed())
            })
            .collect();
    if repeats > 0 {
        best = Duration::MAX;
        batches.iter_mut().for_each(|b| b.3 = Duration::MAX);
    }
    for _ in 0..repeats {
        let t = Instant::now();
        hits = structures::trace_timed(s, rays, query);
        best = best.min(t.elapsed());
        for (pass, _, _, time) in &mut batches {
            let t = Instant::now();
            std::hint::black_box(structures::trace_timed_as(s, rays, query, *pass));
            *time = (*time).min(t.elapsed());
        }
    }
    let mut row = Row::measured(name, s, build_ms, rays.len(), hits, counters, best);
    for (pass, got, c, time) in batches {
        let n = rays.len().max(1) as f64;
        let mrays_per_s = rays.len() as f64 / time.as_secs_f64().max(1e-9) / 1e6;
        let batch = BundleRow {
            mrays_per_s,
            over_single: mrays_per_s / row.mrays_per_s,
            avg_visits: c.node_visits as f64 / n,
            avg_prim_tests: c.prim_tests as f64 / n,
            lane_utilisation: c.lane_utilisation(),
            single_share: c.single_rays as f64 / n,
            differences: got
                .iter()
                .zip(&answers)
                .filter(|(a, b)| !rt_conformance::same_bits(**a, **b))
                .count(),
        };
        match pass {
            Pass::Streams => row.stream = Some(batch),
            _ => row.bundle = Some(batch),
        }
    }
    row.answers = answers;
    row
}

impl Row {
    /// A row's figures from its counted pass (`counters`, `hits` answers found) and its best
    /// time over `queries` queries; the answers are left for the caller.
    pub(crate) fn measured(
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
            bundle: None,
            stream: None,
        }
    }
}

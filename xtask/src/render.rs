//! `cargo xtask render`: a Whitted-style or path-traced picture of a scene through one structure
//! (or several, whose pictures must be the same bytes), or per-pixel cost heatmaps of several
//! side by side.
//! The renderer is the `rt-render` library; this module only reads flags, picks the scene and
//! structures, shows progress and writes the PNG.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rt_render::{Metric, RenderOptions, RenderScene};
use rt_shootout::structures;
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Flags of `cargo xtask render`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// `whitted` (glass and mirror spheres, a checkerboard floor and a teapot), a built-in mesh
    /// scene of `compare`, or a scene file (OBJ, PLY, glTF).
    #[arg(long, default_value = "whitted")]
    pub scene: String,
    /// Comma-separated rows to trace with (as `compare` names them, or `brute-force`)
    /// [default: bvh; with --heatmap, bvh,kdtree,grid,hgrid,octree]. Several rows render the
    /// picture through each, and every picture must be the same bytes.
    #[arg(short, long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// Image width in pixels (per panel for heatmaps).
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 768)]
    pub height: u32,
    /// Rays along a path, the primary ray included (1: no reflection, refraction or bounce).
    #[arg(long, default_value_t = 5)]
    pub depth: u32,
    /// How light is followed: Whitted's mirror and glass rays, or a path tracer's bounces.
    #[arg(long, value_enum, default_value_t = Integrator::Whitted)]
    pub integrator: Integrator,
    /// Paths per pixel, with `--integrator path`.
    #[arg(long, default_value_t = 4)]
    pub samples: u32,
    /// Worker threads [default: all cores].
    #[arg(short = 'j', long)]
    pub threads: Option<usize>,
    /// The PNG to write.
    #[arg(short, long, default_value = "render.png")]
    pub out: PathBuf,
    /// Instead of a picture, the primary rays' cost per pixel, one panel per structure on one
    /// colour scale.
    #[arg(long, value_enum, conflicts_with_all = ["integrator", "samples"])]
    pub heatmap: Option<Heatmap>,
}

/// How `render` follows light.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Whitted's: shadow rays to the lights, mirror and refracted rays (`rt_render::render`).
    Whitted,
    /// A path tracer (`rt_render::render_path`): diffuse bounces as well, several paths per
    /// pixel, rendered once with single rays and once with batches, which must give the same
    /// bytes; prints each bounce depth's speed both ways.
    Path,
}

/// What a heatmap shows per pixel.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heatmap {
    /// Nodes or cells the pixel's primary ray entered.
    Visits,
    /// Primitives it tested.
    Tests,
}

impl Heatmap {
    fn metric(self) -> Metric {
        match self {
            Heatmap::Visits => Metric::Visits,
            Heatmap::Tests => Metric::Tests,
        }
    }
}

/// The text after `--help`: scenes and structures.
pub fn after_help() -> String {
    let mut s = String::from("Scenes: ");
    s.push_str(&rt_render::builtin_names().join(", "));
    s.push_str(", or a scene file (.obj, .ply, .gltf, .glb)\nStructures: ");
    let names: Vec<String> = structures::all().into_iter().map(|e| e.name).collect();
    s.push_str(&names.join(", "));
    s.push_str(
        ", brute-force\n\nExit status: 0 when the PNG is written, 1 when the rows' pictures \
         differ, 2 on bad input.",
    );
    s
}

/// Runs the task; the error is one line for `error: ...`. Returns whether every row rendered
/// the same picture.
pub fn run(args: &Args) -> Result<bool, String> {
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err("--threads must be at least 1".into());
    }
    if args.depth == 0 || args.depth > 64 {
        return Err(format!(
            "--depth {} is not usable: 1 to 64 rays per path",
            args.depth
        ));
    }
    if args.samples == 0 || args.samples > 4096 {
        return Err(format!(
            "--samples {} is not usable: 1 to 4096 paths per pixel",
            args.samples
        ));
    }
    // Checked before any work, so a bad size fails at once, not after loading a mesh.
    rt_render::Image::new(args.width, args.height).map_err(|e| e.to_string())?;
    check_output(&args.out, "PNG")?;
    let scene = load(&args.scene, args.width, args.height)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
    pool.install(|| match args.heatmap {
        None if args.integrator == Integrator::Path => path_picture(args, &scene, threads),
        None => picture(args, &scene, threads),
        Some(heatmap) => heatmaps(args, &scene, heatmap.metric()).map(|()| true),
    })
}

fn load(spec: &str, width: u32, height: u32) -> Result<RenderScene, String> {
    let names = rt_render::builtin_names();
    if !names.contains(&spec) && !Path::new(spec).exists() && !spec.contains(['/', '\\', '.']) {
        return Err(format!(
            "no built-in scene or file named `{spec}` (built-in scenes: {})",
            names.join(", ")
        ));
    }
    rt_render::scene(spec, width, height).map_err(|e| e.to_string())
}

/// Fails early, with the path, if a `kind` file (`PNG`, `SVG`) cannot be written where asked.
pub fn check_output(out: &Path, kind: &str) -> Result<(), String> {
    let dir = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!(
            "{}: cannot write {kind}: directory {} does not exist",
            out.display(),
            dir.display()
        ));
    }
    if out.is_dir() {
        return Err(format!(
            "{}: cannot write {kind}: it is a directory",
            out.display()
        ));
    }
    Ok(())
}

/// The row's builder over triangles and spheres, or why it cannot render.
fn shape_builder(entry: &structures::Entry) -> Result<structures::ShapeBuilder, String> {
    entry.build_shapes.clone().ok_or_else(|| {
        format!(
            "{} is built over triangles only, so it cannot render scenes with spheres",
            entry.name
        )
    })
}

fn progress_bar(label: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(
        None,
        if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    if let Ok(style) = ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} tiles ({elapsed})")
    {
        bar.set_style(style);
    }
    bar.set_message(label.to_string());
    bar
}

/// The rows `--structures` names, or the default for the mode.
fn rows(args: &Args) -> Result<Vec<structures::Entry>, String> {
    let default: &[&str] = match args.heatmap {
        None => &[rt_shootout::cli::DEFAULT_ROW],
        Some(_) => rt_shootout::cli::MAIN_ROWS,
    };
    let all = structures::all();
    rt_shootout::cli::rows_or(&args.structures, default)
        .iter()
        .map(|n| structures::find(&all, n))
        .collect()
}

/// Renders the picture through every row, writes the first row's, and returns whether the
/// others rendered the same bytes.
fn picture(args: &Args, scene: &RenderScene, threads: usize) -> Result<bool, String> {
    let entries = rows(args)?;
    // Checked first: a row that cannot render is an error before any work.
    for entry in &entries {
        shape_builder(entry)?;
    }
    let shapes = scene.shapes();
    let options = RenderOptions {
        width: args.width,
        height: args.height,
        depth: args.depth,
    };
    let mut first: Option<(String, rt_render::Image)> = None;
    let mut same = true;
    for entry in &entries {
        let start = Instant::now();
        let tracer = shape_builder(entry)?(&shapes);
        let build = start.elapsed();
        let bar = progress_bar(&format!("render {}", entry.name));
        let start = Instant::now();
        let image = rt_render::render(scene, &shapes, tracer.as_ref(), &options, &|done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })
        .map_err(|e| e.to_string())?;
        let elapsed = start.elapsed();
        bar.finish_and_clear();
        let verdict = match &first {
            None => {
                image.save_png(&args.out).map_err(|e| e.to_string())?;
                format!("wrote {}", args.out.display())
            }
            Some((name, expected)) if *expected == image => format!("same bytes as {name}"),
            Some((name, _)) => {
                same = false;
                format!("DIFFERENT bytes from {name}")
            }
        };
        println!(
            "{verdict}: {} {}×{}, depth {}, {} primitives; {} built in {:.0} ms, rendered in {:.2} s on {} threads",
            args.scene,
            args.width,
            args.height,
            args.depth,
            shapes.len(),
            entry.name,
            build.as_secs_f64() * 1e3,
            elapsed.as_secs_f64(),
            threads
        );
        if first.is_none() {
            first = Some((entry.name.clone(), image));
        }
    }
    Ok(same)
}

/// Path-traces the picture through every row, with single rays and with batches; writes the
/// first row's, prints each bounce depth's speed both ways, and returns whether every picture
/// (both ways, every row) is the same bytes.
fn path_picture(args: &Args, scene: &RenderScene, threads: usize) -> Result<bool, String> {
    let entries = rows(args)?;
    for entry in &entries {
        shape_builder(entry)?;
    }
    let shapes = scene.shapes();
    let options = rt_render::PathOptions {
        width: args.width,
        height: args.height,
        samples: args.samples,
        bounces: args.depth - 1,
        seed: 1,
    };
    let mut first: Option<(String, rt_render::Image)> = None;
    let mut same = true;
    for entry in &entries {
        let tracer = shape_builder(entry)?(&shapes);
        let mut runs = Vec::new();
        for tracing in [
            rt_render::Tracing::Single,
            rt_render::Tracing::Batch,
            rt_render::Tracing::Paired,
        ] {
            let bar = progress_bar(&format!("path {} {tracing:?}", entry.name));
            let start = Instant::now();
            let run = rt_render::render_path(
                scene,
                &shapes,
                tracer.as_ref(),
                &options,
                tracing,
                &|done, total| {
                    bar.set_length(total as u64);
                    bar.set_position(done as u64);
                },
            )
            .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            runs.push((run, start.elapsed()));
        }
        let [(single, single_time), (batch, batch_time), (paired, _)] =
            <[_; 3]>::try_from(runs).map_err(|_| "three renders".to_string())?;
        let mut verdict = match &first {
            None => {
                batch.image.save_png(&args.out).map_err(|e| e.to_string())?;
                format!("wrote {}", args.out.display())
            }
            Some((name, expected)) if *expected == batch.image => format!("same bytes as {name}"),
            Some((name, _)) => {
                same = false;
                format!("DIFFERENT bytes from {name}")
            }
        };
        let differences: u64 = paired
            .depths
            .iter()
            .filter_map(|d| d.paired.map(|p| p.differences))
            .sum();
        if single.image != batch.image || paired.image != batch.image || differences > 0 {
            same = false;
            verdict.push_str(&format!(
                ", single rays and batches DIFFERENT ({differences} answers differ)"
            ));
        }
        println!(
            "{verdict}: {} {}×{}, {} paths per pixel, depth {}, {} primitives; {} rendered in {:.2} s with single rays, {:.2} s with batches, on {} threads",
            args.scene,
            args.width,
            args.height,
            args.samples,
            args.depth,
            shapes.len(),
            entry.name,
            single_time.as_secs_f64(),
            batch_time.as_secs_f64(),
            threads
        );
        println!("{}", depth_table(&paired.depths));
        if first.is_none() {
            first = Some((entry.name.clone(), batch.image));
        }
    }
    Ok(same)
}

/// Each bounce depth's rays, their hit (or blocked) share and speed with single rays and with
/// batches, in million rays per second per thread (rays over the time the threads spent in the
/// trace calls), from a render that traced every call both ways ([`rt_render::Tracing::Paired`]).
fn depth_table(depths: &[rt_render::DepthStats]) -> String {
    let rate = |rays: u64, t: std::time::Duration| rays as f64 / t.as_secs_f64().max(1e-9) / 1e6;
    let share = |part: u64, all: u64| 100.0 * part as f64 / all.max(1) as f64;
    let mut out = String::from(
        "depth  closest rays   hit  single  batch  ratio | shadow rays  blocked  single  batch  ratio\n",
    );
    for (d, b) in depths.iter().enumerate() {
        let s = b.paired.unwrap_or_default();
        let (cs, cb) = (rate(b.rays, s.trace), rate(b.rays, b.trace));
        let (ss, sb) = (
            rate(b.shadow_rays, s.shadow_trace),
            rate(b.shadow_rays, b.shadow_trace),
        );
        let _ = writeln!(
            out,
            "{d:>5} {:>13} {:>4.0}% {cs:>7.2} {cb:>6.2} {:>5.2}x | {:>11} {:>7.0}% {ss:>7.2} {sb:>6.2} {:>5.2}x",
            b.rays,
            share(b.hits, b.rays),
            cb / cs,
            b.shadow_rays,
            share(b.blocked, b.shadow_rays),
            sb / ss.max(1e-9),
        );
    }
    out.push_str(
        "(single and batch: million rays per second per thread, in the trace calls; each call traced both ways, one after the other)",
    );
    out
}

fn heatmaps(args: &Args, scene: &RenderScene, metric: Metric) -> Result<(), String> {
    let entries = rows(args)?;
    if entries.is_empty() {
        return Err("--structures names no structure".into());
    }
    // Checked first: a row that cannot render is an error here, not a missing panel.
    for entry in &entries {
        shape_builder(entry)?;
    }
    let bar = progress_bar(metric.name());
    let panels = rt_shootout::report::cost_panels(
        scene,
        &entries,
        (args.width, args.height),
        metric,
        &|name, done, total| {
            bar.set_message(format!("{} {name}", metric.name()));
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    bar.finish_and_clear();
    let strip = rt_render::heatmap_strip(&panels, metric);
    strip.save_png(&args.out).map_err(|e| e.to_string())?;
    let mut line = format!(
        "wrote {}: {} per primary ray on {}, {}×{} per panel; mean",
        args.out.display(),
        metric.name(),
        args.scene,
        args.width,
        args.height
    );
    for (name, c) in &panels {
        let _ = write!(line, " {name} {:.1}", c.mean());
    }
    println!("{line}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row `compare` knows, every preset included, renders the Whitted scene to the same
    /// bytes as the first row.
    #[test]
    fn every_row_renders_the_same_bytes() {
        let scene = RenderScene::whitted();
        let shapes = scene.shapes();
        let options = RenderOptions {
            width: 64,
            height: 48,
            depth: 5,
        };
        let mut reference: Option<(String, rt_render::Image)> = None;
        for entry in structures::all() {
            let tracer = shape_builder(&entry).unwrap()(&shapes);
            let image =
                rt_render::render(&scene, &shapes, tracer.as_ref(), &options, &|_, _| {}).unwrap();
            match &reference {
                None => reference = Some((entry.name, image)),
                Some((first, expected)) => assert!(
                    image == *expected,
                    "{} renders differently from {first}",
                    entry.name
                ),
            }
        }
    }
}

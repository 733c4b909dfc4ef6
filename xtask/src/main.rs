//! The rt-accel runner, invoked as `cargo xtask <task>` (an alias in `.cargo/config.toml`).
//!
//! One module per task, as in rust-analyzer's xtask. Tasks:
//! - `compare`: the structure shootout, with `--out DIR` a Markdown report with charts: the
//!   `rt-shootout` library, which other crates call with their own structures added.
//! - `explain`: one ray's walk through one structure, step by step (see [`explain`]).
//! - `draw`: a slice through a built structure as SVG (see [`draw`]).
//! - `render`: a Whitted-style or path-traced picture through any structure, or per-pixel cost
//!   heatmaps (see [`render`]).
//! - `animate`: refitting against rebuilding on a moving scene, frame by frame (see
//!   [`animate`]).
//! - `scale`: the size ladder, build and trace cost and memory from thousands to millions of
//!   triangles (see [`scale`]).
//! - `results`: every measurement the documentation quotes, written as one page (see
//!   [`results`]).

mod animate;
mod draw;
mod explain;
mod render;
mod results;
mod scale;

/// Counts heap bytes in use and their peak, for `scale`'s peak build memory.
#[global_allocator]
static ALLOCATOR: rt_shootout::memory::Counting = rt_shootout::memory::Counting;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(name = "cargo xtask", about = "rt-accel's runner", version)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Subcommand, Debug)]
enum Task {
    /// Build every structure on one scene, trace the same rays through each, check every answer
    /// against brute force and the others, and print cost and speed.
    Compare(rt_shootout::Args),
    /// Render a scene through one structure (Whitted-style: shadows, mirrors, glass) to a PNG,
    /// or, with `--heatmap`, the primary rays' cost per pixel for several structures.
    Render(render::Args),
    /// Draw a slice through a built structure at an axis-aligned plane as SVG: its boxes, split
    /// planes or cells there, and the mesh's cross-section.
    Draw(draw::Args),
    /// Trace one ray through one structure and print its walk step by step: nodes or cells
    /// entered with their t intervals, split planes and the side taken first, pushes and pops,
    /// primitives tested and mailbox skips, and the hit, checked against brute force.
    Explain(explain::Args),
    /// Build and trace each structure on one built-in scene at sizes from thousands to millions
    /// of triangles: build time per triangle, trace time per ray, bytes per triangle and peak
    /// build memory, as a table and optionally an SVG chart.
    Scale(scale::Args),
    /// Follow a built-in animation (a wave through the mesh, or an explosion) frame by frame:
    /// structures that can refit are refitted and rebuilt, the others rebuilt; per frame the
    /// update time, trace time, their sum and the SAH cost, every frame checked against brute
    /// force.
    Animate(animate::Args),
    /// Measure everything the documentation quotes and write the results page (by default
    /// docs/results.md), stamped with the date, the commit and the CPU.
    Results(results::Args),
}

fn main() -> ExitCode {
    let command = Cli::command()
        .mut_subcommand("compare", |c| {
            c.after_help(rt_shootout::compare::after_help(
                &rt_shootout::structures::all(),
            ))
        })
        .mut_subcommand("render", |c| c.after_help(render::after_help()));
    let matches = command
        .try_get_matches()
        .unwrap_or_else(|e| rt_shootout::cli::exit_on_error(e));
    let cli =
        Cli::from_arg_matches(&matches).unwrap_or_else(|e| rt_shootout::cli::exit_on_error(e));
    match cli.task {
        Task::Compare(args) => rt_shootout::Shootout::new().main_with(&args),
        Task::Draw(args) => match draw::run(&args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
        Task::Explain(args) => match explain::run(&args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
        Task::Scale(args) => match scale::run(&args) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => {
                eprintln!("error: rows disagree with the first row on some rays");
                ExitCode::from(1)
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
        Task::Animate(args) => match animate::run(&args) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => {
                eprintln!("error: some answers differ from brute force");
                ExitCode::from(1)
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
        Task::Results(args) => match results::run(&args) {
            Ok(path) => {
                println!("wrote {}", path.display());
                ExitCode::SUCCESS
            }
            Err(results::Failure::Run(e)) => {
                eprintln!("error: {e}");
                ExitCode::from(1)
            }
            Err(results::Failure::BadInput(e)) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
        Task::Render(args) => match render::run(&args) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => {
                eprintln!("error: the rows rendered different pictures");
                ExitCode::from(1)
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
    }
}

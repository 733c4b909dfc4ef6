//! The rt-accel shootout as a library: what `cargo xtask compare` runs, for anyone's structure.
//!
//! It builds every selected structure on the same scene, traces the same rays through each,
//! checks every answer (against brute force on a random subset, against each other on all rays,
//! and against brute force again wherever they disagree), and reports build time, memory, shape,
//! node visits and primitive tests per ray, the surface area heuristic's prediction of those,
//! and speed: as a table, JSON (`--json`), or a Markdown report with charts (`--out DIR`).
//!
//! A structure from another crate joins the built-in rows in a few lines, with every flag of
//! `compare`. In that crate's `examples/shootout.rs`:
//!
//! ```no_run
//! # use rt_core::{Accel, BruteForce, Triangle};
//! # type MyGrid = BruteForce<Triangle>; // your structure here
//! fn main() -> std::process::ExitCode {
//!     rt_shootout::Shootout::new()
//!         .with_triangles::<MyGrid>() // or `.with::<MyGrid<Triangle>, MyGrid<Shape>>()`
//!         .main()
//! }
//! ```
//!
//! and then `cargo run --release --example shootout -- --scene teapot-in-stadium`, or
//! `--structures mine,grid,bvh --json`, or `--out report`, as with `cargo xtask compare`.
//! The crate needs `rt-core` and `rt-shootout` as dependencies (see the workspace README).

pub mod animate;
pub mod cli;
pub mod compare;
pub mod data;
pub mod explain;
pub mod fuzz;
pub mod grade;
pub mod measure;
pub mod memory;
pub mod report;
pub mod scale;
pub mod scene;
pub mod structures;

pub use compare::{Args, Report, Row};
pub use structures::{Entry, entries_of, entries_of_triangles};

use clap::{CommandFactory, FromArgMatches, Parser};
use rt_core::{Accel, Shape, Triangle};
use std::path::PathBuf;
use std::process::ExitCode;

/// A set of rows to compare: the built-in structures and presets, plus any added.
#[derive(Clone, Debug)]
pub struct Shootout {
    entries: Vec<Entry>,
}

impl Default for Shootout {
    fn default() -> Self {
        Self::new()
    }
}

/// The command line of [`Shootout::main`]: `compare`'s flags, or the `explain` subcommand.
#[derive(Parser, Debug)]
#[command(
    about = "Build structures on one scene, trace the same rays through each, check every answer against brute force and the others, and print cost and speed.",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Sub>,
    #[command(flatten)]
    args: Args,
}

#[derive(clap::Subcommand, Debug)]
enum Sub {
    /// One ray's walk through one or more rows, step by step, checked against brute force (as
    /// `cargo xtask explain`; a grade's replay commands use it).
    Explain(explain::ExplainArgs),
}

impl Shootout {
    /// Every built-in structure and preset (rt-bvh, rt-kdtree, rt-grid, rt-hgrid, rt-octree).
    pub fn new() -> Self {
        Self {
            entries: structures::all(),
        }
    }

    /// No rows at all, for a shootout of only the structures added next.
    pub fn empty() -> Self {
        Self {
            entries: Vec::new(),
        }
    }

    /// Adds every preset of a structure generic over its primitive: `A` over triangles, `S` the
    /// same type over [`Shape`]s (so that `render` can use it too).
    pub fn with<A, S>(mut self) -> Self
    where
        A: Accel<Prim = Triangle> + 'static,
        S: Accel<Prim = Shape, Params = A::Params> + 'static,
    {
        self.entries.extend(entries_of::<A, S>());
        self
    }

    /// Adds every preset of a structure over triangles.
    pub fn with_triangles<A>(mut self) -> Self
    where
        A: Accel<Prim = Triangle> + 'static,
    {
        self.entries.extend(entries_of_triangles::<A>());
        self
    }

    /// Adds rows made some other way.
    pub fn with_entries(mut self, entries: impl IntoIterator<Item = Entry>) -> Self {
        self.entries.extend(entries);
        self
    }

    /// The rows, in report order.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// Runs the comparison with `args` (see [`compare::run`]).
    ///
    /// # Errors
    /// One line describing bad input.
    pub fn run(&self, args: &Args) -> Result<Vec<Report>, String> {
        compare::run(args, &self.entries)
    }

    /// Grades the row `args.grade` names (see [`grade::run`]); returns the Markdown's path.
    ///
    /// # Errors
    /// One line describing bad input.
    pub fn grade(&self, args: &Args) -> Result<PathBuf, String> {
        grade::run(args, &self.entries)
    }

    /// Parses `compare`'s flags from the process's arguments (`--help` lists the scenes and
    /// these rows), runs, and returns the exit status `cargo xtask compare` uses: 0 when every
    /// answer agrees, 1 on any mismatch, 2 on bad input (after one `error:` line).
    pub fn main(&self) -> ExitCode {
        let command = Cli::command().after_help(compare::after_help(&self.entries));
        let matches = command
            .try_get_matches()
            .unwrap_or_else(|e| cli::exit_on_error(e));
        let mut cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| cli::exit_on_error(e));
        if let Some(Sub::Explain(args)) = &cli.command {
            return match explain::explain(args, &self.entries) {
                Ok(text) => {
                    print!("{text}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            };
        }
        cli.args.flags = std::env::args_os().skip(1).collect();
        self.main_with(&cli.args)
    }

    /// Runs what `args` asks, a comparison or (with `--grade`) a grade, and returns the exit
    /// status: 0 when every answer agrees (or the grade is written), 1 on any mismatch, 2 on bad
    /// input (after one `error:` line).
    pub fn main_with(&self, args: &Args) -> ExitCode {
        if args.grade.is_none() {
            return exit_code(self.run(args));
        }
        if args.grade_worker.is_some() {
            return grade::worker(args, &self.entries);
        }
        match self.grade(args) {
            Ok(path) => {
                println!("wrote {}", path.display());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        }
    }
}

/// `compare`'s flags parsed from `flags` (without a program name), for running a shootout from
/// code: `args_from(["--scene", "random-soup", "--json"])`.
///
/// # Errors
/// clap's message for flags it does not accept.
pub fn args_from<I, T>(flags: I) -> Result<Args, String>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let flags: Vec<std::ffi::OsString> = flags.into_iter().map(Into::into).collect();
    let argv = std::iter::once(std::ffi::OsString::from("shootout")).chain(flags.iter().cloned());
    let cli = Cli::try_parse_from(argv).map_err(|e| e.to_string())?;
    if cli.command.is_some() {
        return Err("args_from takes compare's flags, not a subcommand".into());
    }
    let mut args = cli.args;
    args.scene = args.scenes.first().cloned().unwrap_or_default();
    args.flags = flags;
    Ok(args)
}

/// The exit status for a comparison's outcome, printing the error line if there is one.
pub fn exit_code(outcome: Result<Vec<Report>, String>) -> ExitCode {
    match outcome {
        Ok(reports) if reports.iter().all(|r| r.total_mismatches() == 0) => ExitCode::SUCCESS,
        Ok(_) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

/// The Rust examples of the repository's README and guide (`docs/`), compiled (and run, where
/// they need no file) as doctests of this crate, which depends on every crate they use. Outside
/// a doctest build the items do not exist, so the packaged crate does not need the files.
#[cfg(doctest)]
mod guide {
    #[doc = include_str!("../../../README.md")]
    struct Readme;
    #[doc = include_str!("../../../docs/using.md")]
    struct Using;
    #[doc = include_str!("../../../docs/closest-points.md")]
    struct ClosestPoints;
    #[doc = include_str!("../../../docs/overlap.md")]
    struct Overlap;
    #[doc = include_str!("../../../docs/inside-outside.md")]
    struct InsideOutside;
    #[doc = include_str!("../../../docs/saved-structures.md")]
    struct SavedStructures;
    #[doc = include_str!("../../../docs/ray-queries.md")]
    struct RayQueries;
    #[doc = include_str!("../../../docs/instances.md")]
    struct Instances;
    #[doc = include_str!("../../../docs/dynamic.md")]
    struct Dynamic;
    #[doc = include_str!("../../../docs/your-structure.md")]
    struct YourStructure;
}

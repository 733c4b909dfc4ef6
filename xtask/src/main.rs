//! The rt-accel runner, invoked as `cargo xtask <task>` (an alias in `.cargo/config.toml`).
//!
//! One module per task, as in rust-analyzer's xtask. Tasks:
//! - `compare`: the structure shootout (see [`compare`]).

mod compare;
mod structures;

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
    Compare(compare::Args),
}

fn main() -> ExitCode {
    let command = Cli::command().mut_subcommand("compare", |c| c.after_help(compare::after_help()));
    let matches = command.get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    match cli.task {
        Task::Compare(args) => match compare::run(&args) {
            Ok(report) if report.total_mismatches() == 0 => ExitCode::SUCCESS,
            Ok(_) => ExitCode::from(1),
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
    }
}

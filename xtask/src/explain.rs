//! `cargo xtask explain`: one ray's walk through one structure, step by step. The logic is
//! `rt_shootout::explain`; this module prints it.

pub use rt_shootout::explain::ExplainArgs as Args;

/// Runs the task; the error is one line for `error: ...`.
pub fn run(args: &Args) -> Result<(), String> {
    let text = rt_shootout::explain::explain(args, &rt_shootout::structures::all())?;
    print!("{text}");
    Ok(())
}

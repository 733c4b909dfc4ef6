//! `cargo xtask animate`: refitting against rebuilding, frame by frame, on a built-in
//! animation. The logic is `rt_shootout::animate`; this module prints it.

pub use rt_shootout::animate::AnimateArgs as Args;

/// Runs the task; the error is one line for `error: ...`. Returns whether every checked ray of
/// every frame agreed with brute force.
pub fn run(args: &Args) -> Result<bool, String> {
    let report = rt_shootout::animate::animate(args, &rt_shootout::structures::all())?;
    if args.json {
        println!("{}", report.json());
    } else {
        print!("{}", report.table());
    }
    Ok(report.mismatches() == 0)
}

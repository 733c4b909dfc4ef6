//! `cargo xtask scale`: the size ladder (build time per triangle, trace time per ray, bytes per
//! triangle and peak build heap, from thousands to millions of triangles). The logic is
//! `rt_shootout::scale`; this module prints it and writes the chart.

pub use rt_shootout::scale::ScaleArgs as Args;

/// Runs the task; the error is one line for `error: ...`. Returns whether every row agreed with
/// the first on the checked rays.
pub fn run(args: &Args) -> Result<bool, String> {
    if let Some(path) = &args.out {
        crate::render::check_output(path, "SVG")?;
    }
    let report = rt_shootout::scale::scale(args, &rt_shootout::structures::all())?;
    if args.json {
        println!("{}", report.json());
    } else {
        print!("{}", report.table());
    }
    if let Some(path) = &args.out {
        report.svg(path)?;
        if !args.json {
            println!("wrote {}", path.display());
        }
    }
    Ok(report.disagreements() == 0)
}

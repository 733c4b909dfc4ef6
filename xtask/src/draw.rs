//! `cargo xtask draw`: a slice through a built structure at an axis-aligned plane, as SVG: its
//! boxes, split planes or cells where they meet the plane, and the mesh's cross-section. The
//! drawing is `rt_render::slice_svg`; this module reads flags, builds the row and writes the file.

use rt_core::{Aabb, Primitive};
use rt_render::{Coloring, SliceOptions};
use rt_shootout::{compare, structures};
use std::path::PathBuf;

/// Flags of `cargo xtask draw`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A built-in scene (as `compare` names them) or a scene file (OBJ, PLY, glTF).
    #[arg(long, default_value = "sphereflake")]
    pub scene: String,
    /// The structure row to draw (as `compare` names them).
    #[arg(long, default_value = "kdtree")]
    pub structure: String,
    /// The axis the slicing plane is perpendicular to.
    #[arg(long, default_value = "z", value_name = "x|y|z")]
    pub axis: String,
    /// Where the plane lies along the axis, as a fraction of the scene's box (0 to 1).
    #[arg(long, default_value_t = 0.5)]
    pub at: f32,
    /// What fills leaves and cells: their depth or their primitive count.
    #[arg(long, default_value = "depth", value_name = "depth|prims")]
    pub color: String,
    /// Width of the drawing in pixels.
    #[arg(long, default_value_t = 900.0)]
    pub width: f32,
    /// The SVG file to write.
    #[arg(long, default_value = "slice.svg")]
    pub out: PathBuf,
}

/// Runs the task; the error is one line for `error: ...`.
pub fn run(args: &Args) -> Result<(), String> {
    let axis = match args.axis.as_str() {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        other => return Err(format!("unknown axis `{other}` (known: x, y, z)")),
    };
    if !(0.0..=1.0).contains(&args.at) {
        return Err(format!("--at {} is outside 0 to 1", args.at));
    }
    if !(args.width.is_finite() && (100.0..=20_000.0).contains(&args.width)) {
        return Err(format!(
            "--width {} is not usable: 100 to 20000",
            args.width
        ));
    }
    let coloring = Coloring::parse(&args.color)?;
    crate::render::check_output(&args.out, "SVG")?;
    let entry = structures::find(&structures::all(), &args.structure)?;
    let (_, triangles) = compare::load_scene(&args.scene)?;
    let built = (entry.build)(&triangles);
    let regions = built.regions();
    if regions.is_empty() {
        return Err(format!(
            "{} does not describe its nodes (Accel::regions), so it cannot be drawn",
            entry.name
        ));
    }
    let bounds = triangles
        .iter()
        .filter(|t| t.is_valid())
        .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let options = SliceOptions {
        axis,
        at: args.at,
        coloring,
        width: args.width,
    };
    // A file is named by its file name; the directories would crowd the drawing's title.
    let scene_name = std::path::Path::new(&args.scene)
        .file_name()
        .map_or(args.scene.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!("{} on {scene_name}", entry.name);
    let (document, summary) = rt_render::slice_svg(&title, &triangles, &regions, &bounds, &options);
    svg::save(&args.out, &document)
        .map_err(|e| format!("{}: cannot write SVG: {e}", args.out.display()))?;
    println!(
        "wrote {}: {} slice {} = {} ({} of the box): {} leaves or cells, {} interior nodes, {} mesh segments",
        args.out.display(),
        title,
        args.axis,
        summary.plane,
        args.at,
        summary.leaves,
        summary.interior,
        summary.segments
    );
    Ok(())
}

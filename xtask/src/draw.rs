//! `cargo xtask draw`: a slice through a built structure at an axis-aligned plane, as SVG: its
//! boxes, split planes or cells where they meet the plane, and the mesh's cross-section. The
//! drawing is `rt_render::slice_svg`; this module reads flags, builds the rows and writes the
//! files (one per row: `--out slice.svg` with two rows writes `slice-kdtree.svg` and
//! `slice-bvh.svg`).

use rt_render::{Coloring, SliceOptions};
use rt_shootout::{compare, structures};
use std::path::{Path, PathBuf};

/// Flags of `cargo xtask draw`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A built-in scene (as `compare` names them) or a scene file (OBJ, PLY, glTF).
    #[arg(long, default_value = "sphereflake")]
    pub scene: String,
    /// Comma-separated rows to draw, each to a file of its own (as `compare` names them)
    /// [default: bvh].
    #[arg(short, long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// The axis the slicing plane is perpendicular to.
    #[arg(long, value_enum, default_value_t = Axis::Z)]
    pub axis: Axis,
    /// Where the plane lies along the axis, as a fraction of the scene's box (0 to 1).
    #[arg(long, default_value_t = 0.5)]
    pub at: f32,
    /// What fills leaves and cells with colour.
    #[arg(long, value_enum, default_value_t = Fill::Depth)]
    pub fill: Fill,
    /// Width of the drawing in pixels.
    #[arg(long, default_value_t = 900.0)]
    pub width: f32,
    /// The SVG file to write (with several rows, each row's name is added to it).
    #[arg(short, long, default_value = "slice.svg")]
    pub out: PathBuf,
}

/// The axis a slicing plane is perpendicular to.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// The plane x = const.
    X,
    /// The plane y = const.
    Y,
    /// The plane z = const.
    Z,
}

/// What fills a drawn leaf or cell with colour.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fill {
    /// Its depth in the structure.
    Depth,
    /// How many primitive references it lists (on a logarithmic scale).
    Prims,
}

/// Where row `name`'s drawing goes: `out` itself for one row, else `out` with the row's name
/// added before its extension.
fn out_for(out: &Path, name: &str, rows: usize) -> PathBuf {
    if rows == 1 {
        return out.to_path_buf();
    }
    let stem = out
        .file_stem()
        .map_or("slice".into(), |s| s.to_string_lossy());
    let ext = out
        .extension()
        .map_or("svg".into(), |e| e.to_string_lossy());
    out.with_file_name(format!("{stem}-{name}.{ext}"))
}

/// Runs the task; the error is one line for `error: ...`.
pub fn run(args: &Args) -> Result<(), String> {
    let (axis, axis_name) = match args.axis {
        Axis::X => (0, "x"),
        Axis::Y => (1, "y"),
        Axis::Z => (2, "z"),
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
    let coloring = match args.fill {
        Fill::Depth => Coloring::Depth,
        Fill::Prims => Coloring::Prims,
    };
    crate::render::check_output(&args.out, "SVG")?;
    let all = structures::all();
    let entries = rt_shootout::cli::rows_or(&args.structures, &[rt_shootout::cli::DEFAULT_ROW])
        .iter()
        .map(|name| structures::find(&all, name))
        .collect::<Result<Vec<_>, _>>()?;
    let (_, triangles) = compare::load_scene(&args.scene)?;
    let bounds = rt_core::valid_bounds(triangles.iter());
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
    for entry in &entries {
        let built = (entry.build)(&triangles);
        let regions = built.regions_dyn();
        if regions.is_empty() {
            return Err(format!(
                "{} does not describe its nodes (Accel::regions), so it cannot be drawn",
                entry.name
            ));
        }
        let title = format!("{} on {scene_name}", entry.name);
        let (document, summary) =
            rt_render::slice_svg(&title, &triangles, &regions, &bounds, &options);
        let out = out_for(&args.out, &entry.name, entries.len());
        svg::save(&out, &document)
            .map_err(|e| format!("{}: cannot write SVG: {e}", out.display()))?;
        println!(
            "wrote {}: {} slice {} = {} ({} of the box): {} leaves or cells, {} interior nodes, {} mesh segments",
            out.display(),
            title,
            axis_name,
            summary.plane,
            args.at,
            summary.leaves,
            summary.interior,
            summary.segments
        );
    }
    Ok(())
}

//! `compare`'s flags.

use crate::structures;
use rt_scene::scenes::BUILTIN_SCENES;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Which query `compare` measures.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum QueryKind {
    /// Rays (`--rays` says which).
    #[default]
    Rays,
    /// Closest-point queries: the primitive nearest to each of `--points` points.
    ClosestPoint,
    /// Box overlap queries: the primitives meeting a box around each of `--points` points
    /// (`--box-size` says how large).
    Overlap,
    /// Every hit along each ray (`--rays` says which), sorted by distance.
    AllHits,
    /// Closest and any hits through an alpha mask: a checkerboard over each triangle's
    /// barycentric coordinates cuts away half of every triangle (`--rays` says which rays).
    Filtered,
    /// Signed distances at `--points` points: each row's closest point, negative inside by
    /// the fast winding number of a tree every row shares; brute force signs by the exact sum.
    SignedDistance,
}

impl QueryKind {
    /// The flag's value for this kind, as `--query` takes it.
    pub fn name(self) -> &'static str {
        match self {
            QueryKind::Rays => "rays",
            QueryKind::ClosestPoint => "closest-point",
            QueryKind::Overlap => "overlap",
            QueryKind::AllHits => "all-hits",
            QueryKind::Filtered => "filtered",
            QueryKind::SignedDistance => "signed-distance",
        }
    }
}

/// Which rays to trace.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// One ray per pixel from a pinhole camera (`--view` says which).
    Primary,
    /// Random origins inside the scene box, random directions.
    Incoherent,
    /// Occlusion rays from the primary hits to a point light (any-hit queries).
    Shadow,
    /// A diffuse bounce from each primary hit: a cosine-weighted direction about the surface
    /// normal, started off the surface as shadow rays are (closest-hit queries).
    Diffuse,
}

/// Which view primary rays (and the shadow rays from their hits) come from.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ViewKind {
    /// A view the scene fills: a built-in scene's own camera where it has one, else the scene
    /// box's centre seen from 1.5 radii of its bounding sphere. Most rays enter the box.
    #[default]
    Filled,
    /// The whole scene box in the image: most rays of a compact mesh miss its box and leave
    /// after one test, which measures a call's cost more than traversal.
    Sparse,
}

impl From<ViewKind> for rt_scene::scenes::View {
    fn from(v: ViewKind) -> Self {
        match v {
            ViewKind::Filled => Self::Filled,
            ViewKind::Sparse => Self::Sparse,
        }
    }
}

#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// A built-in scene name (listed below) or the path of an .obj, .ply, .gltf or .glb file; repeat the flag to run
    /// several scenes in turn.
    #[arg(long = "scene", default_value = "sphereflake", value_name = "SCENE")]
    pub scenes: Vec<String>,
    /// The scene being measured (one of `scenes`, set by `run`).
    #[arg(skip)]
    pub scene: String,
    /// Also write a report into DIR: `report.md` with SVG charts of every scene's figures and a
    /// heatmap strip per scene (with `--grade`: `grade.md` and `grade.json`).
    #[arg(short, long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Grade this row instead: run the conformance kit on it (every scene passed or failed, the
    /// first failing ray of each), then the shootout against `--structures` (default bvh,
    /// kdtree, grid), and write `grade.json` and `grade.md` into `--out DIR` (default `grade`).
    #[arg(long, value_name = "ROW")]
    pub grade: Option<String>,
    /// With `--grade`: how long one build or query of the graded row may take before its check
    /// calls it stuck (a loop that never ends?) and moves on.
    #[arg(long, default_value_t = 5.0, value_name = "SECONDS")]
    pub grade_stall: f64,
    /// Grading runs each part of the kit, and the shootout, in a process of its own (so that a
    /// panic, a loop or a stack overflow in the graded row costs one check, not the grade): this
    /// is how the grade tells that process which part to run (a kit part's name, or `shootout`).
    #[arg(long, hide = true, requires = "grade", value_name = "PART")]
    pub grade_worker: Option<String>,
    /// The kit scene (an index into the kit's scenes, then its random scenes) a grading worker
    /// starts at, after an earlier worker of the same part stopped.
    #[arg(long, hide = true, default_value_t = 0)]
    pub grade_from: usize,
    /// The flags as given (without the program's name), for grading to start its workers with.
    #[arg(skip)]
    pub flags: Vec<std::ffi::OsString>,
    /// Which query to measure: rays, closest points (nearest primitive to a point), box
    /// overlap (the primitives meeting a box), all hits along a ray, or hits through an alpha
    /// mask.
    #[arg(long, value_enum, default_value_t = QueryKind::Rays)]
    pub query: QueryKind,
    /// Closest-point and box overlap queries: how many query points (half uniform in the scene
    /// box grown by a quarter on every side, half within 2% of its diagonal from the surface);
    /// box queries put a box around each.
    #[arg(long, default_value = "100k", value_parser = crate::cli::count)]
    pub points: usize,
    /// Box overlap queries: each box's sides, as a share of the scene box's diagonal, each
    /// drawn between a quarter and 1.75 times this.
    #[arg(long, default_value_t = 0.01, value_name = "F")]
    pub box_size: f32,
    /// Closest-point queries: the largest distance searched [default: no limit].
    #[arg(long, value_name = "D")]
    pub max_distance: Option<f32>,
    /// Trace a field of N instances of the scene instead (on a square grid, each rotated,
    /// scaled unevenly, every seventh mirrored): a two-level scene. Each row's structure is
    /// built once over the mesh and instanced under rt-bvh's `Instances`; brute force visits
    /// every instance. Rays only.
    #[arg(long, value_name = "N", value_parser = crate::cli::count)]
    pub instances: Option<usize>,
    /// Which rays to trace [default: primary].
    #[arg(long, value_enum)]
    pub rays: Option<RayKind>,
    /// The view of primary and shadow rays.
    #[arg(long, value_enum, default_value_t = ViewKind::Filled)]
    pub view: ViewKind,
    /// Image width for primary and shadow rays (incoherent: width × height rays).
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Image height for primary and shadow rays.
    #[arg(long, default_value_t = 768)]
    pub height: u32,
    /// Also trace every row's rays as bundles (`Accel::intersect_bundle`, `occluded_bundle`):
    /// primary rays in tiles of WxH pixels (8x8 fills a 64-lane bundle), shadow rays in the same
    /// order, incoherent rays and rays from a file as they come. Every row's single rays then
    /// follow that order too, and a table sets the bundles' speed, steps and lane use beside
    /// them; every bundle answer must equal the row's single answer bit for bit.
    #[arg(long, value_name = "WxH", value_parser = crate::cli::tile)]
    pub bundle: Option<(u32, u32)>,
    /// Also trace every row's rays as streams (`Accel::intersect_stream`, `occluded_stream`),
    /// in the order `--bundle` gives them (else as they come), and set a table of the streams'
    /// speed and steps beside the single rays'; every stream answer must equal the row's single
    /// answer bit for bit.
    #[arg(long)]
    pub stream: bool,
    /// Comma-separated rows to run (listed below); brute force is always the baseline.
    /// [default: every row]
    #[arg(short, long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// Threads for building and tracing [default: all cores]; structures that build in parallel
    /// use them.
    #[arg(short = 'j', long)]
    pub threads: Option<usize>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Replay rays from a file, one per line: `ox oy oz dx dy dz [tmin tmax]` (`#` comments).
    /// Closest-hit queries, or any-hit with `--rays shadow`. The JSON then carries every answer.
    #[arg(long)]
    pub rays_file: Option<PathBuf>,
    /// How many rays brute force checks (a random subset; all rays if there are fewer).
    /// [default: 20,000; 1,000 with --instances, where one brute-force ray tests every
    /// triangle of each instance whose box it enters]
    #[arg(long, value_parser = crate::cli::count)]
    pub check_rays: Option<usize>,
    /// Seed for incoherent rays and for the checked subset.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Timed builds and trace passes per structure, the fastest reported (brute force: its one
    /// counted pass).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
}

/// The text after `--help`: built-in scenes and structure rows.
pub fn after_help(entries: &[structures::Entry]) -> String {
    let mut s = String::from(
        "Built-in scenes (add a size for about that many triangles: `random-soup:10M`, \
         `terrain:500k`):\n",
    );
    for b in BUILTIN_SCENES {
        let _ = writeln!(s, "  {:<14} {}", b.name, b.description);
    }
    s.push_str("\nStructure rows:\n");
    for e in entries {
        let _ = writeln!(s, "  {}", e.name);
    }
    s.push_str("\nExit status: 0 when every answer agrees, 1 on any mismatch, 2 on bad input.");
    s
}

//! One ray, explained: the walk a structure takes for one ray, step by step, as text.
//!
//! The row is traced with [`rt_core::Trace`], the sink that records every event a traversal
//! reports (nodes and cells entered with their `t` intervals, split planes and the side taken,
//! pushes and pops, each primitive test and its outcome, mailbox skips), and the answer is
//! checked against brute force. `cargo xtask explain` prints what [`explain`] returns.

use crate::structures::{self, Entry, Query};
use rt_core::{Aabb, Accel, BruteForce, Hit, Ray, Triangle};
use rt_scene::raygen::parse_rays;
use rt_scene::scenes;

/// Flags of `cargo xtask explain`.
#[derive(clap::Args, Debug, Clone)]
pub struct ExplainArgs {
    /// The rows to explain, each in turn (as `compare` names them) [default: bvh].
    #[arg(short, long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// A built-in scene (as `compare` names them) or a scene file (OBJ, PLY, glTF).
    #[arg(long, default_value = "sphereflake")]
    pub scene: String,
    /// The ray, as a rays-file line: "ox oy oz dx dy dz [tmin tmax]".
    #[arg(long, conflicts_with = "pixel", allow_hyphen_values = true)]
    pub ray: Option<String>,
    /// The primary ray through the centre of pixel X,Y of `compare`'s camera [default: the
    /// image's centre].
    #[arg(long, value_name = "X,Y")]
    pub pixel: Option<String>,
    /// Image width for `--pixel`.
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Image height for `--pixel`.
    #[arg(long, default_value_t = 768)]
    pub height: u32,
    /// Explain the any-hit (occlusion) query instead of the closest hit.
    #[arg(long)]
    pub any: bool,
    /// Print at most this many steps (a grid can test hundreds of primitives per ray).
    #[arg(long, default_value = "400", value_parser = crate::cli::count)]
    pub max_steps: usize,
}

/// The ray `args` names: `--ray`, or the primary ray of `--pixel` (default the centre pixel)
/// with the camera `compare` uses for the scene.
///
/// # Errors
/// A one-line description of a malformed ray or pixel.
pub fn chosen_ray(args: &ExplainArgs, scene: &str, bounds: &Aabb) -> Result<Ray, String> {
    if let Some(text) = &args.ray {
        let rays = parse_rays(text).map_err(|(_, e)| format!("--ray \"{text}\": {e}"))?;
        return match rays[..] {
            [ray] => Ok(ray),
            _ => Err(format!("--ray \"{text}\": expected one ray")),
        };
    }
    if args.width == 0 || args.height == 0 || args.width > 1 << 15 || args.height > 1 << 15 {
        return Err(format!(
            "--width {} --height {}: each must be 1 to 32768",
            args.width, args.height
        ));
    }
    let (x, y) = match &args.pixel {
        None => (args.width / 2, args.height / 2),
        Some(p) => {
            let parsed = p
                .split_once(',')
                .and_then(|(x, y)| Some((x.trim().parse().ok()?, y.trim().parse().ok()?)));
            match parsed {
                Some((x, y)) if x < args.width && y < args.height => (x, y),
                _ => {
                    return Err(format!(
                        "--pixel {p}: expected X,Y inside the {}x{} image",
                        args.width, args.height
                    ));
                }
            }
        }
    };
    let camera = scenes::camera_for(scene, bounds, args.width, args.height);
    Ok(camera
        .raster(args.width, args.height)
        .ray(x as f32 + 0.5, y as f32 + 0.5))
}

/// The walk of the ray `args` names through each of its rows on its scene, as text, one row
/// after another: a header, one line per step, the answer, the counts, and brute force's answer.
///
/// # Errors
/// A one-line description of an unknown row or scene, an unreadable file, or a bad ray.
pub fn explain(args: &ExplainArgs, entries: &[Entry]) -> Result<String, String> {
    let rows = crate::cli::rows_or(&args.structures, &[crate::cli::DEFAULT_ROW]);
    let rows: Vec<Entry> = rows
        .iter()
        .map(|name| structures::find(entries, name))
        .collect::<Result<_, _>>()?;
    let (_, triangles) = crate::scene::load_scene(&args.scene)?;
    let bounds = rt_core::valid_bounds(triangles.iter());
    let ray = chosen_ray(args, &args.scene, &bounds)?;
    let walks: Vec<String> = rows
        .iter()
        .map(|entry| explain_one(args, entry, &triangles, &ray))
        .collect();
    Ok(walks.join("\n"))
}

/// One row's walk of `ray` (see [`explain`]).
fn explain_one(args: &ExplainArgs, entry: &Entry, triangles: &[Triangle], ray: &Ray) -> String {
    let ray = *ray;
    let built = (entry.build)(triangles);
    let query = if args.any { Query::Any } else { Query::Closest };
    let (answer, trace) = built.trace_dyn(&ray, query == Query::Any);

    let mut out = format!(
        "{} on {} ({} triangles), {} query\n",
        entry.name,
        args.scene,
        triangles.len(),
        if args.any { "any-hit" } else { "closest-hit" }
    );
    let v = |v: rt_core::glam::Vec3| format!("{} {} {}", v.x, v.y, v.z);
    out += &format!(
        "ray: {} {} {} {} (as a rays-file line)\n\n",
        v(ray.origin),
        v(ray.dir()),
        ray.t_min,
        ray.t_max
    );
    let text = trace.to_string();
    let lines: Vec<&str> = text.lines().collect();
    for line in lines.iter().take(args.max_steps) {
        out += line;
        out.push('\n');
    }
    if lines.len() > args.max_steps {
        out += &format!(
            "... {} more steps (--max-steps to see them)\n",
            lines.len() - args.max_steps
        );
    }
    if trace.events.is_empty() {
        out += &format!(
            "({} reports no steps, only the counts below: its traversal calls \
             stats.node_visit() and stats.prim_test() but not Stats::event; the helpers of \
             rt_core::trace (report, tested, blocked) add the steps)\n",
            entry.name
        );
    }
    let c = trace.counters;
    out += &format!(
        "\nanswer: {}\n{} nodes or cells entered, {} primitive tests, {} mailbox skips\n",
        describe(answer, args.any),
        c.node_visits,
        c.prim_tests,
        c.mailbox_skips
    );
    let reference = BruteForce::build(triangles, &());
    let expected = if args.any {
        reference.occluded(&ray).then_some(Hit {
            prim: u32::MAX,
            t: f32::NAN,
            u: 0.0,
            v: 0.0,
        })
    } else {
        reference.intersect(&ray)
    };
    let agree = if args.any {
        expected.is_some() == answer.is_some()
    } else {
        Hit::agree(expected, answer)
    };
    out += &if agree {
        "brute force gives the same answer\n".to_string()
    } else {
        format!("brute force DISAGREES: {}\n", describe(expected, args.any))
    };
    out
}

fn describe(hit: Option<Hit>, any: bool) -> String {
    match (hit, any) {
        (None, _) => "no hit".into(),
        (Some(_), true) => "occluded".into(),
        (Some(h), false) => format!(
            "primitive {} at t = {} (u = {}, v = {})",
            h.prim, h.t, h.u, h.v
        ),
    }
}

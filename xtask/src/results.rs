//! `cargo xtask results`: the pages of measurements the README, the guide and the crate docs
//! link to (through the index `docs/results.md`), so that no figure is copied into a doc where
//! it would go stale. One page per machine kind (`docs/results/KIND.md`,
//! [`rt_shootout::measure::machine_kind`]): a run on one CPU writes its own kind's page and
//! leaves the others'.
//!
//! It runs a fixed list of this binary's own commands (`compare`, `scale`, `animate`, each with
//! `--json`) as child processes, exactly as the page shows them, and writes their figures as
//! Markdown tables under a stamp of the date, the commit and the CPU. With `--embree` it also runs
//! the Embree benchmark (`cargo bench -p rt-benches --features embree --bench peers`) and embeds
//! its tables. Any mismatch or failure in any command fails the page: a page is written only
//! from runs whose every answer was checked.

use rt_shootout::data::three_digits;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Where the pages live: one per machine kind, and the index that lists them.
const PAGES_DIR: &str = "docs/results";
const INDEX: &str = "docs/results.md";

/// Flags of `cargo xtask results`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The page to write. By default this machine kind's page, `docs/results/KIND.md` (`KIND`
    /// as `amd-zen4`, `amd-zen5`, `intel-emerald-rapids`), after which the index
    /// `docs/results.md` is written again to list every machine kind's page.
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Only write the index `docs/results.md` again from the pages in `docs/results/`.
    #[arg(long, conflicts_with_all = ["out", "quick", "embree", "python"])]
    pub index: bool,
    /// A small page from small runs on built-in scenes (seconds instead of minutes), to check
    /// the generator itself; its figures measure nothing worth quoting.
    #[arg(long)]
    pub quick: bool,
    /// Also measure rt-bvh against Embree 3 (needs Debian's libembree-dev).
    #[arg(long)]
    pub embree: bool,
    /// Also measure the Python package against the Python tools people use (Open3D, embreex,
    /// libigl, point-cloud-utils, fcpw, those installed) with this Python interpreter: the
    /// package is installed into its environment from `python/` first.
    #[arg(long, value_name = "PYTHON")]
    pub python: Option<PathBuf>,
}

/// The rows every shootout table shows: each structure's default and the presets the guide
/// discusses.
const ROWS: &str =
    "bvh,bvh-binary,bvh-median,bvh-middle,bvh-reinserted,kdtree,kdtree-restart,grid,hgrid,octree";

/// One structure of each kind, for the tables that compare kinds.
const MAIN_ROWS: &str = "bvh,kdtree,grid,hgrid,octree";
/// The rows of the bundle table: the main rows and the binary BVH, whose bundle walk differs
/// from the wide tree's.
const BUNDLE_ROWS: &str = "bvh,bvh-binary,kdtree,grid,hgrid,octree";

/// The bunny, for the runs on a real mesh (the built-in scenes are procedural).
const BUNNY: &str = "../shared/meshes/stanford-bunny.obj";

/// What one page holds: the arguments of each run, by section.
struct Plan {
    scenes: Vec<&'static str>,
    rows: &'static str,
    image: [&'static str; 4],
    other_rays: Vec<&'static str>,
    real: &'static str,
    points: &'static str,
    instances: &'static str,
    scale: [&'static str; 4],
    animate: Vec<&'static str>,
    more: Vec<&'static str>,
    bundles: Vec<&'static str>,
}

impl Plan {
    fn new(quick: bool) -> Self {
        if quick {
            return Self {
                scenes: vec!["sphereflake:20k", "random-soup:5k"],
                rows: "bvh,kdtree,grid",
                image: ["--width", "64", "--height", "48"],
                other_rays: vec!["random-soup:5k"],
                real: "sphereflake:20k",
                points: "2k",
                instances: "9",
                scale: ["--min", "1k", "--max", "3k"],
                animate: vec!["--scene", "teapot:2k", "--frames", "2"],
                more: vec!["sphereflake:20k", "random-soup:5k"],
                bundles: vec!["sphereflake:20k"],
            };
        }
        Self {
            scenes: vec![
                BUNNY,
                "sphereflake",
                "teapot-in-stadium",
                "random-soup",
                "terrain",
            ],
            rows: ROWS,
            image: ["--width", "1024", "--height", "768"],
            other_rays: vec![BUNNY, "teapot-in-stadium"],
            real: BUNNY,
            points: "100k",
            instances: "1000",
            scale: ["--min", "10k", "--max", "1M"],
            animate: vec![],
            more: vec![
                "../shared/meshes/teapot.obj",
                "../shared/meshes/beetle-alt.obj",
                "../shared/meshes/rocker-arm.obj",
                "../shared/meshes/cheburashka.obj",
                "../shared/meshes/fandisk.obj",
                "../shared/meshes/homer.obj",
            ],
            bundles: vec![
                BUNNY,
                "sphereflake",
                "teapot-in-stadium",
                "../shared/meshes/rocker-arm.obj",
            ],
        }
    }
}

/// Why no page was written.
#[derive(Debug)]
pub enum Failure {
    /// Bad input, found before anything ran (exit status 2).
    BadInput(String),
    /// A measurement failed or found a mismatch (exit status 1).
    Run(String),
}

/// Runs the task: every measurement, then the page (and the index, for the default page).
/// Returns the path written.
pub fn run(args: &Args) -> Result<PathBuf, Failure> {
    if args.index {
        return write_index().map_err(Failure::Run);
    }
    let out = page_path(args);
    crate::render::check_output(&out, "Markdown").map_err(Failure::BadInput)?;
    if !args.quick && !Path::new(BUNNY).is_file() {
        return Err(Failure::BadInput(format!(
            "{BUNNY} not found: run from the repository root with the shared meshes beside it \
             (or use --quick)"
        )));
    }
    let page = measure_all(args, &out).map_err(Failure::Run)?;
    if args.out.is_none() {
        write_index().map_err(Failure::Run)?;
    }
    Ok(page)
}

/// The page `args` write: `--out`, else this machine kind's page.
fn page_path(args: &Args) -> PathBuf {
    args.out.clone().unwrap_or_else(|| {
        Path::new(PAGES_DIR).join(format!("{}.md", rt_shootout::measure::machine_kind().slug))
    })
}

/// Writes the index, `docs/results.md`: every page in `docs/results/` with its stamp.
fn write_index() -> Result<PathBuf, String> {
    let mut pages: Vec<PathBuf> = std::fs::read_dir(PAGES_DIR)
        .map_err(|e| format!("{PAGES_DIR}: {e}"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    let mut index = String::from(
        "# Results\n\nThe measurements, one page per kind of machine they were made on, so that a \
         run on one CPU never overwrites another's figures: what is fastest differs between CPUs \
         (see the kernel table, `cargo bench -p rt-benches --bench kernels`). Each page is \
         written by `cargo xtask results --embree --python PYTHON` on its machine (`PYTHON` \
         an interpreter whose environment has the Python peers), stamped with the date, the \
         commit, the CPU and its kind, and has the same sections: primary rays, more meshes, \
         other rays, one thread, ray bundles, closest points, signed distance, instances, scale, \
         dynamic scenes, saved structures, kernels on this CPU, rt-bvh against Embree 3, and \
         rt_accel against the Python tools. A page older than a section lacks it. Compare figures within one page; across pages, \
         compare ratios.\n\n| machine kind | written |\n| --- | --- |\n",
    );
    for page in &pages {
        let text = std::fs::read_to_string(page).map_err(|e| format!("{}: {e}", page.display()))?;
        let stamp = text
            .lines()
            .find(|l| l.starts_with("Written by "))
            .ok_or_else(|| {
                format!(
                    "{}: no stamp (a line starting `Written by`)",
                    page.display()
                )
            })?;
        let name = page
            .file_stem()
            .map_or(String::new(), |s| s.to_string_lossy().into_owned());
        let _ = writeln!(index, "| [{name}](results/{name}.md) | {stamp} |");
    }
    std::fs::write(INDEX, index).map_err(|e| format!("{INDEX}: cannot write: {e}"))?;
    Ok(PathBuf::from(INDEX))
}

fn measure_all(args: &Args, out: &Path) -> Result<PathBuf, String> {
    let plan = Plan::new(args.quick);
    let started = Instant::now();
    let mut page = stamp(args)?;
    let image: Vec<&str> = plan.image.to_vec();

    page += "\n## Primary rays\n\nOne ray per pixel from a view each scene fills (`compare`'s \
             default `--view filled`: a built-in scene's own camera where it has one, else the \
             scene box's centre seen from 1.5 radii of its bounding sphere), every answer \
             checked (against brute force on a random subset of 20,000 rays, and against each \
             other on all of them); builds and traces on every thread. The hit share says how \
             many rays hit the mesh: a view where most rays miss times the call, not the \
             traversal.\n";
    for scene in &plan.scenes {
        let mut argv = vec!["compare", "--scene", scene, "-s", plan.rows];
        argv.extend(&image);
        argv.push("--json");
        let run = measure(&argv)?;
        shootout_table(&mut page, &run);
    }

    page += "\n## More meshes\n\nPrimary rays on meshes nothing here was tuned on, one of each \
             structure; Mrays/s (all threads), every answer checked.\n\n";
    let mut runs = Vec::new();
    for scene in &plan.more {
        let mut argv = vec!["compare", "--scene", scene, "-s", MAIN_ROWS];
        argv.extend(&image);
        argv.push("--json");
        runs.push(measure(&argv)?);
    }
    speed_table(&mut page, &runs);

    page += "\n## Other rays\n\nIncoherent rays (random origins in the scene box, random \
             directions, as many as the image has pixels), diffuse bounces (from each primary \
             hit, a cosine-weighted direction about the surface normal) and shadow rays (from \
             each primary hit to a point light, any-hit queries).\n";
    for scene in &plan.other_rays {
        for kind in ["incoherent", "diffuse", "shadow"] {
            let mut argv = vec!["compare", "--scene", scene, "--rays", kind, "-s", plan.rows];
            argv.extend(&image);
            argv.push("--json");
            let run = measure(&argv)?;
            shootout_table(&mut page, &run);
        }
    }

    page += "\n## One thread\n\nThe same primary rays with builds and traces on one thread.\n";
    let mut argv = vec!["compare", "--scene", plan.real, "-s", plan.rows, "-j", "1"];
    argv.extend(&image);
    argv.push("--json");
    let run = measure(&argv)?;
    shootout_table(&mut page, &run);

    page += "\n## Ray bundles\n\nThe same rays traced as bundles (`Accel::intersect_bundle`, \
             `occluded_bundle`): primary rays of the filled view in 8×8 pixel tiles, the shadow \
             rays of their hits in that order, and incoherent rays as they come (which bundles \
             must not trace slower than single rays), on one thread; each bundle pass timed \
             right after the same row's single rays, every bundle answer checked bit for bit \
             against the single answer. Structures without a bundle traversal trace every ray \
             alone.\n\n";
    let mut runs = Vec::new();
    for kind in ["primary", "shadow", "incoherent"] {
        for scene in &plan.bundles {
            let mut argv = vec![
                "compare",
                "--scene",
                scene,
                "--rays",
                kind,
                "-s",
                BUNDLE_ROWS,
            ];
            argv.extend(["--bundle", "8x8", "-j", "1"]);
            argv.extend(&image);
            argv.push("--json");
            runs.push(measure(&argv)?);
        }
    }
    bundle_table(&mut page, &runs);
    // Minutes of runs over the peers' scenes: the quick page, which checks the generator, leaves
    // it out.
    if !args.quick {
        page += &one_ray_bundles()?;
    }

    let closest = "\n## Closest points\n\nThe primitive nearest to each point: half of the points \
                   anywhere in the scene box grown by a quarter on every side, half within 2% of \
                   its diagonal from the surface.\n";
    let signed = "\n## Signed distance\n\nThe same points' signed distance: each row's closest \
                  point, signed by one winding tree every row shares (built once, outside the \
                  rows' figures); brute force signs with the exact winding number over every \
                  triangle. The share is of the points inside.\n";
    for (query, section) in [("closest-point", closest), ("signed-distance", signed)] {
        page += section;
        let argv = [
            "compare",
            "--scene",
            plan.real,
            "--query",
            query,
            "--points",
            plan.points,
            "-s",
            "bvh,kdtree,grid,hgrid,octree",
            "--json",
        ];
        let run = measure(&argv)?;
        shootout_table(&mut page, &run);
    }

    page += "\n## Instances\n\nA field of instances of one mesh (each rotated, scaled unevenly, \
             every seventh mirrored) under rt-bvh's top-level BVH, each row's structure built \
             once and shared by every instance.\n";
    let mut argv = vec![
        "compare",
        "--scene",
        plan.real,
        "--instances",
        plan.instances,
        "-s",
        "bvh,bvh-binary,kdtree,grid,hgrid,octree",
    ];
    argv.extend(&image);
    argv.push("--json");
    let run = measure(&argv)?;
    shootout_table(&mut page, &run);

    page += "\n## Scale\n\nEach structure built and traced on the terrain at growing sizes \
             (256×192 primary rays per size), answers checked against the first row.\n";
    let mut argv = vec!["scale", "--scene", "terrain"];
    argv.extend(plan.scale);
    argv.push("--json");
    let run = measure(&argv)?;
    scale_table(&mut page, &run);

    page += "\n## Dynamic scenes\n\nThe teapot exploding: each frame refitted (structures that \
             can refit) and rebuilt, then traced; every frame checked against brute force.\n";
    let mut argv = vec!["animate"];
    argv.extend(&plan.animate);
    argv.push("--json");
    let run = measure(&argv)?;
    animate_table(&mut page, &run);

    // Minutes of builds at 10M triangles: the quick page leaves it out too.
    if !args.quick {
        page += &saved()?;
        page += &kernels()?;
    }

    if args.embree {
        page += &embree()?;
    }
    if let Some(python) = &args.python {
        page += &python_peers(python)?;
    }
    let _ = writeln!(
        page,
        "\n---\nAll runs took {:.0} s.",
        started.elapsed().as_secs_f64()
    );
    std::fs::write(out, page).map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
    Ok(out.to_path_buf())
}

/// One finished run: its command line as the page shows it, and its JSON.
struct Run {
    command: String,
    json: Value,
}

/// Runs `cargo xtask ARGV...` (this very binary) and parses its JSON; fails on any exit status
/// but 0, which includes any answer that disagreed with brute force.
fn measure(argv: &[&str]) -> Result<Run, String> {
    let command = format!("cargo xtask {}", argv.join(" "));
    eprintln!("{command}");
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this binary: {e}"))?;
    let out = Command::new(exe)
        .args(argv)
        .output()
        .map_err(|e| format!("{command}: cannot run: {e}"))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(format!(
            "{command} failed ({}): {}",
            out.status,
            err.lines().next().unwrap_or("")
        ));
    }
    let json = serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("{command}: its output is not one JSON object: {e}"))?;
    Ok(Run { command, json })
}

/// The page's first lines: what it is, and when, where and on what it was measured.
fn stamp(args: &Args) -> Result<String, String> {
    let git = |a: &[&str]| {
        Command::new("git")
            .args(a)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
    };
    let commit = git(&["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into());
    let dirty =
        git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    let cpu = rt_shootout::measure::cpu_model();
    let kind = rt_shootout::measure::machine_kind().name;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rustc = Command::new("rustc")
        .arg("--version")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_else(|| "rustc (unknown version)".into());
    let mut s = String::from("# Results\n\n");
    if args.quick {
        s += "**A quick page from small runs, for checking the generator: its figures measure \
              nothing worth quoting.**\n\n";
    }
    let _ = writeln!(
        s,
        "Written by `cargo xtask results{}{}{}` on {} (UTC) at commit {commit}{}, on {cpu} \
         ({kind}) with {threads} threads, built by {rustc} with the workspace's release profile \
         (`codegen-units = 1`, thin LTO).\n",
        if args.quick { " --quick" } else { "" },
        if args.embree { " --embree" } else { "" },
        if args.python.is_some() {
            " --python PYTHON"
        } else {
            ""
        },
        today(),
        if dirty {
            " plus uncommitted changes"
        } else {
            ""
        },
    );
    s += "Every figure below comes from the command printed above its table, run by that \
          command in this page's run. Absolute speeds move by up to ±30% between runs on a \
          shared machine; ratios within one table are what to compare. A program that depends \
          on these crates builds with its own release profile: see the guide's page on using \
          the crates for what that changes.\n";
    Ok(s)
}

/// Today's date, `YYYY-MM-DD`, from the system clock (civil-from-days, Howard Hinnant's
/// algorithm).
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// A `compare --json` run as a table: per row build time, memory, visits and tests per query,
/// speed and the speedup over brute force.
fn shootout_table(page: &mut String, run: &Run) {
    let j = &run.json;
    let signed = j["query"] == "signed-distance";
    let points = j["query"] == "closest-point" || signed;
    let (unit, speed) = if points {
        ("query", "Mqueries/s")
    } else {
        ("ray", "Mrays/s")
    };
    let verb = if signed { "are inside" } else { "hit" };
    let hits = j["hit_share"].as_f64().map_or(String::new(), |h| {
        format!(", {:.1}% of them {verb}", 100.0 * h)
    });
    let _ = writeln!(
        page,
        "\n### {} ({} triangles), {} {}{hits}\n\n`{}` ({} threads, {} checked against brute \
         force, 0 mismatches)\n",
        j["scene"].as_str().unwrap_or("?"),
        j["triangles"],
        j["rays"],
        if signed {
            "signed-distance queries".to_owned()
        } else if points {
            "closest-point queries".to_owned()
        } else {
            format!("{} rays", j["ray_kind"].as_str().unwrap_or("?"))
        },
        run.command,
        j["threads"],
        j["checked_rays"],
    );
    let _ = writeln!(
        page,
        "| structure | build ms | memory MiB | visits/{unit} | tests/{unit} | {speed} | × brute force |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for row in j["results"].as_array().into_iter().flatten() {
        let _ = writeln!(
            page,
            "| {} | {} | {:.2} | {} | {} | {} | {:.0} |",
            row["structure"].as_str().unwrap_or("?"),
            three_digits(f(&row["build_ms"])),
            f(&row["memory_bytes"]) / (1024.0 * 1024.0),
            three_digits(f(&row["avg_visits"])),
            three_digits(f(&row["avg_prim_tests"])),
            three_digits(f(&row["mrays_per_s"])),
            f(&row["speedup"]),
        );
    }
}

/// The rows of a `compare --json` run, brute force left out.
fn row_names(run: &Run) -> Vec<String> {
    run.json["results"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|r| r["structure"].as_str().map(String::from))
        .filter(|name| name != "brute-force")
        .collect()
}

/// The figures of row `name` in a `compare --json` run.
fn result<'a>(json: &'a Value, name: &str) -> Option<&'a Value> {
    json["results"]
        .as_array()
        .into_iter()
        .flatten()
        .find(|r| r["structure"] == name)
}

/// Several `compare --json` runs as one table: per scene its size, hit share and every row's
/// speed, the commands listed under it.
fn speed_table(page: &mut String, runs: &[Run]) {
    let Some(first) = runs.first() else { return };
    let rows = row_names(first);
    let _ = writeln!(
        page,
        "| scene | triangles | hit | {} |\n| --- | ---: | ---: |{}",
        rows.join(" | "),
        " ---: |".repeat(rows.len())
    );
    for run in runs {
        let j = &run.json;
        let speed =
            |name: &str| result(j, name).map_or("-".into(), |r| three_digits(f(&r["mrays_per_s"])));
        let cells: Vec<String> = rows.iter().map(|n| speed(n)).collect();
        let _ = writeln!(
            page,
            "| {} | {} | {:.1}% | {} |",
            j["scene"].as_str().unwrap_or("?"),
            j["triangles"],
            100.0 * f(&j["hit_share"]),
            cells.join(" | ")
        );
    }
    page.push('\n');
    for run in runs {
        let _ = writeln!(page, "- `{}`", run.command);
    }
}

/// `compare --bundle --json` runs as one table: per scene and ray kind its hit share and, per
/// row, the bundles' Mrays/s with their ratio to the row's single rays; the commands under it.
fn bundle_table(page: &mut String, runs: &[Run]) {
    let Some(first) = runs.first() else { return };
    let rows = row_names(first);
    let _ = writeln!(
        page,
        "| scene | rays | hit | {} |\n| --- | --- | ---: |{}",
        rows.join(" | "),
        " ---: |".repeat(rows.len())
    );
    for run in runs {
        let j = &run.json;
        let cell = |name: &str| {
            result(j, name).map_or("-".into(), |r| {
                let b = &r["bundle"];
                format!(
                    "{} ({:.2}×)",
                    three_digits(f(&b["mrays_per_s"])),
                    f(&b["over_single"])
                )
            })
        };
        let cells: Vec<String> = rows.iter().map(|n| cell(n)).collect();
        let _ = writeln!(
            page,
            "| {} | {} | {:.1}% | {} |",
            j["scene"].as_str().unwrap_or("?"),
            j["ray_kind"].as_str().unwrap_or("?"),
            100.0 * f(&j["hit_share"]),
            cells.join(" | ")
        );
    }
    // The geometric mean of the ratios per ray kind, over the scenes: the figure the bundles
    // are judged by.
    let mut kinds: Vec<&str> = Vec::new();
    for run in runs {
        let kind = run.json["ray_kind"].as_str().unwrap_or("?");
        if !kinds.contains(&kind) {
            kinds.push(kind);
        }
    }
    for kind in kinds {
        let of_kind: Vec<&Run> = runs
            .iter()
            .filter(|r| r.json["ray_kind"].as_str() == Some(kind))
            .collect();
        let cells: Vec<String> = rows
            .iter()
            .map(|name| {
                let ratios: Vec<f64> = of_kind
                    .iter()
                    .filter_map(|r| result(&r.json, name))
                    .map(|r| f(&r["bundle"]["over_single"]))
                    .filter(|x| *x > 0.0)
                    .collect();
                if ratios.is_empty() {
                    return "-".into();
                }
                let mean = ratios.iter().map(|x| x.ln()).sum::<f64>() / ratios.len() as f64;
                format!("**{:.2}×**", mean.exp())
            })
            .collect();
        let _ = writeln!(
            page,
            "| geometric mean | {kind} | | {} |",
            cells.join(" | ")
        );
    }
    page.push_str(
        "\nMrays/s of the bundles (their speed ÷ the same row's single rays); the last \
                   rows, the geometric means of those ratios over the scenes.\n\n",
    );
    for run in runs {
        let _ = writeln!(page, "- `{}`", run.command);
    }
}

/// A `scale --json` run as a table: per size and row the build and trace cost, bytes per
/// triangle and the build's peak memory.
fn scale_table(page: &mut String, run: &Run) {
    let j = &run.json;
    let _ = writeln!(
        page,
        "\n`{}` ({} threads, {} rays per size)\n\n| triangles | structure | build ns/triangle | trace ns/ray | bytes/triangle | build peak MiB | scratch × |\n| ---: | --- | ---: | ---: | ---: | ---: | ---: |",
        run.command, j["threads"], j["rays"]
    );
    for p in j["points"].as_array().into_iter().flatten() {
        let _ = writeln!(
            page,
            "| {} | {} | {} | {} | {} | {} | {} |",
            p["triangles"],
            p["structure"].as_str().unwrap_or("?"),
            three_digits(f(&p["build_ns_per_triangle"])),
            three_digits(f(&p["trace_ns_per_ray"])),
            three_digits(f(&p["bytes_per_triangle"])),
            p["peak_build_bytes"]
                .as_f64()
                .map_or("n/a".into(), |b| three_digits(b / (1024.0 * 1024.0))),
            three_digits(f(&p["scratch_ratio"])),
        );
    }
}

/// An `animate --json` run as a table: per row and strategy, the update and trace time and the
/// SAH cost of the first, second and last frames.
fn animate_table(page: &mut String, run: &Run) {
    let j = &run.json;
    let _ = writeln!(
        page,
        "\n`{}` ({}, {} triangles, {} threads, {} checked rays per frame, 0 mismatches)\n\n| structure | strategy | frame | update ms | trace ms | SAH cost |\n| --- | --- | ---: | ---: | ---: | ---: |",
        run.command,
        j["animation"].as_str().unwrap_or("?"),
        j["triangles"],
        j["threads"],
        j["checked"],
    );
    for t in j["tracks"].as_array().into_iter().flatten() {
        let frames = t["frames"].as_array().cloned().unwrap_or_default();
        let last = frames.len().saturating_sub(1);
        for (i, fr) in frames.iter().enumerate() {
            if i > 1 && i != last {
                continue;
            }
            let _ = writeln!(
                page,
                "| {} | {} | {} | {} | {} | {} |",
                t["structure"].as_str().unwrap_or("?"),
                t["strategy"].as_str().unwrap_or("?"),
                fr["frame"],
                three_digits(f(&fr["update_ms"])),
                three_digits(f(&fr["trace_ms"])),
                three_digits(f(&fr["sah"])),
            );
        }
    }
}

/// Runs `cargo bench -p rt-benches` with `args` and gives back the command as the page shows it
/// and what it printed; a bench that cannot run or fails is an error naming the command and its
/// last line.
fn cargo_bench(args: &[&str]) -> Result<(String, String), String> {
    let mut argv = vec!["bench", "-p", "rt-benches"];
    argv.extend(args);
    let command = format!("cargo {}", argv.join(" "));
    eprintln!("{command}");
    let out = Command::new("cargo")
        .args(&argv)
        .output()
        .map_err(|e| format!("{command}: cannot run: {e}"))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let last = err
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        return Err(format!("{command} failed ({}): {last}", out.status));
    }
    Ok((command, String::from_utf8_lossy(&out.stdout).into_owned()))
}

/// What a bundle of one ray costs against a single-ray call: the `bundle_of_one` benchmark's
/// own tables.
fn one_ray_bundles() -> Result<String, String> {
    let (command, table) = cargo_bench(&["--bench", "bundle_of_one"])?;
    Ok(format!(
        "\n### One-ray bundles\n\n`{command}`: a renderer that hands over one ray at a time \
         through the bundle queries must not pay for them (the target: at most 2% more than \
         the single-ray call).\n\n{table}"
    ))
}

/// Loading saved structures against building them: the saved benchmark's own table.
fn saved() -> Result<String, String> {
    let (command, table) = cargo_bench(&["--bench", "saved"])?;
    Ok(format!(
        "\n## Saved structures\n\n`{command}`: each structure built, saved to a file and \
         loaded from it (read warm from the page cache, framing and checksum checked, every \
         invariant validated), each the median of three runs, both on all threads. Every \
         loaded structure traces a 128 × 128 camera's primary rays and must answer them bit \
         for bit as the built one (the hit share beside).\n\n{table}"
    ))
}

/// Which instruction set traces fastest on this CPU: the kernels benchmark's own tables.
fn kernels() -> Result<String, String> {
    let (command, tables) = cargo_bench(&["--bench", "kernels"])?;
    Ok(format!(
        "\n## Kernels on this CPU\n\n`{command}`: rt-bvh's wide tree traced with every \
         instruction set this CPU runs, each forced in turn on the same tree and the same rays \
         (primary and shadow rays from the view each scene fills, incoherent rays), over every \
         built-in scene and shared mesh, one thread, passes interleaved, medians; every set's \
         answers equal the portable kernels' bit for bit. The run-time choice \
         (`rt_simd::Isa::detect`) should be the fastest here.\n{tables}"
    ))
}

/// The Python package against the Python tools: `python/bench/peers.py`'s own tables, run by
/// `python` after installing the package from this tree into its environment.
fn python_peers(python: &Path) -> Result<String, String> {
    let run = |args: &[&str]| -> Result<(String, String), String> {
        let command = format!("python {}", args.join(" "));
        eprintln!("{command}");
        let out = Command::new(python)
            .args(args)
            .output()
            .map_err(|e| format!("{}: cannot run: {e}", python.display()))?;
        if !out.status.success() {
            let err = String::from_utf8_lossy(&out.stderr);
            let last = err.lines().rev().find(|l| !l.trim().is_empty());
            return Err(format!(
                "{command} failed ({}): {}",
                out.status,
                last.unwrap_or("")
            ));
        }
        Ok((command, String::from_utf8_lossy(&out.stdout).into_owned()))
    };
    let (install, _) = run(&["-m", "pip", "install", "--quiet", "./python"])?;
    let (command, tables) = run(&["python/bench/peers.py", "--repeats", "3"])?;
    Ok(format!(
        "\n## rt_accel against the Python tools\n\n`{install}`, then `{command}`: the Python \
         package (`rt_accel`, the wide BVH) and the tools Python users have today on the same \
         triangles, rays and points, every query on all threads where the tool has threads, \
         best of three, the crossing from Python included on both sides. Primary rays come \
         from a view each mesh fills (the hit share beside), scattered rays join random points \
         of the mesh's box, shadow rays go from the primary hits to a light; points lie half \
         in the box grown by a quarter, half near the surface. Ratios are the tool's time over \
         rt_accel's (above 1, rt_accel is faster); the last column compares the answers, and \
         counts the signs that differ from rt_accel's exact winding-number signs.\n\n{tables}"
    ))
}

/// rt-bvh against Embree 3: the peers benchmark's own tables.
fn embree() -> Result<String, String> {
    let (command, tables) = cargo_bench(&["--features", "embree", "--bench", "peers"])?;
    Ok(format!(
        "\n## rt-bvh against Embree 3\n\n`{command}`: rt-bvh's presets and Embree 3 on the same \
         triangles and the same rays, traced on one thread, passes interleaved, medians. \
         Primary and shadow rays come from the view each scene fills (as `compare`'s default \
         `--view filled`), and the ratios judge rt-bvh on those and on incoherent rays; the \
         sparse rows repeat them from the sparse view (`--view sparse`), where most rays of a \
         compact mesh leave its box after one test, which times the cost of a call more than \
         a traversal. Each ray set's hit share stands beside its speeds.\n\n{tables}"
    ))
}

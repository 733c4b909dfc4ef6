//! Grading one row: the conformance kit's scenes passed or failed (with the first failing ray of
//! each), and the shootout against reference structures, as JSON and Markdown for a teacher.

use crate::compare::{self, Args};
use crate::data::Report;
use crate::structures::{self, Builder, Entry, Query};
use rt_conformance::SCENES;
use rt_core::DynAccel;
use rt_core::{Accel, BuildStats, Hit, Region, Stats, Triangle};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A row's builder as the parameters of an [`Accel`], so the conformance kit, which checks
/// types, can check a row it only knows as a builder.
#[derive(Clone, Default)]
pub struct RowParams(Option<Builder>);

impl std::fmt::Debug for RowParams {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("row")
    }
}

/// A built row as an [`Accel`]: each query asks the row and replays its counted events into the
/// caller's sink.
pub struct Row(Arc<dyn DynAccel<Triangle>>);

impl std::fmt::Debug for Row {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Row")
    }
}

/// Asks the row, traced when the sink traces (so the kit's checks of the trace see the row's
/// events), and replays what it reported into `stats`.
fn ask<S: Stats>(
    row: &dyn DynAccel<Triangle>,
    ray: &rt_core::Ray,
    query: Query,
    stats: &mut S,
) -> Option<Hit> {
    if S::TRACE {
        let (hit, trace) = row.trace_dyn(ray, query == Query::Any);
        replay(trace.counters, stats);
        for e in trace.events {
            stats.event(e);
        }
        hit
    } else {
        let (hit, c) = structures::answer_counted(row, ray, query);
        replay(c, stats);
        hit
    }
}

fn replay<S: Stats>(c: rt_core::Counters, stats: &mut S) {
    for _ in 0..c.node_visits {
        stats.node_visit();
    }
    for _ in 0..c.prim_tests {
        stats.prim_test();
    }
    for _ in 0..c.mailbox_skips {
        stats.mailbox_skip();
    }
}

impl Accel for Row {
    type Prim = Triangle;
    type Params = RowParams;
    const NAME: &'static str = "the graded row";
    fn presets() -> Vec<(&'static str, RowParams)> {
        vec![("default", RowParams::default())]
    }
    fn build(prims: &[Triangle], params: &RowParams) -> Self {
        let build = params
            .0
            .clone()
            .unwrap_or_else(|| structures::brute_force().build);
        Row(build(prims))
    }
    fn intersect_with<S: Stats>(&self, ray: &rt_core::Ray, stats: &mut S) -> Option<Hit> {
        ask(self.0.as_ref(), ray, Query::Closest, stats)
    }
    fn occluded_with<S: Stats>(&self, ray: &rt_core::Ray, stats: &mut S) -> bool {
        ask(self.0.as_ref(), ray, Query::Any, stats).is_some()
    }
    fn bounds(&self) -> rt_core::Aabb {
        self.0.bounds_dyn()
    }
    /// The row's own ball query, its counts replayed into `stats` when it returns.
    fn ball_query<Q: rt_core::BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        let mut c = rt_core::Counters::default();
        self.0.ball_query_dyn(query, Some(&mut c));
        replay(c, stats);
    }
    /// The row's own box query, its counts replayed into `stats` when it returns.
    fn box_query<Q: rt_core::BoxQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        let mut c = rt_core::Counters::default();
        self.0.box_query_dyn(query, Some(&mut c));
        replay(c, stats);
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes_dyn()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats_dyn()
    }
    fn regions(&self, visit: &mut dyn FnMut(Region)) {
        for r in self.0.regions_dyn() {
            visit(r);
        }
    }
}

/// One check of the kit: a scene (or the random-scene run) and its outcome.
#[derive(Clone, Debug)]
pub struct Check {
    /// The scene's name, or `random_scenes`.
    pub scene: String,
    /// The failure (naming the first failing ray), or `None` if it passed.
    pub failure: Option<String>,
}

/// Runs every adversarial scene of the kit and the random-scene proptest on `entry`.
pub fn kit(entry: &Entry) -> Vec<Check> {
    let params = RowParams(Some(entry.build.clone()));
    let mut checks: Vec<Check> = SCENES
        .iter()
        .map(|&name| {
            let s = rt_conformance::scene(name);
            Check {
                scene: name.to_string(),
                failure: rt_conformance::check_case::<Row>(&params, &s.triangles, &s.rays).err(),
            }
        })
        .collect();
    let random = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        rt_conformance::check_random::<Row>(&params)
    }));
    checks.push(Check {
        scene: "random_scenes".into(),
        failure: random.err().map(|p| {
            p.downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "the random-scene run failed".into())
        }),
    });
    checks
}

/// Grades the row `args.grade` of `entries`: the kit, then the shootout of that row against the
/// rows `args.structures` names (bvh, kdtree and grid by default) on `args`' scenes. Writes
/// `grade.json` and `grade.md` into `--out DIR` (default `grade`) and returns the Markdown's
/// path.
///
/// # Errors
/// One line for an unknown row or an unwritable directory.
pub fn run(args: &Args, entries: &[Entry]) -> Result<PathBuf, String> {
    let name = args.grade.clone().unwrap_or_default();
    let entry = structures::find(entries, &name)?;
    let dir = args.out.clone().unwrap_or_else(|| PathBuf::from("grade"));
    crate::report::prepare(&dir)?;
    let checks = kit(&entry);
    let mut rows = vec![name.clone()];
    if args.structures.is_empty() {
        rows.extend(["bvh", "kdtree", "grid"].map(String::from));
    } else {
        rows.extend(args.structures.iter().filter(|s| **s != name).cloned());
    }
    let shootout_args = Args {
        structures: rows,
        out: None,
        grade: None,
        ..args.clone()
    };
    let reports = compare::run(&shootout_args, entries)?;
    write(&dir, &name, &checks, &reports)
}

fn write(dir: &Path, name: &str, checks: &[Check], reports: &[Report]) -> Result<PathBuf, String> {
    let passed = checks.iter().filter(|c| c.failure.is_none()).count();
    let json = serde_json::json!({
        "structure": name,
        "kit": {
            "passed": passed,
            "checks": checks.len(),
            "results": checks.iter().map(|c| serde_json::json!({
                "scene": c.scene,
                "passed": c.failure.is_none(),
                "failure": c.failure,
            })).collect::<Vec<_>>(),
        },
        "shootout": reports.iter().map(|r| serde_json::json!({
            "scene": r.scene,
            "rays": r.rays,
            "ray_kind": r.ray_kind,
            "rows": r.rows.iter().map(|row| serde_json::json!({
                "structure": row.name,
                "mismatches": row.mismatches,
                "build_ms": row.build_ms,
                "memory_bytes": row.memory_bytes,
                "avg_visits": row.avg_visits,
                "avg_prim_tests": row.avg_prim_tests,
                "mrays_per_s": row.mrays_per_s,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    });
    let json_path = dir.join("grade.json");
    std::fs::write(&json_path, json.to_string())
        .map_err(|e| format!("{}: cannot write: {e}", json_path.display()))?;

    let mut md = format!(
        "# Grade: {name}\n\nConformance kit: {passed} of {} checks passed.\n\n| check | result |\n| --- | --- |\n",
        checks.len()
    );
    for c in checks {
        let _ = writeln!(
            md,
            "| {} | {} |",
            c.scene,
            if c.failure.is_none() {
                "passed"
            } else {
                "**failed**"
            }
        );
    }
    for c in checks {
        if let Some(f) = &c.failure {
            let _ = writeln!(md, "\n### {} failed\n\n```text\n{f}\n```", c.scene);
        }
    }
    for r in reports {
        let _ = writeln!(
            md,
            "\n## Shootout: {} ({} {} rays)\n\n| structure | mismatches | build ms | memory MiB | visits/ray | tests/ray | Mrays/s |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
            r.scene, r.rays, r.ray_kind
        );
        for row in &r.rows {
            let _ = writeln!(
                md,
                "| {} | {} | {:.1} | {:.2} | {:.1} | {:.2} | {:.3} |",
                row.name,
                row.mismatches,
                row.build_ms,
                row.memory_bytes as f64 / (1024.0 * 1024.0),
                row.avg_visits,
                row.avg_prim_tests,
                row.mrays_per_s
            );
        }
    }
    let md_path = dir.join("grade.md");
    std::fs::write(&md_path, md)
        .map_err(|e| format!("{}: cannot write: {e}", md_path.display()))?;
    Ok(md_path)
}

//! The worker side of grading: one part of the kit, or the shootout, in a process the grade
//! started (see [`super::run`]). It reports on stdout, one line per event, each a JSON object
//! after [`MARK`]: `{"start": i}` before kit scene `i` (the random scenes come last), then
//! `{"index": i, "status": ..., "message": ...}`; the shootout worker sends
//! `{"shootout": {...}}`. Other lines (the shootout's table) are the grade's to show.

use super::{Row, RowParams, Status};
use crate::compare::{self, Args};
use crate::data::{Report, three_digits};
use crate::structures::{self, Entry};
use rt_conformance::{Part, SCENES};
use std::fmt::Write as _;
use std::io::Write as _;
use std::process::ExitCode;
use std::sync::Mutex;

/// What starts every line a worker sends to the grade.
pub(super) const MARK: &str = "@grade ";

/// The worker name of the shootout (the kit's parts go by [`Part::name`]).
pub(super) const SHOOTOUT: &str = "shootout";

/// Where the last panic happened (`file:line:column`), for the check it failed.
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

/// Runs the worker `args.grade_worker` names and returns its exit status: 0 when it ran to the
/// end, 2 for a name it does not know. A check that gets stuck ends the process right after its
/// report, so that the thread still spinning in the graded code stops too.
pub fn worker(args: &Args, entries: &[Entry]) -> ExitCode {
    // The default hook prints every panic with a backtrace, and the kit catches one panic per
    // failing check (hundreds while proptest shrinks): one line each is enough, and where the
    // panic happened is kept for the check's report.
    std::panic::set_hook(Box::new(|info| {
        let at = info
            .location()
            .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column()));
        let text = info.to_string().replace('\n', " ");
        eprintln!("{text}");
        if let Ok(mut last) = LAST_PANIC.lock() {
            *last = at;
        }
    }));
    let name = args.grade.clone().unwrap_or_default();
    let what = args.grade_worker.clone().unwrap_or_default();
    let entry = match structures::find(entries, &name) {
        Ok(entry) => entry,
        Err(e) => return refuse(&e),
    };
    if what == SHOOTOUT {
        return shootout(args, entries, &name);
    }
    let Some(part) = Part::from_name(&what) else {
        return refuse(&format!("--grade-worker {what}: no such part of the kit"));
    };
    let stall = match super::stall(args) {
        Ok(stall) => stall,
        Err(e) => return refuse(&e),
    };
    let params = RowParams(Some(entry.build.clone()));
    for index in args.grade_from..=SCENES.len() {
        send(&serde_json::json!({ "start": index }));
        LAST_PANIC.lock().map(|mut p| p.take()).ok();
        let result = match SCENES.get(index) {
            Some(scene) => {
                let s = rt_conformance::scene(scene);
                rt_conformance::check_part::<Row>(&params, &s.triangles, &s.rays, part, stall)
            }
            None => rt_conformance::check_random_part::<Row>(&params, part, stall),
        };
        let at = LAST_PANIC.lock().ok().and_then(|mut p| p.take());
        let (status, message) = classify(result, at);
        send(&serde_json::json!({
            "index": index,
            "status": status.name(),
            "message": message,
        }));
        if status == Status::Stuck {
            std::process::exit(0);
        }
    }
    ExitCode::SUCCESS
}

/// One line for the grade, flushed at once: the grade reads it while this process runs.
fn send(value: &serde_json::Value) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{MARK}{value}");
    let _ = out.flush();
}

fn refuse(e: &str) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(2)
}

/// A check's status and message from the kit's answer and where a panic happened, if one did.
fn classify(result: Result<(), String>, at: Option<String>) -> (Status, String) {
    let Err(message) = result else {
        return (Status::Passed, String::new());
    };
    let status = if message.contains(rt_conformance::STALL_MARK) {
        Status::Stuck
    } else if message.contains("panicked: not yet implemented")
        || message.contains("panicked: not implemented")
    {
        Status::NotImplemented
    } else if message.contains(" panicked: ") {
        Status::Panicked
    } else {
        Status::Failed
    };
    let message = match at {
        Some(at) if matches!(status, Status::NotImplemented | Status::Panicked) => {
            format!("{message}\n  panicked at: {at}")
        }
        _ => message,
    };
    (status, message)
}

/// The rows of the grade's shootout: the graded row, then `--structures` (default bvh, kdtree
/// and grid) without it.
pub(super) fn shootout_rows(args: &Args, name: &str) -> Vec<String> {
    let mut rows = vec![name.to_string()];
    if args.structures.is_empty() {
        rows.extend(["bvh", "kdtree", "grid"].map(String::from));
    } else {
        rows.extend(args.structures.iter().filter(|s| **s != name).cloned());
    }
    rows
}

/// The shootout worker: `compare` of the graded row against the reference rows, its table
/// printed as usual, and its figures sent to the grade as JSON, a Markdown section and a
/// verdict.
fn shootout(args: &Args, entries: &[Entry], name: &str) -> ExitCode {
    let rows = shootout_rows(args, name);
    let shootout_args = Args {
        structures: rows.clone(),
        out: None,
        grade: None,
        grade_worker: None,
        json: false,
        ..args.clone()
    };
    let reports = match compare::run(&shootout_args, entries) {
        Ok(reports) => reports,
        Err(e) => {
            send(&serde_json::json!({ "error": e }));
            return ExitCode::from(2);
        }
    };
    send(&serde_json::json!({ "shootout": {
        "reports": reports.iter().map(report_json).collect::<Vec<_>>(),
        "markdown": markdown(&reports),
        "verdict": verdict(&reports, name, rows.get(1).map(String::as_str)),
    }}));
    ExitCode::SUCCESS
}

fn report_json(r: &Report) -> serde_json::Value {
    serde_json::json!({
        "scene": r.scene,
        "rays": r.rays,
        "ray_kind": r.ray_kind,
        "hit_share": r.hit_share(),
        "rows": r.rows.iter().map(|row| serde_json::json!({
            "structure": row.name,
            "mismatches": row.mismatches,
            "build_ms": row.build_ms,
            "memory_bytes": row.memory_bytes,
            "avg_visits": row.avg_visits,
            "avg_prim_tests": row.avg_prim_tests,
            "mrays_per_s": row.mrays_per_s,
        })).collect::<Vec<_>>(),
    })
}

fn markdown(reports: &[Report]) -> String {
    let mut md = String::new();
    for r in reports {
        let share = r
            .hit_share()
            .map_or(String::new(), |s| format!(", {:.1}% hit", 100.0 * s));
        let _ = writeln!(
            md,
            "\n## Shootout: {} ({} {} rays{share})\n\n| structure | mismatches | build ms | memory MiB | visits/ray | tests/ray | Mrays/s |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
            r.scene, r.rays, r.ray_kind
        );
        for row in &r.rows {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {:.2} | {} | {} | {} |",
                row.name,
                row.mismatches,
                three_digits(row.build_ms),
                row.memory_bytes as f64 / (1024.0 * 1024.0),
                three_digits(row.avg_visits),
                three_digits(row.avg_prim_tests),
                three_digits(row.mrays_per_s)
            );
        }
    }
    md
}

/// One sentence per scene: the graded row's mismatches, and its visits per ray and speed as
/// ratios to the first reference row's, measured in the same run.
fn verdict(reports: &[Report], name: &str, reference: Option<&str>) -> String {
    let mut parts = Vec::new();
    for r in reports {
        let Some(row) = r.rows.iter().find(|row| row.name == name) else {
            continue;
        };
        let mut s = format!(
            "on {} {} mismatch{}",
            r.scene,
            row.mismatches,
            if row.mismatches == 1 { "" } else { "es" }
        );
        if let Some(base) = reference.and_then(|n| r.rows.iter().find(|row| row.name == n)) {
            let ratio = |a: f64, b: f64| {
                if b > 0.0 {
                    three_digits(a / b)
                } else {
                    "-".into()
                }
            };
            let _ = write!(
                s,
                ", {}× {}'s node visits per ray and {}× its speed",
                ratio(row.avg_visits, base.avg_visits),
                base.name,
                ratio(row.mrays_per_s, base.mrays_per_s)
            );
        }
        parts.push(s);
    }
    parts.join("; ")
}

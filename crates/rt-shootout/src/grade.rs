//! Grading one row, for a student and a teacher: every part of the conformance kit
//! ([`rt_conformance::Part`]: closest hit, any hit, bundles, closest points, box overlap, all
//! hits, inside) on every kit scene and on random scenes, each check passed, failed (with its
//! first failing ray and how to replay it), not implemented yet, panicked, stuck or crashed; then
//! the shootout against reference rows, and a one-line verdict. Written as `grade.md` and
//! `grade.json` whatever the graded code does.
//!
//! A row under grading may be half written: a `todo!()` in one step, a loop, a recursion without
//! end. So the grade runs each part of the kit, and the shootout, in a process of its own (the
//! same program, started again with a hidden `--grade-worker PART` flag): a panic fails one
//! check, a loop is stopped by the kit's watchdog and then by killing the process, and a crash
//! (a stack overflow aborts a process) costs the check it happened in. The grade goes on with
//! the next check in a new process.

use crate::compare::Args;
use crate::structures::{self, Builder, Entry};
use rt_core::DynAccel;
use rt_core::{Accel, BuildStats, PrimHit, RayQuery, Region, Stats, Triangle};
use std::path::PathBuf;
use std::sync::Arc;

mod launch;
mod worker;
mod write;

pub use launch::{Check, GIVE_UP, Status};
pub use worker::worker;

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

/// Runs `query` through the row's own ray walk and replays what it reported into `stats`.
/// Traced (the kit traces closest and any hits), the row answers that query with every step
/// recorded, the steps are replayed into `stats`, and the answer is offered to `query`.
fn ask<Q: RayQuery, S: Stats>(
    row: &dyn DynAccel<Triangle>,
    ray: &rt_core::Ray,
    query: &mut Q,
    stats: &mut S,
) {
    if S::TRACE {
        let (hit, trace) = row.trace_dyn(ray, Q::OCCLUSION);
        replay(trace.counters, stats);
        for e in trace.events {
            stats.event(e);
        }
        if let Some(h) = hit {
            let hit = if Q::OCCLUSION {
                rt_core::query::BLOCKS
            } else {
                PrimHit {
                    t: h.t,
                    u: h.u,
                    v: h.v,
                }
            };
            let _ = query.offer(h.prim, hit);
        }
    } else {
        let mut c = rt_core::Counters::default();
        row.ray_query_dyn(ray, query, Some(&mut c));
        replay(c, stats);
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
    /// The row's own ray walk, its counts replayed into `stats` when it returns.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &rt_core::Ray, query: &mut Q, stats: &mut S) {
        ask(self.0.as_ref(), ray, query, stats);
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

/// `--grade-stall` as a duration.
///
/// # Errors
/// One line for a value that is not a positive number of seconds up to an hour.
fn stall(args: &Args) -> Result<std::time::Duration, String> {
    let s = args.grade_stall;
    if s.is_finite() && s > 0.0 && s <= 3600.0 {
        Ok(std::time::Duration::from_secs_f64(s))
    } else {
        Err(format!(
            "--grade-stall {s}: expected seconds, more than 0 and at most 3600"
        ))
    }
}

/// Grades the row `args.grade` of `entries`: each part of the kit in turn, then the shootout of
/// that row against the rows `args.structures` names (bvh, kdtree and grid by default) on
/// `args`' scenes. Writes `grade.json` and `grade.md` into `--out DIR` (default `grade`) and
/// returns the Markdown's path.
///
/// # Errors
/// One line for an unknown row, an unwritable directory, or a program that cannot be started
/// again for the workers.
pub fn run(args: &Args, entries: &[Entry]) -> Result<PathBuf, String> {
    let name = args.grade.clone().unwrap_or_default();
    structures::find(entries, &name)?;
    stall(args)?;
    let dir = args.out.clone().unwrap_or_else(|| PathBuf::from("grade"));
    crate::report::prepare(&dir)?;
    let launcher = launch::Launcher::new(args)?;
    let mut checks = Vec::new();
    for part in rt_conformance::Part::ALL {
        let done = launcher.part(part);
        let passed = done.iter().filter(|c| c.status == Status::Passed).count();
        println!(
            "{:<15} {passed:>2} of {} checks pass{}",
            part.name(),
            done.len(),
            launch::summary(&done)
        );
        checks.extend(done);
    }
    // The shootout traces hundreds of thousands of rays: a closest-hit query that is not
    // written, or that hung or crashed on a kit scene, would only do the same there, slowly.
    let unfinished = checks.iter().find(|c| {
        c.part == rt_conformance::Part::Closest
            && !matches!(c.status, Status::Passed | Status::Failed | Status::Panicked)
    });
    let shootout = match unfinished {
        Some(c) => Err(format!(
            "not run, because the closest-hit check on {} is {}",
            c.scene,
            c.status.name()
        )),
        None => launcher.shootout(),
    };
    write::write(&dir, &name, &launcher, &checks, &shootout)
}

//! Grading a row that is not done: a `todo!()` in one query, a query that loops, a build that
//! overflows its stack, a query that panics. Each grade must be written, with every check
//! reported and the checks that pass shown as passed.
//!
//! Grading starts the program it runs in again for each part of the kit (see
//! `rt_shootout::grade`), so this test is a program of its own (`harness = false`): run by
//! cargo, it grades the rows below; started by a grade with `--grade-worker`, it is that
//! grade's worker.

#[path = "../examples/groups/groups.rs"]
mod groups;

use groups::{GROUP, Groups};
use rt_conformance::Part;
use rt_core::{
    Aabb, Accel, BallQuery, BruteForce, BuildStats, PrimHit, Ray, RayQuery, Stats, Triangle,
};
use rt_shootout::Shootout;
use serde_json::Value;
use std::ops::ControlFlow;
use std::process::ExitCode;

/// Everything but the build and the query a row below breaks, answered by brute force.
macro_rules! brute_force_but {
    () => {
        type Prim = Triangle;
        type Params = ();
        fn presets() -> Vec<(&'static str, ())> {
            vec![("default", ())]
        }
        fn bounds(&self) -> Aabb {
            self.0.bounds()
        }
        fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
            self.0.ball_query(query, stats)
        }
        fn memory_bytes(&self) -> usize {
            self.0.memory_bytes()
        }
        fn build_stats(&self) -> BuildStats {
            self.0.build_stats()
        }
    };
}

/// A lab before its any-hit step: the closest hit is right, the any hit is a `todo!()`.
struct TodoAny(BruteForce<Triangle>);

impl Accel for TodoAny {
    brute_force_but!();
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()))
    }
    const NAME: &'static str = "todo-any";
    // The stub a lab's template has: the lint against `todo!()` is for code that ships.
    #[allow(clippy::todo)]
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if Q::OCCLUSION {
            todo!("step 5: the any hit")
        }
        self.0.ray_query(ray, query, stats);
    }
}

/// A closest hit that never returns on rays heading mostly down (a walk that steps by zero).
struct Loops(BruteForce<Triangle>);

impl Accel for Loops {
    brute_force_but!();
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()))
    }
    const NAME: &'static str = "loops";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        while !Q::OCCLUSION && ray.is_valid() && ray.dir().y < -0.5 * ray.dir().length() {
            std::hint::spin_loop();
        }
        self.0.ray_query(ray, query, stats);
    }
}

/// A build that recurses without end once it has two triangles: the process overflows its
/// stack and aborts.
struct Overflows(BruteForce<Triangle>);

fn deeper(n: u64) -> u64 {
    if n == u64::MAX {
        return 0;
    }
    let pad = std::hint::black_box([n; 32]);
    deeper(pad[0] + 1).wrapping_add(pad[31])
}

impl Accel for Overflows {
    brute_force_but!();
    const NAME: &'static str = "overflows";
    fn build(prims: &[Triangle], _: &()) -> Self {
        if prims.len() >= 2 {
            std::hint::black_box(deeper(0));
        }
        Self(BruteForce::build(prims, &()))
    }
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }
}

/// A closest hit that indexes out of bounds on rays from far to the right.
struct Panics(BruteForce<Triangle>);

impl Accel for Panics {
    brute_force_but!();
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(BruteForce::build(prims, &()))
    }
    const NAME: &'static str = "panics";
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        let far = [!Q::OCCLUSION && ray.origin.x > 3.0];
        if std::hint::black_box(far)[usize::from(far[0])] {
            unreachable!("the index above is out of bounds");
        }
        self.0.ray_query(ray, query, stats);
    }
}

/// [`Groups`] with a classic bug: it forgets the last triangle of every group.
struct DropsLast(Groups);

impl Accel for DropsLast {
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "drops-last";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        Self(Groups::build(prims, &()))
    }
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        let mut skip = SkipsLast {
            inner: query,
            tris: &self.0.tris,
        };
        self.0.ray_query(ray, &mut skip, stats);
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }
    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }
}

/// A query offered every hit but those on the last triangle of a group.
struct SkipsLast<'a, Q> {
    inner: &'a mut Q,
    tris: &'a [(u32, Triangle)],
}

impl<Q: RayQuery> RayQuery for SkipsLast<'_, Q> {
    const OCCLUSION: bool = Q::OCCLUSION;
    const REPEATABLE: bool = Q::REPEATABLE;
    fn t_far(&self) -> f32 {
        self.inner.t_far()
    }
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        let pos = self
            .tris
            .iter()
            .position(|(id, _)| *id == prim)
            .unwrap_or(0);
        if pos % GROUP == GROUP - 1 || pos + 1 == self.tris.len() {
            ControlFlow::Continue(())
        } else {
            self.inner.offer(prim, hit)
        }
    }
}

fn rows() -> Shootout {
    Shootout::new()
        .with_triangles::<Groups>()
        .with_triangles::<DropsLast>()
        .with_triangles::<TodoAny>()
        .with_triangles::<Loops>()
        .with_triangles::<Overflows>()
        .with_triangles::<Panics>()
}

fn main() -> ExitCode {
    if std::env::args().any(|a| a == "--grade-worker") {
        return rows().main();
    }
    check_groups();
    check_drops_last();
    check_todo_any();
    check_loops();
    check_overflows();
    check_panics();
    println!("test result: ok. 6 grades written and checked");
    ExitCode::SUCCESS
}

/// Grades `row` (the shootout on a small kit scene against brute force and `bvh`) and returns
/// `grade.json` and `grade.md`.
fn grade(row: &str) -> (Value, String) {
    let dir = std::env::temp_dir().join(format!("rt-grade-test-{}-{row}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let args = rt_shootout::args_from([
        "--grade",
        row,
        "--out",
        dir.to_str().expect("a UTF-8 temporary directory"),
        "--scene",
        "kit:closed_meshes",
        "--structures",
        "bvh",
        "--grade-stall",
        "1",
        "--repeats",
        "1",
    ])
    .expect("the grade's flags parse");
    let written = rows().grade(&args);
    assert!(written.is_ok(), "grading {row} failed: {written:?}");
    let json = std::fs::read_to_string(dir.join("grade.json")).expect("grade.json is written");
    let md = std::fs::read_to_string(dir.join("grade.md")).expect("grade.md is written");
    let _ = std::fs::remove_dir_all(&dir);
    (serde_json::from_str(&json).expect("grade.json parses"), md)
}

/// The statuses of one part's checks, in scene order.
fn statuses(grade: &Value, part: Part) -> Vec<String> {
    let results = grade["kit"]["results"].as_array().expect("results");
    results
        .iter()
        .filter(|r| r["part"] == part.name())
        .map(|r| r["status"].as_str().unwrap_or("?").to_string())
        .collect()
}

fn all(statuses: &[String], status: &str) -> bool {
    !statuses.is_empty() && statuses.iter().all(|s| s == status)
}

fn message_of(grade: &Value, part: Part, status: &str) -> String {
    grade["kit"]["results"]
        .as_array()
        .expect("results")
        .iter()
        .find(|r| r["part"] == part.name() && r["status"] == status)
        .and_then(|r| r["message"].as_str())
        .unwrap_or_default()
        .to_string()
}

fn check_groups() {
    let (g, md) = grade("groups");
    let checks = (rt_conformance::SCENES.len() + 1) * Part::ALL.len();
    assert!(
        g["kit"]["passed"] == checks && md.contains(&format!("{checks} of {checks} checks passed")),
        "groups: a right structure passes every check of every part:\n{md}"
    );
    assert!(
        g["shootout"][0]["rows"][1]["structure"] == "groups"
            && g["shootout"][0]["rows"][1]["mismatches"] == 0,
        "groups: the shootout ran the row with no mismatch: {}",
        g["shootout"]
    );
}

fn check_drops_last() {
    let (g, md) = grade("drops-last");
    let closest = statuses(&g, Part::Closest);
    assert!(
        closest.iter().any(|s| s == "failed"),
        "drops-last: its closest-hit checks fail, got {closest:?}"
    );
    let results = g["kit"]["results"].as_array().expect("results");
    let one = results
        .iter()
        .find(|r| r["scene"] == "one_triangle" && r["part"] == Part::Closest.name())
        .expect("a closest-hit check on one_triangle");
    let message = one["message"].as_str().unwrap_or_default();
    assert!(
        one["status"] == "failed"
            && message.contains("Ray::with_interval(")
            && message.contains("rays-file line: "),
        "drops-last: the check names its ray as Rust and as a rays-file line: {one}"
    );
    let replay = one["replay"].as_str().unwrap_or_default();
    assert!(
        replay.contains("explain --scene kit:one_triangle --structures drops-last --ray \""),
        "drops-last: the check says how to replay its ray: {one}"
    );
    let random = results
        .iter()
        .find(|r| r["scene"] == "random_scenes" && r["part"] == Part::Closest.name())
        .expect("a closest-hit check on random scenes");
    assert!(
        random["status"] == "failed"
            && random["message"]
                .as_str()
                .unwrap_or_default()
                .lines()
                .count()
                <= 8,
        "drops-last: the random scenes fail with a short shrunk case: {random}"
    );
    // The shootout ran against the reference row, and found the same bug.
    let rows = g["shootout"][0]["rows"].as_array().expect("shootout rows");
    let names: Vec<&str> = rows
        .iter()
        .filter_map(|r| r["structure"].as_str())
        .collect();
    assert!(
        names == ["brute-force", "drops-last", "bvh"]
            && rows[1]["mismatches"].as_u64().is_some_and(|m| m > 0),
        "drops-last: the shootout finds the bug too: {rows:?}"
    );
    assert!(
        md.contains("**FAIL**") && md.contains("Replay this ray step by step"),
        "drops-last: grade.md marks the failures and how to replay them:\n{md}"
    );
}

fn check_todo_any() {
    let (g, md) = grade("todo-any");
    let checks = rt_conformance::SCENES.len() + 1;
    let closest = statuses(&g, Part::Closest);
    assert!(
        closest.len() == checks && all(&closest, "passed"),
        "todo-any: every closest-hit check passes, got {closest:?}"
    );
    let any = statuses(&g, Part::Any);
    assert!(
        all(&any, "not implemented yet"),
        "todo-any: every any-hit check is not implemented yet, got {any:?}"
    );
    let message = message_of(&g, Part::Any, "not implemented yet");
    assert!(
        message.contains("step 5: the any hit") && message.contains("panicked at: "),
        "todo-any: the any-hit message names the todo!() and where it is: {message}"
    );
    for part in [Part::ClosestPoints, Part::BoxOverlap] {
        let s = statuses(&g, part);
        assert!(
            all(&s, "passed"),
            "todo-any: {} passes, got {s:?}",
            part.name()
        );
    }
    let verdict = g["verdict"].as_str().unwrap_or_default();
    assert!(
        verdict.contains("closest-hit 19/19") && verdict.contains("any-hit not implemented yet"),
        "todo-any: the verdict shows the progress: {verdict}"
    );
    assert!(
        g["shootout"][0]["rows"][1]["structure"] == "todo-any"
            && g["shootout"][0]["rows"][1]["mismatches"] == 0,
        "todo-any: the shootout ran the row with no mismatch: {}",
        g["shootout"]
    );
    assert!(
        md.contains("| empty_scene | pass | todo |")
            && md.contains("`not yet implemented: step 5: the any hit` at `"),
        "todo-any: grade.md shows the table and the todo!() once:\n{md}"
    );
}

fn check_loops() {
    let (g, md) = grade("loops");
    let closest = statuses(&g, Part::Closest);
    let stuck = closest.iter().filter(|s| *s == "stuck").count();
    assert!(
        stuck == rt_shootout::grade::GIVE_UP
            && closest
                .iter()
                .all(|s| ["passed", "stuck", "not run"].contains(&s.as_str())),
        "loops: the closest-hit part is given up after {} stuck checks, got {closest:?}",
        rt_shootout::grade::GIVE_UP
    );
    let message = message_of(&g, Part::Closest, "stuck");
    assert!(
        message.contains("did not return within") && message.contains("rays-file line: "),
        "loops: a stuck check names its ray: {message}"
    );
    let any = statuses(&g, Part::Any);
    assert!(
        all(&any, "passed"),
        "loops: the any-hit part passes, got {any:?}"
    );
    assert!(
        g["shootout"]["error"]
            .as_str()
            .is_some_and(|e| e.starts_with("not run")),
        "loops: the shootout is not run after stuck closest-hit checks: {}",
        g["shootout"]
    );
    assert!(
        md.contains("explain --scene kit:") && md.contains("Ctrl-C"),
        "loops: grade.md says how to replay a stuck ray, and that it will not return:\n{md}"
    );
}

fn check_overflows() {
    let (g, _) = grade("overflows");
    for part in Part::ALL {
        let s = statuses(&g, part);
        assert!(
            s.first().is_some_and(|s| s == "passed")
                && s.iter().filter(|s| *s == "crashed").count() == rt_shootout::grade::GIVE_UP
                && s.iter()
                    .all(|s| ["passed", "crashed", "not run"].contains(&s.as_str())),
            "overflows: {} passes the empty scene, then crashes {} times and gives up, got {s:?}",
            part.name(),
            rt_shootout::grade::GIVE_UP
        );
    }
    let message = message_of(&g, Part::Closest, "crashed");
    assert!(
        message.contains("overflowed its stack"),
        "overflows: a crash says how the worker died: {message}"
    );
}

fn check_panics() {
    let (g, _) = grade("panics");
    let closest = statuses(&g, Part::Closest);
    assert!(
        closest.iter().any(|s| s == "panicked") && closest.iter().any(|s| s == "passed"),
        "panics: some closest-hit checks panic and some pass, got {closest:?}"
    );
    let message = message_of(&g, Part::Closest, "panicked");
    assert!(
        message.contains("index out of bounds") && message.contains("tests/grade.rs:"),
        "panics: the message says what panicked, and where: {message}"
    );
    let any = statuses(&g, Part::Any);
    assert!(
        all(&any, "passed"),
        "panics: the any-hit part passes, got {any:?}"
    );
}

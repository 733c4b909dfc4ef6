//! The grade's side of its workers: starting them, reading their reports with a time limit,
//! and going on after one that crashed or hung.

use super::worker::{MARK, SHOOTOUT};
use crate::compare::Args;
use rt_conformance::{Part, SCENES};
use std::collections::VecDeque;
use std::ffi::OsString;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How a check ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The row answered like brute force.
    Passed,
    /// The row answered differently; the message names the first ray (or point, or box).
    Failed,
    /// The row reached a `todo!()` or `unimplemented!()`: a step not written yet.
    NotImplemented,
    /// The row panicked otherwise (an index out of bounds, an `unwrap` on `None`, ...).
    Panicked,
    /// A build or query did not return within `--grade-stall` seconds (a loop?).
    Stuck,
    /// The worker process died in this check (a stack overflow aborts a process).
    Crashed,
    /// Not run: the part got stuck or crashed [`GIVE_UP`] times already.
    NotRun,
}

impl Status {
    /// The status as the grade writes it.
    pub fn name(self) -> &'static str {
        match self {
            Status::Passed => "passed",
            Status::Failed => "failed",
            Status::NotImplemented => "not implemented yet",
            Status::Panicked => "panicked",
            Status::Stuck => "stuck",
            Status::Crashed => "crashed",
            Status::NotRun => "not run",
        }
    }

    fn from_name(name: &str) -> Status {
        [
            Status::Passed,
            Status::Failed,
            Status::NotImplemented,
            Status::Panicked,
            Status::Stuck,
            Status::Crashed,
        ]
        .into_iter()
        .find(|s| s.name() == name)
        .unwrap_or(Status::Crashed)
    }
}

/// One check of the kit: one part on one scene.
#[derive(Clone, Debug)]
pub struct Check {
    /// The kit scene's name, or `random_scenes`.
    pub scene: String,
    /// The part of the kit.
    pub part: Part,
    /// How it ended.
    pub status: Status,
    /// What went wrong (naming the first failing ray), empty when it passed.
    pub message: String,
}

/// After a part gets stuck or crashes this many times, its other checks are not run: a loop
/// in a query usually loops on every scene, and each costs the stall limit.
pub const GIVE_UP: usize = 3;

/// How long the grade waits for a worker's next line before it kills the worker: the kit's own
/// watchdog stops a stuck check within `--grade-stall`, so this only catches what that misses. A kit scene's checks take well under a second; the random scenes (256 of them) take
/// longer.
const SCENE_WAIT: Duration = Duration::from_secs(120);
const RANDOM_WAIT: Duration = Duration::from_secs(900);
const SHOOTOUT_WAIT: Duration = Duration::from_secs(1800);

/// The name of the random-scene check.
const RANDOM: &str = "random_scenes";

/// Starts the workers: this program again, with the grade's flags and the worker's.
pub struct Launcher {
    exe: PathBuf,
    flags: Vec<OsString>,
    /// The graded row.
    pub row: String,
    /// `--grade-stall`.
    pub stall_seconds: f64,
    /// How the user runs this program, for the replay commands: `cargo run --release --example
    /// shootout --` for an example, `cargo xtask` for xtask, else the program's path.
    pub command: String,
}

/// What one worker sent before it ended.
struct Run {
    lines: Vec<serde_json::Value>,
    /// Whether it was killed for not answering in time.
    killed: bool,
    /// How it exited, as a phrase.
    exit: String,
    /// The last lines it wrote to stderr.
    stderr: Vec<String>,
}

impl Launcher {
    /// The launcher for the grade `args` asks for.
    ///
    /// # Errors
    /// One line when this program's path cannot be found.
    pub fn new(args: &Args) -> Result<Self, String> {
        let exe = std::env::current_exe()
            .map_err(|e| format!("cannot find this program to start the grading workers: {e}"))?;
        let given = if args.flags.is_empty() {
            std::env::args_os().skip(1).collect()
        } else {
            args.flags.clone()
        };
        // A worker's own flags are the launcher's to set.
        let mut flags = Vec::new();
        let mut skip = false;
        for f in given {
            let text = f.to_string_lossy();
            if skip {
                skip = false;
            } else if text == "--grade-worker" || text == "--grade-from" {
                skip = true;
            } else if !text.starts_with("--grade-worker=") && !text.starts_with("--grade-from=") {
                flags.push(f);
            }
        }
        Ok(Self {
            command: user_command(&exe),
            exe,
            flags,
            row: args.grade.clone().unwrap_or_default(),
            stall_seconds: args.grade_stall,
        })
    }

    /// Runs one part of the kit on every kit scene and the random scenes, starting a worker
    /// again after one that got stuck or crashed, and returns a check per scene.
    pub fn part(&self, part: Part) -> Vec<Check> {
        let names: Vec<&str> = SCENES.iter().copied().chain([RANDOM]).collect();
        let mut done: Vec<Option<Check>> = vec![None; names.len()];
        let check = |i: usize, status: Status, message: String| Check {
            scene: names[i].to_string(),
            part,
            status,
            message,
        };
        let mut troubles = Vec::new();
        let mut from = 0;
        while from < names.len() {
            if troubles.len() >= GIVE_UP {
                for (i, slot) in done.iter_mut().enumerate().skip(from) {
                    *slot = Some(check(
                        i,
                        Status::NotRun,
                        format!(
                            "not run: this part got stuck or crashed on {} already",
                            troubles.join(", ")
                        ),
                    ));
                }
                break;
            }
            let extra = [
                "--grade-worker",
                part.name(),
                "--grade-from",
                &from.to_string(),
            ];
            let mut started = None;
            let run = self.spawn(&extra, false, |line| {
                if line.get("start").is_some() {
                    started = line["start"].as_u64().map(|i| i as usize);
                    return if started == Some(names.len() - 1) {
                        RANDOM_WAIT
                    } else {
                        SCENE_WAIT
                    };
                }
                SCENE_WAIT
            });
            for line in &run.lines {
                let (Some(i), Some(status)) = (line["index"].as_u64(), line["status"].as_str())
                else {
                    continue;
                };
                let i = i as usize;
                if i < names.len() {
                    let status = Status::from_name(status);
                    if status == Status::Stuck {
                        troubles.push(names[i].to_string());
                    }
                    let message = line["message"].as_str().unwrap_or_default().to_string();
                    done[i] = Some(check(i, status, message));
                }
            }
            // The first check without a report is the one the worker was on when it ended, if
            // it started it; a worker that reported a stuck check ended itself after it.
            let Some(first) = (from..names.len()).find(|&i| done[i].is_none()) else {
                break;
            };
            if started != Some(first) {
                if first > from {
                    from = first;
                    continue;
                }
                // The worker never reached its first check: it failed to start at all.
                for (i, slot) in done.iter_mut().enumerate().skip(first) {
                    *slot = Some(check(
                        i,
                        Status::Crashed,
                        format!("the grading worker did not start: {}", describe(&run)),
                    ));
                }
                break;
            }
            let status = if run.killed {
                Status::Stuck
            } else {
                Status::Crashed
            };
            done[first] = Some(check(first, status, describe(&run)));
            troubles.push(names[first].to_string());
            from = first + 1;
        }
        done.into_iter().flatten().collect()
    }

    /// Runs the shootout in a worker (its table shown as it comes) and returns its JSON
    /// (`reports`, `markdown` and `verdict`), or why it did not finish.
    pub fn shootout(&self) -> Result<serde_json::Value, String> {
        let run = self.spawn(&["--grade-worker", SHOOTOUT], true, |_| SHOOTOUT_WAIT);
        for line in &run.lines {
            if let Some(s) = line.get("shootout") {
                return Ok(s.clone());
            }
            if let Some(e) = line.get("error").and_then(|e| e.as_str()) {
                return Err(e.to_string());
            }
        }
        Err(describe(&run))
    }

    /// Starts a worker with `extra` flags and collects its report lines until it ends, or until
    /// it sends nothing for the time `wait` gives after each line (and before the first, the
    /// scene wait), when it is killed. With `echo`, its other output is shown as it comes.
    fn spawn(
        &self,
        extra: &[&str],
        echo: bool,
        mut wait: impl FnMut(&serde_json::Value) -> Duration,
    ) -> Run {
        let child = Command::new(&self.exe)
            .args(&self.flags)
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn();
        let mut child = match child {
            Ok(child) => child,
            Err(e) => {
                return Run {
                    lines: Vec::new(),
                    killed: false,
                    exit: format!("{} could not be started: {e}", self.exe.display()),
                    stderr: Vec::new(),
                };
            }
        };
        let stderr = Arc::new(Mutex::new(VecDeque::new()));
        let (tx, rx) = mpsc::channel();
        if let Some(out) = child.stdout.take() {
            std::thread::spawn(move || {
                for line in BufReader::new(out).lines().map_while(Result::ok) {
                    if tx.send(line).is_err() {
                        break;
                    }
                }
            });
        }
        let err_thread = child.stderr.take().map(|err| {
            let keep = stderr.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(err).lines().map_while(Result::ok) {
                    if echo && !line.starts_with("panicked at") {
                        eprintln!("{line}");
                    }
                    if let Ok(mut keep) = keep.lock() {
                        if keep.len() == 12 {
                            keep.pop_front();
                        }
                        keep.push_back(line);
                    }
                }
            })
        });
        let mut lines = Vec::new();
        let mut limit = SCENE_WAIT;
        let mut killed = false;
        loop {
            match rx.recv_timeout(limit) {
                Ok(line) => match line.strip_prefix(MARK) {
                    Some(json) => {
                        if let Ok(value) = serde_json::from_str::<serde_json::Value>(json) {
                            limit = wait(&value);
                            lines.push(value);
                        }
                    }
                    None if echo => println!("{line}"),
                    None => {}
                },
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    let _ = child.kill();
                    killed = true;
                    break;
                }
            }
        }
        let exit = match child.wait() {
            Ok(_) if killed => format!("killed after {} s without a report", limit.as_secs()),
            Ok(status) => exit_phrase(status),
            Err(e) => format!("could not be waited for: {e}"),
        };
        if let Some(t) = err_thread {
            let _ = t.join();
        }
        let stderr = stderr
            .lock()
            .map(|s| s.iter().cloned().collect())
            .unwrap_or_default();
        Run {
            lines,
            killed,
            exit,
            stderr,
        }
    }
}

/// How a worker that did not finish ended, with the last lines it wrote.
fn describe(run: &Run) -> String {
    let mut s = format!("the grading worker {}", run.exit);
    let mut tail: Vec<&String> = run.stderr.iter().filter(|l| !l.trim().is_empty()).collect();
    // Threads that panic at the same place say the same thing.
    tail.dedup();
    if !tail.is_empty() {
        s.push_str("; its last words:");
        for l in tail.iter().rev().take(4).rev() {
            s.push_str("\n  ");
            s.push_str(l);
        }
    }
    s
}

fn exit_phrase(status: std::process::ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            let what = match signal {
                6 => " (an abort: a stack overflow, or a panic while panicking)",
                9 => " (killed)",
                11 => " (a segmentation fault)",
                _ => "",
            };
            return format!("died of signal {signal}{what}");
        }
    }
    match status.code() {
        Some(0) => "ended without reporting every check".into(),
        Some(code) => format!("exited with status {code}"),
        None => "ended".into(),
    }
}

/// How a user runs `exe`: an example through cargo, xtask through its alias, else its path.
fn user_command(exe: &Path) -> String {
    let stem = exe
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    // Cargo also keeps a copy named `stem-<16 hex digits>`.
    let stem = match stem.rsplit_once('-') {
        Some((base, hash)) if hash.len() == 16 && hash.chars().all(|c| c.is_ascii_hexdigit()) => {
            base.to_string()
        }
        _ => stem,
    };
    let dir = exe.parent();
    let in_examples = dir
        .and_then(|d| d.file_name())
        .is_some_and(|d| d == "examples");
    let release = dir
        .and_then(|d| if in_examples { d.parent() } else { Some(d) })
        .and_then(|d| d.file_name())
        .is_some_and(|d| d == "release");
    if in_examples {
        let profile = if release { " --release" } else { "" };
        format!("cargo run{profile} --example {stem} --")
    } else if stem == "xtask" {
        "cargo xtask".into()
    } else {
        exe.display().to_string()
    }
}

/// The statuses other than passed among `checks`, as a parenthesised count list, or nothing.
pub fn summary(checks: &[Check]) -> String {
    let mut counts: Vec<(Status, usize)> = Vec::new();
    for c in checks.iter().filter(|c| c.status != Status::Passed) {
        match counts.iter_mut().find(|(s, _)| *s == c.status) {
            Some((_, n)) => *n += 1,
            None => counts.push((c.status, 1)),
        }
    }
    if counts.is_empty() {
        return String::new();
    }
    let list: Vec<String> = counts
        .iter()
        .map(|(s, n)| format!("{n} {}", s.name()))
        .collect();
    format!(" ({})", list.join(", "))
}

/// The command that replays a failed check's ray with `explain`, when the message names one
/// on a kit scene.
pub fn replay(launcher: &Launcher, check: &Check) -> Option<String> {
    let line = check
        .message
        .lines()
        .find_map(|l| l.trim().strip_prefix("rays-file line: "))?;
    if check.scene == RANDOM {
        return None;
    }
    let any = if check.part == Part::Any {
        " --any"
    } else {
        ""
    };
    Some(format!(
        "{} explain --scene kit:{} --structures {} --ray \"{line}\"{any}",
        launcher.command, check.scene, launcher.row
    ))
}

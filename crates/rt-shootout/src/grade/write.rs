//! `grade.md` and `grade.json`: the checks as a table of scenes by parts, what went wrong in
//! each failed check and how to replay it, the shootout, and the verdict.

use super::launch::{self, Check, Launcher, Status};
use rt_conformance::Part;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Writes the grade into `dir` and returns the Markdown's path.
///
/// # Errors
/// One line naming a file that cannot be written.
pub(super) fn write(
    dir: &Path,
    name: &str,
    launcher: &Launcher,
    checks: &[Check],
    shootout: &Result<serde_json::Value, String>,
) -> Result<PathBuf, String> {
    let passed = checks.iter().filter(|c| c.status == Status::Passed).count();
    let verdict = verdict(name, checks, shootout);
    let json = serde_json::json!({
        "structure": name,
        "verdict": verdict,
        "kit": {
            "passed": passed,
            "checks": checks.len(),
            "parts": Part::ALL.iter().map(|p| serde_json::json!({
                "part": p.name(),
                "passed": count(checks, *p, Status::Passed),
                "checks": checks.iter().filter(|c| c.part == *p).count(),
            })).collect::<Vec<_>>(),
            "results": checks.iter().map(|c| serde_json::json!({
                "scene": c.scene,
                "part": c.part.name(),
                "status": c.status.name(),
                "passed": c.status == Status::Passed,
                "message": (!c.message.is_empty()).then_some(&c.message),
                "replay": launch::replay(launcher, c),
            })).collect::<Vec<_>>(),
        },
        "shootout": match shootout {
            Ok(s) => s["reports"].clone(),
            Err(e) => serde_json::json!({ "error": e }),
        },
    });
    let json_path = dir.join("grade.json");
    std::fs::write(&json_path, json.to_string())
        .map_err(|e| format!("{}: cannot write: {e}", json_path.display()))?;
    let md_path = dir.join("grade.md");
    std::fs::write(
        &md_path,
        markdown(name, launcher, checks, shootout, &verdict),
    )
    .map_err(|e| format!("{}: cannot write: {e}", md_path.display()))?;
    println!("\n{verdict}");
    Ok(md_path)
}

fn count(checks: &[Check], part: Part, status: Status) -> usize {
    checks
        .iter()
        .filter(|c| c.part == part && c.status == status)
        .count()
}

/// One line: each part's passed checks, and the shootout's verdict.
fn verdict(name: &str, checks: &[Check], shootout: &Result<serde_json::Value, String>) -> String {
    let parts: Vec<String> = Part::ALL
        .iter()
        .map(|&p| {
            let of = checks.iter().filter(|c| c.part == p).count();
            let done = count(checks, p, Status::Passed);
            let todo = count(checks, p, Status::NotImplemented);
            if todo == of && of > 0 {
                format!("{} not implemented yet", p.name())
            } else {
                format!("{} {done}/{of}", p.name())
            }
        })
        .collect();
    let shootout = match shootout {
        Ok(s) => s["verdict"].as_str().unwrap_or_default().to_string(),
        Err(e) if e.starts_with("not run") => "not run".into(),
        Err(_) => "did not finish".into(),
    };
    format!(
        "Verdict for {name}: kit checks passed: {}; shootout: {shootout}.",
        parts.join(", ")
    )
}

fn cell(status: Status) -> &'static str {
    match status {
        Status::Passed => "pass",
        Status::Failed => "**FAIL**",
        Status::NotImplemented => "todo",
        Status::Panicked => "**panic**",
        Status::Stuck => "**stuck**",
        Status::Crashed => "**crash**",
        Status::NotRun => "not run",
    }
}

fn markdown(
    name: &str,
    launcher: &Launcher,
    checks: &[Check],
    shootout: &Result<serde_json::Value, String>,
    verdict: &str,
) -> String {
    let passed = checks.iter().filter(|c| c.status == Status::Passed).count();
    let mut md = format!(
        "# Grade: {name}\n\n{verdict}\n\n## Conformance kit: {passed} of {} checks passed\n\n\
         Each check runs one part of the kit on one scene and compares every answer with brute \
         force. `todo` is a `todo!()` the check reached (a step not written yet); `stuck` a \
         build or query that did not return within {} s (`--grade-stall`); `crash` a process that died (a stack \
         overflow, say); `not run` a part given up after {} such checks.\n\n| scene |",
        checks.len(),
        launcher.stall_seconds,
        launch::GIVE_UP,
    );
    for p in Part::ALL {
        let _ = write!(md, " {} |", p.name());
    }
    md.push_str("\n| --- |");
    md.push_str(&" :---: |".repeat(Part::ALL.len()));
    md.push('\n');
    let mut scenes: Vec<&str> = Vec::new();
    for c in checks {
        if !scenes.contains(&c.scene.as_str()) {
            scenes.push(&c.scene);
        }
    }
    for scene in &scenes {
        let _ = write!(md, "| {scene} |");
        for p in Part::ALL {
            let status = checks
                .iter()
                .find(|c| c.part == p && c.scene == *scene)
                .map_or("-", |c| cell(c.status));
            let _ = write!(md, " {status} |");
        }
        md.push('\n');
    }
    for p in Part::ALL {
        let bad: Vec<&Check> = checks
            .iter()
            .filter(|c| c.part == p && !matches!(c.status, Status::Passed | Status::NotRun))
            .collect();
        if bad.is_empty() {
            continue;
        }
        let _ = writeln!(md, "\n### {}\n", p.name());
        // Checks that stopped at the same `todo!()` say the same thing: once is enough.
        let mut said: Vec<String> = Vec::new();
        for c in bad {
            if let Some(key) = todo_key(c) {
                if said.contains(&key) {
                    continue;
                }
                let same = checks
                    .iter()
                    .filter(|o| o.part == p && todo_key(o).as_ref() == Some(&key))
                    .count();
                let _ = writeln!(
                    md,
                    "**{}: not implemented yet** ({same} scene{}): `{}`\n",
                    c.scene,
                    if same == 1 { "" } else { "s" },
                    key
                );
                said.push(key);
                continue;
            }
            let _ = writeln!(
                md,
                "**{}: {}**\n\n```text\n{}\n```\n",
                c.scene,
                c.status.name(),
                c.message
            );
            if let Some(replay) = launch::replay(launcher, c) {
                let how = if c.status == Status::Stuck {
                    "Replay this ray step by step (it did not return here, so `explain` will not \
                     either: stop it with Ctrl-C; a step counter in your loop that panics past a \
                     limit shows where it goes round)"
                } else {
                    "Replay this ray step by step"
                };
                let _ = writeln!(md, "{how}:\n\n```text\n{replay}\n```\n");
            } else if c.scene == "random_scenes" {
                md.push_str(
                    "A random scene: the message shows the shrunk scene and ray as Rust, to paste \
                     into a test with `rt_conformance::check_case`.\n\n",
                );
            }
        }
    }
    match shootout {
        Ok(s) => md.push_str(s["markdown"].as_str().unwrap_or_default()),
        Err(e) => {
            let what = if e.starts_with("not run") {
                "was"
            } else {
                "did not finish:"
            };
            let _ = writeln!(md, "\n## Shootout\n\nThe shootout {what} {e}.");
        }
    }
    md
}

/// The `todo!()` a not-implemented check stopped at: its message (`not yet implemented: step
/// 5: ...`) and where it is.
fn todo_key(c: &Check) -> Option<String> {
    if c.status != Status::NotImplemented {
        return None;
    }
    let start = c
        .message
        .find("not yet implemented")
        .or_else(|| c.message.find("not implemented"))?;
    let what = c.message[start..].lines().next().unwrap_or_default();
    let at = c
        .message
        .lines()
        .find_map(|l| l.trim().strip_prefix("panicked at: "));
    Some(match at {
        Some(at) => format!("{what}` at `{at}"),
        None => what.to_string(),
    })
}

//! Helpers shared by the CLI tests.

use std::process::{Command, Output};

/// Bad input: exit status 2, exactly one line on stderr that starts with `error: ` and contains
/// `needle`, and nothing on stdout.
pub fn assert_one_line_error(out: &Output, needle: &str) {
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "stderr: {err}");
    assert!(
        err.starts_with("error: ") && err.contains(needle),
        "stderr: {err}"
    );
    assert!(out.stdout.is_empty());
}

/// Runs `cargo xtask TASK ARGS...` (the binary this package builds) and collects its output.
pub fn xtask(task: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_xtask"))
        .arg(task)
        .args(args)
        .output()
        .expect("xtask runs")
}

/// Runs `cargo xtask TASK ARGS...`, which must succeed, and parses the one JSON object it
/// prints (the caller passes `--json`).
#[allow(dead_code)] // Not every test file that includes this module runs JSON tasks.
pub fn json(task: &str, args: &[&str]) -> serde_json::Value {
    let out = xtask(task, args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

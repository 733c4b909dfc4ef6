//! The README and the guide stay true: every command they show in a `sh` block runs as shown
//! (or, for `cargo` commands that build benchmarks and examples, names targets that exist),
//! every relative link points at a file (and heading) that exists, and the README stays a front
//! page. The guide's Rust examples are compiled and run as doctests of `rt-shootout`.
//!
//! Conventions the guide follows so that this test can run it:
//! - a command is one line of a ```` ```sh ```` block (a `\` continues it), from the
//!   repository root; `# exits N` after it says the status it must exit with (default 0);
//! - `-o`/`--out` paths are redirected into a scratch folder, so a run writes nothing into the
//!   repository;
//! - a command `.ci/run` runs itself (`cargo test --workspace`) is left to CI.
//!
//! `cargo xtask ...` runs the xtask binary these tests were built with, the README's
//! `cargo xtask compare` among them (CI runs it nowhere else); a test below checks that the
//! `xtask` alias runs that package.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The README and every guide page but the generated results page.
fn guide_pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .filter(|p| !p.ends_with("results.md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// One shown command: where, the words, and the exit status it must end with.
#[derive(Debug)]
struct Shown {
    page: String,
    words: Vec<String>,
    status: i32,
}

/// The commands of a page's `sh` blocks.
fn commands(page: &Path) -> Vec<Shown> {
    let text = std::fs::read_to_string(page).unwrap();
    let name = page.file_name().unwrap().to_string_lossy().into_owned();
    let mut out = Vec::new();
    let mut in_sh = false;
    let mut pending = String::new();
    for line in text.lines() {
        if line.starts_with("```") {
            in_sh = line.trim() == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        if let Some(head) = line.strip_suffix('\\') {
            pending += head;
            continue;
        }
        let full = std::mem::take(&mut pending) + line;
        let (command, comment) = full.split_once('#').unwrap_or((&full, ""));
        if command.trim().is_empty() {
            continue;
        }
        let status = comment
            .trim()
            .strip_prefix("exits ")
            .and_then(|s| s.split(|c: char| !c.is_ascii_digit()).next())
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        out.push(Shown {
            page: name.clone(),
            words: command.split_whitespace().map(String::from).collect(),
            status,
        });
    }
    out
}

/// The lines `.ci/run` runs itself.
fn ci_commands() -> BTreeSet<String> {
    std::fs::read_to_string(root().join(".ci/run"))
        .unwrap()
        .lines()
        .map(|l| l.trim().to_owned())
        .collect()
}

/// Runs `cargo xtask ARGS` as shown, from the repository root, with its output files in
/// `scratch`; returns a failure message, if any.
fn run_xtask(shown: &Shown, scratch: &Path) -> Option<String> {
    let mut args: Vec<String> = shown.words[2..].to_vec();
    for i in 0..args.len() {
        if (args[i] == "-o" || args[i] == "--out") && i + 1 < args.len() {
            let name = Path::new(&args[i + 1]).file_name().unwrap().to_owned();
            args[i + 1] = scratch.join(name).to_string_lossy().into_owned();
        }
    }
    let out = Command::new(env!("CARGO_BIN_EXE_xtask"))
        .args(&args)
        .current_dir(root())
        .output()
        .expect("xtask runs");
    (out.status.code() != Some(shown.status)).then(|| {
        format!(
            "{}: `{}` exited with {:?}, not {}: {}",
            shown.page,
            shown.words.join(" "),
            out.status.code(),
            shown.status,
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("")
        )
    })
}

/// Every package of the repository (the workspace and the labs), by name, with its folder.
fn packages() -> Vec<(String, PathBuf)> {
    let mut found = Vec::new();
    let mut stack = vec![root()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let skip = path
                .file_name()
                .is_some_and(|n| n == "target" || n.to_string_lossy().starts_with('.'));
            if path.is_dir() && !skip {
                stack.push(path);
            } else if path.ends_with("Cargo.toml") {
                let text = std::fs::read_to_string(&path).unwrap();
                if let Some(name) = text
                    .lines()
                    .find_map(|l| l.strip_prefix("name = \""))
                    .and_then(|l| l.strip_suffix('"'))
                {
                    found.push((name.to_owned(), dir.clone()));
                }
            }
        }
    }
    found
}

/// Checks a `cargo run`, `cargo bench` or `cargo test` line without running it (they build
/// benchmarks or the whole suite): its package, example, bench and features exist.
fn check_cargo(shown: &Shown, cwd: &Path, packages: &[(String, PathBuf)]) -> Option<String> {
    let w = &shown.words;
    let value = |flag: &str| w.iter().position(|x| x == flag).and_then(|i| w.get(i + 1));
    let dir = match value("-p") {
        Some(p) => match packages.iter().find(|(n, _)| n == p) {
            Some((_, d)) => d.clone(),
            None => return Some(format!("{}: no package {p}", shown.page)),
        },
        None => cwd.to_path_buf(),
    };
    let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap_or_default();
    let exists = |kind: &str, name: &str| {
        dir.join(format!("{kind}/{name}.rs")).is_file()
            || dir.join(format!("{kind}/{name}/main.rs")).is_file()
            || manifest.contains(&format!("name = \"{name}\""))
    };
    if let Some(example) = value("--example").filter(|e| !exists("examples", e)) {
        return Some(format!(
            "{}: no example {example} in {}",
            shown.page,
            dir.display()
        ));
    }
    if let Some(bench) = value("--bench").filter(|b| !exists("benches", b)) {
        return Some(format!(
            "{}: no bench {bench} in {}",
            shown.page,
            dir.display()
        ));
    }
    if let Some(feature) = value("--features").filter(|f| !manifest.contains(&format!("\n{f} "))) {
        return Some(format!(
            "{}: no feature {feature} in {}",
            shown.page,
            dir.display()
        ));
    }
    None
}

/// Checks or runs one shown command; a failure message, if any.
fn check(
    shown: &Shown,
    scratch: &Path,
    packages: &[(String, PathBuf)],
    ci: &BTreeSet<String>,
) -> Option<String> {
    let line = shown.words.join(" ");
    if ci.contains(&line) {
        return None;
    }
    let mut cwd = root();
    let mut words: &[String] = &shown.words;
    if words.first().is_some_and(|w| w == "cd") && words.get(2).is_some_and(|w| w == "&&") {
        cwd = root().join(&words[1]);
        if !cwd.join("Cargo.toml").is_file() {
            return Some(format!(
                "{}: `{line}`: no crate in {}",
                shown.page, words[1]
            ));
        }
        words = &words[3..];
    }
    let rest = Shown {
        page: shown.page.clone(),
        words: words.to_vec(),
        status: shown.status,
    };
    match words.iter().map(String::as_str).take(2).collect::<Vec<_>>()[..] {
        ["cargo", "xtask"] => run_xtask(&rest, scratch),
        ["cargo", "run" | "bench" | "test" | "build"] => check_cargo(&rest, &cwd, packages),
        _ => Some(format!(
            "{}: `{line}` is neither a cargo xtask nor a cargo run/bench/test command",
            shown.page
        )),
    }
}

/// `cargo xtask ARGS` runs this package's binary, optimised: the commands above run that binary
/// directly, so they are what the alias runs.
#[test]
fn the_xtask_alias_runs_this_package_in_release() {
    let config = std::fs::read_to_string(root().join(".cargo/config.toml")).unwrap();
    let alias = config
        .lines()
        .find_map(|l| l.trim().strip_prefix("xtask = "))
        .expect("an `xtask` alias in .cargo/config.toml");
    assert_eq!(alias, r#""run --release --package xtask --""#);
    let manifest = std::fs::read_to_string(root().join("xtask/Cargo.toml")).unwrap();
    assert!(manifest.contains("name = \"xtask\""), "{manifest}");
}

#[test]
fn every_shown_command_runs() {
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("docs-commands");
    std::fs::create_dir_all(&scratch).unwrap();
    let shown: Vec<Shown> = guide_pages().iter().flat_map(|p| commands(p)).collect();
    assert!(shown.len() > 20, "{shown:?}");
    let (packages, ci) = (packages(), ci_commands());
    // Two at a time: most of the time goes to the xtask runs, each mostly single-threaded.
    let next = std::sync::atomic::AtomicUsize::new(0);
    let failures = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(cmd) = shown.get(i) else { break };
                    if let Some(f) = check(cmd, &scratch, &packages, &ci) {
                        failures.lock().unwrap().push(f);
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    std::fs::remove_dir_all(&scratch).ok();
}

/// The anchor GitHub gives a heading: lower case, spaces to hyphens, other punctuation dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The results pages, one per machine kind (`docs/results/*.md`).
fn results_pages() -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root().join("docs/results"))
        .expect("docs/results/")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    pages
}

/// The index `docs/results.md` lists every machine kind's page, with its stamp, as
/// `cargo xtask results --index` writes it.
#[test]
fn the_results_index_lists_every_page() {
    let index = std::fs::read_to_string(root().join("docs/results.md")).unwrap();
    let pages = results_pages();
    assert!(!pages.is_empty(), "no page in docs/results/");
    for page in pages {
        let name = page.file_stem().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(&page).unwrap();
        let stamp = text
            .lines()
            .find(|l| l.starts_with("Written by "))
            .unwrap_or_else(|| panic!("{}: no stamp", page.display()));
        let row = format!("| [{name}](results/{name}.md) | {stamp} |");
        assert!(
            index.contains(&row),
            "docs/results.md lacks the row of {name} (run `cargo xtask results --index`):\n{row}"
        );
    }
}

/// Every Markdown file of the repository that a reader follows links in.
fn linked_pages() -> Vec<PathBuf> {
    let mut pages = guide_pages();
    pages.push(root().join("docs/results.md"));
    pages.extend(results_pages());
    for extra in ["ARCHITECTURE.md", "labs/README.md", "fuzz/README.md"] {
        pages.push(root().join(extra));
    }
    for entry in std::fs::read_dir(root().join("crates")).unwrap() {
        let readme = entry.unwrap().path().join("README.md");
        if readme.is_file() {
            pages.push(readme);
        }
    }
    pages
}

#[test]
fn every_relative_link_resolves() {
    let mut broken = Vec::new();
    for page in linked_pages() {
        let Ok(text) = std::fs::read_to_string(&page) else {
            broken.push(format!("{} is missing", page.display()));
            continue;
        };
        for (i, _) in text.match_indices("](") {
            let rest = &text[i + 2..];
            let Some(end) = rest.find(')') else { continue };
            let target = &rest[..end];
            if target.contains("://") || target.starts_with('#') || target.contains(' ') {
                continue;
            }
            let (file, anchor) = target.split_once('#').unwrap_or((target, ""));
            let path = page.parent().unwrap().join(file);
            if !path.exists() {
                broken.push(format!("{}: {target}", page.display()));
            } else if !anchor.is_empty() {
                let headings: Vec<String> = std::fs::read_to_string(&path)
                    .unwrap_or_default()
                    .lines()
                    .filter_map(|l| l.strip_prefix('#'))
                    .map(|l| slug(l.trim_start_matches('#')))
                    .collect();
                if !headings.iter().any(|h| h == anchor) {
                    broken.push(format!("{}: {target} (no such heading)", page.display()));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_readme_is_a_front_page() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    assert!(
        readme.len() < 15 * 1024,
        "README.md is {} bytes",
        readme.len()
    );
    // The two set-up commands. `.ci/run` runs the test command exactly as shown; the shootout
    // runs as shown in `every_shown_command_runs`, which leaves to CI only what CI runs.
    for command in ["cargo xtask compare", "cargo test --workspace"] {
        assert!(readme.contains(&format!("{command} ")), "{command}");
    }
    let ci = ci_commands();
    assert!(
        ci.contains("cargo test --workspace"),
        ".ci/run does not run `cargo test --workspace`"
    );
    let shown = commands(&root().join("README.md"));
    assert!(
        shown
            .iter()
            .any(|s| s.words.join(" ") == "cargo xtask compare" && s.status == 0),
        "the README shows no `cargo xtask compare` line: {shown:?}"
    );
    assert!(
        !ci.contains("cargo xtask compare"),
        "`cargo xtask compare` runs in the tests; .ci/run need not build it again"
    );
}

#[test]
fn the_slug_rule_matches_github() {
    assert_eq!(
        slug(" Where the meshes come from"),
        "where-the-meshes-come-from"
    );
    assert_eq!(
        slug(" Dynamic scenes: `cargo xtask animate`"),
        "dynamic-scenes-cargo-xtask-animate"
    );
}

/// The crates whose sources ARCHITECTURE.md lists: every directory under `crates/`, xtask and
/// the benchmarks, each with the heading of its section.
fn documented_crates() -> Vec<(String, PathBuf)> {
    let root = root();
    let mut crates: Vec<(String, PathBuf)> = std::fs::read_dir(root.join("crates"))
        .expect("crates/")
        .map(|e| e.expect("an entry of crates/").path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), p))
        .collect();
    crates.push(("xtask".into(), root.join("xtask")));
    crates.push(("benches".into(), root.join("benches")));
    crates.push(("python".into(), root.join("python")));
    crates.sort();
    crates
}

/// Every `.rs` file under `dir`, as paths relative to it with `/` between components.
fn rust_files(dir: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.expect("a directory entry").path();
            if p.is_dir() {
                todo.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p.strip_prefix(dir).expect("below the directory");
                let parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.insert(parts.join("/"));
            }
        }
    }
    out
}

/// What is wrong between `text` (ARCHITECTURE.md) and the sources: a crate's source file its
/// section (`## name`) does not name, or a named file that does not exist.
fn architecture_problems(text: &str) -> Vec<String> {
    let root = root();
    // The sections, by the first word of their heading.
    let mut sections: Vec<(String, String)> = Vec::new();
    for line in text.lines() {
        if let Some(heading) = line.strip_prefix("## ") {
            let name = heading.split_whitespace().next().unwrap_or("").to_string();
            sections.push((name, String::new()));
        } else if let Some((_, body)) = sections.last_mut() {
            body.push_str(line);
            body.push('\n');
        }
    }
    let mut problems = Vec::new();
    for (name, dir) in documented_crates() {
        let Some(body) = sections
            .iter()
            .filter(|(s, _)| *s == name)
            .map(|(_, b)| b.as_str())
            .reduce(|_, b| b)
        else {
            problems.push(format!("no section `## {name}` for {}", dir.display()));
            continue;
        };
        let src = dir.join("src");
        let files = rust_files(&src);
        let prefix = dir
            .strip_prefix(&root)
            .expect("below the root")
            .to_string_lossy()
            .replace('\\', "/");
        let mut named = BTreeSet::new();
        // Every `…rs` between backticks: a path below the crate's `src/` (`traverse.rs`,
        // `builder/reinsert.rs`), below the crate (`tests/…`, `examples/…`, `benches/…`), or
        // below the repository (`crates/…`, `xtask/…`).
        for token in body.split('`').skip(1).step_by(2) {
            if !token.ends_with(".rs") || token.contains(char::is_whitespace) || token.contains('*')
            {
                continue;
            }
            let first = token.split('/').next().unwrap_or("");
            let path = if ["crates", "xtask", "benches", "labs", "fuzz"].contains(&first)
                && token.contains('/')
            {
                let from_root = root.join(token);
                if let Some(rest) = token.strip_prefix(&format!("{prefix}/src/")) {
                    named.insert(rest.to_string());
                }
                from_root
            } else if ["tests", "examples", "benches", "src"].contains(&first) {
                if let Some(rest) = token.strip_prefix("src/") {
                    named.insert(rest.to_string());
                }
                dir.join(token)
            } else {
                named.insert(token.to_string());
                src.join(token)
            };
            if !path.is_file() {
                problems.push(format!("## {name} names `{token}`, which does not exist"));
            }
        }
        for f in files.difference(&named) {
            problems.push(format!("## {name} does not name {prefix}/src/{f}"));
        }
    }
    problems
}

/// ARCHITECTURE.md names every source file of every crate in that crate's section, and every
/// file it names exists: a file added, moved or removed without the page following fails here,
/// naming it.
#[test]
fn the_architecture_names_every_source_file() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let problems = architecture_problems(&text);
    assert!(
        problems.is_empty(),
        "ARCHITECTURE.md and the sources disagree:\n{}",
        problems.join("\n")
    );
}

/// The check fails a page that forgets a file or names one that is gone.
#[test]
fn the_architecture_check_finds_a_missing_and_a_stale_file() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let doctored = text
        .replace("`watertight.rs`", "the watertight kernel")
        .replace("`slab.rs`", "`slab_old.rs`");
    let problems = architecture_problems(&doctored);
    assert!(
        problems
            .iter()
            .any(|p| p.contains("does not name crates/rt-simd/src/watertight.rs")),
        "{problems:?}"
    );
    assert!(
        problems
            .iter()
            .any(|p| p.contains("names `slab_old.rs`, which does not exist")),
        "{problems:?}"
    );
}

/// The modules of one flat crate `src` directory and the sibling modules each one's code (not
/// its comments, not its `#[cfg(test)]` part) names: through `crate::module`, `super::module`,
/// or an item the crate root re-exports from that module (`crate::Hit`, `crate::{Ray, Aabb}`).
fn module_imports(sources: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    let modules: BTreeSet<String> = sources.keys().filter(|m| *m != "lib").cloned().collect();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    // `pub use module::{A, B};` and `pub use module::A;` in lib.rs: item -> module.
    let mut home = BTreeMap::new();
    let lib = sources.get("lib").map(String::as_str).unwrap_or("");
    for stmt in lib.split("pub use ").skip(1) {
        let stmt = stmt.split(';').next().unwrap_or("");
        let Some((module, items)) = stmt.split_once("::") else {
            continue;
        };
        if modules.contains(module) {
            for item in items.split(|c: char| !(c.is_alphanumeric() || c == '_')) {
                if !item.is_empty() {
                    home.insert(item.to_string(), module.to_string());
                }
            }
        }
    }
    let mut graph = BTreeMap::new();
    for m in &modules {
        let text = &sources[m];
        let code: String = text
            .split("#[cfg(test)]")
            .next()
            .unwrap_or("")
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n")
            .replace("$crate", "");
        let mut names = Vec::new();
        for prefix in ["crate::", "super::"] {
            for rest in code.split(prefix).skip(1) {
                if let Some(group) = rest.strip_prefix('{') {
                    let group = group.split('}').next().unwrap_or("");
                    names.extend(
                        group
                            .split(|c: char| !(c.is_alphanumeric() || c == '_'))
                            .map(String::from),
                    );
                } else {
                    names.push(ident(rest));
                }
            }
        }
        let deps: BTreeSet<String> = names
            .iter()
            .filter_map(|n| {
                if modules.contains(n) {
                    Some(n.clone())
                } else {
                    home.get(n).cloned()
                }
            })
            .filter(|d| d != m)
            .collect();
        graph.insert(m.clone(), deps);
    }
    graph
}

/// A circle of imports in `graph`, as the modules around it (`a -> b -> a`), if there is one.
fn import_circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<String> {
    // Depth-first, with the path so far: reaching a module on the path closes a circle.
    fn visit(
        m: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<String> {
        if let Some(at) = path.iter().position(|p| p == m) {
            let mut circle = path[at..].to_vec();
            circle.push(m.to_string());
            return Some(circle.join(" -> "));
        }
        if !done.insert(m.to_string()) {
            return None;
        }
        path.push(m.to_string());
        for d in graph.get(m).into_iter().flatten() {
            if let Some(c) = visit(d, graph, path, done) {
                return Some(c);
            }
        }
        path.pop();
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|m| visit(m, graph, &mut Vec::new(), &mut done))
}

/// rt-core's sources, by module name.
fn rt_core_sources() -> BTreeMap<String, String> {
    let src = root().join("crates/rt-core/src");
    rust_files(&src)
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(src.join(&f)).expect("a source of rt-core");
            (f.trim_end_matches(".rs").to_string(), text)
        })
        .collect()
}

/// rt-core's modules import each other in layers (ARCHITECTURE.md, "## rt-core"): a reader can
/// start from the bottom, and no change brings back a circle like the one the SIMD lanes, the
/// bundles and the kernels once made.
#[test]
fn rt_core_modules_import_in_layers() {
    let graph = module_imports(&rt_core_sources());
    assert!(
        graph.len() > 20,
        "rt-core's modules were not read: {graph:?}"
    );
    assert_eq!(import_circle(&graph), None);
}

/// The check finds a circle made through a re-exported item, as `Hit` in `accel.rs` once made
/// one with `query.rs`.
#[test]
fn the_layer_check_finds_a_circle() {
    let mut sources = rt_core_sources();
    let hit = sources.get_mut("hit").expect("hit.rs");
    hit.insert_str(0, "use crate::{Accel, Ray};\n");
    let circle = import_circle(&module_imports(&sources)).expect("a circle through hit.rs");
    assert!(
        circle.contains("hit") && circle.contains("accel"),
        "{circle}"
    );
}

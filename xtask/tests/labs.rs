//! The lab templates are their reference solutions with each solution replaced by a stub: a
//! teacher edits a solution, and this test names the template lines that must follow.

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The template text of a solution file: each block from `// BEGIN SOLUTION step N: what` to
/// `// END SOLUTION` becomes `todo!("step N: what")`, or a comment where it lists a struct's
/// fields.
fn stubbed(solution: &str) -> String {
    let mut out = String::new();
    let mut inside = false;
    for line in solution.lines() {
        let trimmed = line.trim_start();
        if let Some(what) = trimmed.strip_prefix("// BEGIN SOLUTION ") {
            let indent = &line[..line.len() - trimmed.len()];
            out += &if what.contains("fields") {
                let mut c = what.chars();
                let first = c.next().map(|f| f.to_uppercase().to_string());
                format!("{indent}// {}{}.\n", first.unwrap_or_default(), c.as_str())
            } else {
                format!("{indent}todo!(\"{what}\")\n")
            };
            inside = true;
        } else if trimmed == "// END SOLUTION" {
            inside = false;
        } else if !inside {
            out += line;
            out.push('\n');
        }
    }
    out
}

/// The template's `lib.rs` without the lines that quiet its stubs' warnings.
fn without_allow(template_lib: &str) -> String {
    let allow = "\n// Until a step is written, its stub leaves parameters and imports unused. (The \
                 reference\n// solution's copy of this file has no such line.)\n\
                 #![allow(unused_imports, unused_variables)]\n";
    template_lib.replacen(allow, "", 1)
}

#[test]
fn every_template_is_its_solution_with_stubs() {
    let solutions = root().join("labs/solutions");
    let mut labs = 0;
    for lab in std::fs::read_dir(&solutions).expect("labs/solutions exists") {
        let lab = lab.unwrap().path();
        let name = lab.file_name().unwrap().to_owned();
        let template = root().join("labs").join(&name);
        for file in std::fs::read_dir(lab.join("src")).unwrap() {
            let file = file.unwrap().path();
            let solution = std::fs::read_to_string(&file).unwrap();
            let twin = template.join("src").join(file.file_name().unwrap());
            let got = std::fs::read_to_string(&twin)
                .unwrap_or_else(|e| panic!("{}: {e}", twin.display()));
            let (got, want) = if file.ends_with("lib.rs") {
                (without_allow(&got), solution)
            } else {
                (got, stubbed(&solution))
            };
            if got != want {
                let line = got.lines().zip(want.lines()).position(|(a, b)| a != b);
                panic!(
                    "{} is not {} with stubs (first difference at line {})",
                    twin.display(),
                    file.display(),
                    line.map_or("end".into(), |l| (l + 1).to_string())
                );
            }
            if !file.ends_with("lib.rs") {
                assert!(got.contains("todo!(\"step "), "{}: no stub", twin.display());
            }
        }
        assert!(template.join("tests/steps.rs").exists());
        assert!(template.join("HANDOUT.md").exists());
        labs += 1;
    }
    assert!(labs >= 1, "no lab found");
}

/// The assert macros in `text` (`assert!`, `assert_eq!`, `assert_ne!`) that carry no message:
/// their line and their macro, for a step test whose failure must say which case failed.
fn bare_asserts(text: &str) -> Vec<(usize, &'static str)> {
    let mut bare = Vec::new();
    for (at, _) in text.match_indices("assert") {
        let rest = &text[at..];
        let (name, needed) = if rest.starts_with("assert!(") {
            ("assert!", 2)
        } else if rest.starts_with("assert_eq!(") {
            ("assert_eq!", 3)
        } else if rest.starts_with("assert_ne!(") {
            ("assert_ne!", 3)
        } else {
            continue;
        };
        // Count the arguments: commas at the macro's own depth, outside strings and chars.
        let open = at + name.len();
        let (mut depth, mut args, mut in_str, mut escaped, mut any) =
            (0i32, 1, false, false, false);
        let mut chars = text[open..].char_indices().peekable();
        while let Some((_, c)) = chars.next() {
            if in_str {
                match (escaped, c) {
                    (true, _) => escaped = false,
                    (false, '\\') => escaped = true,
                    (false, '"') => in_str = false,
                    _ => {}
                }
                continue;
            }
            match c {
                '"' => in_str = true,
                '\'' => {
                    // A char literal such as ',' (a lifetime has no closing quote two on).
                    let ahead: String = chars.clone().take(3).map(|(_, c)| c).collect();
                    if ahead.chars().nth(1) == Some('\'') {
                        chars.next();
                        chars.next();
                    }
                }
                '(' | '[' | '{' => depth += 1,
                ')' | ']' | '}' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                ',' if depth == 1 => {
                    // A trailing comma before the closing parenthesis adds no argument.
                    let next = text[open..].get(chars.peek().map_or(0, |&(i, _)| i)..);
                    if !next.is_some_and(|n| n.trim_start().starts_with(')')) {
                        args += 1;
                    }
                }
                _ => any = true,
            }
        }
        if any && args < needed {
            bare.push((text[..at].matches('\n').count() + 1, name));
        }
    }
    bare
}

#[test]
fn bare_assert_finder_finds_them() {
    let text = "assert!(a);\nassert!(a, \"why\");\nassert_eq!(f(a, b), c);\nassert_eq!(a, b, \"{}, {}\", x, y);\nassert_eq!(\n    a,\n    [1, 2],\n);\nassert!(s == \",\", \"a comma\");\n";
    assert_eq!(
        bare_asserts(text),
        [(1, "assert!"), (3, "assert_eq!"), (5, "assert_eq!")]
    );
}

/// Every assert in a lab's step tests says which case failed: a student reads the message, not
/// the test's source.
#[test]
fn every_step_test_assert_has_a_message() {
    let mut bare = Vec::new();
    for lab in std::fs::read_dir(root().join("labs")).expect("labs exists") {
        let steps = lab.unwrap().path().join("tests/steps.rs");
        let Ok(text) = std::fs::read_to_string(&steps) else {
            continue;
        };
        for (line, name) in bare_asserts(&text) {
            bare.push(format!(
                "{}:{line}: {name} without a message",
                steps.display()
            ));
        }
    }
    assert!(
        bare.is_empty(),
        "step test asserts without a message:\n{}",
        bare.join("\n")
    );
}

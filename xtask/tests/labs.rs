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

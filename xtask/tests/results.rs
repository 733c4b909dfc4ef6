//! `cargo xtask results` as a user runs it, in its quick form: the page has its stamp, every
//! section, and above every table the command that produced it.

mod common;

use common::{assert_one_line_error, xtask};

#[test]
fn the_quick_page_has_every_section_and_its_commands() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("results");
    std::fs::create_dir_all(&dir).unwrap();
    let page = dir.join("results.md");
    let out = xtask("results", &["--quick", "-o", page.to_str().unwrap()]);
    assert!(out.status.success(), "{out:?}");
    let text = std::fs::read_to_string(&page).unwrap();
    assert!(text.starts_with("# Results\n"), "{text}");
    assert!(text.contains("at commit "), "{text}");
    for section in [
        "## Primary rays",
        "## More meshes",
        "## Other rays",
        "## One thread",
        "## Ray bundles",
        "## Closest points",
        "## Signed distance",
        "## Instances",
        "## Scale",
        "## Dynamic scenes",
    ] {
        assert!(text.contains(section), "no {section} in:\n{text}");
    }
    // Every table comes with the commands that measured it.
    let commands = text.matches("`cargo xtask ").count() - 1; // less the stamp's own
    let tables = text.matches("\n| --- |").count() + text.matches("\n| ---: |").count();
    assert!(
        commands >= tables && tables >= 10,
        "{commands} commands, {tables} tables:\n{text}"
    );
    assert!(text.contains("| bvh | "), "{text}");
    assert!(text.contains("% of them hit"), "{text}");
    assert!(text.contains("% of them are inside"), "{text}");
    // The bundle table ends with each ray kind's geometric mean.
    for kind in ["primary", "shadow", "incoherent"] {
        assert!(
            text.contains(&format!("| geometric mean | {kind} |")),
            "no {kind} mean in:\n{text}"
        );
    }
}

#[test]
fn an_unwritable_page_is_a_one_line_error() {
    assert_one_line_error(
        &xtask("results", &["--quick", "-o", "/no/such/dir/results.md"]),
        "cannot write Markdown",
    );
}

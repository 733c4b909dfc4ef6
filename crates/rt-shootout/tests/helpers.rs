//! The command line's small helpers: counts with suffixes, clap's messages on one line, and the
//! sizes `scale` steps through.

use rt_shootout::cli::{count, one_line};
use rt_shootout::scale::ladder;

#[test]
fn counts_take_suffixes() {
    assert_eq!(count("20000"), Ok(20_000));
    assert_eq!(count("0"), Ok(0));
    assert_eq!(count("20k"), Ok(20_000));
    assert_eq!(count("1.5M"), Ok(1_500_000));
    assert!(count("lots").unwrap_err().contains("`lots` is not a count"));
}

#[test]
fn clap_messages_become_one_line() {
    let message = "error: invalid value 'pink' for '--fill <FILL>'\n  [possible values: depth, prims]\n\nFor more information, try '--help'.\n";
    assert_eq!(
        one_line(message),
        "invalid value 'pink' for '--fill <FILL>' [possible values: depth, prims]"
    );
}

#[test]
fn the_ladder_goes_up_by_one_and_three_times_powers_of_ten() {
    assert_eq!(
        ladder(10_000, 10_000_000),
        [
            10_000, 30_000, 100_000, 300_000, 1_000_000, 3_000_000, 10_000_000
        ]
    );
    assert_eq!(ladder(5_000, 50_000), [10_000, 30_000, 50_000]);
    assert_eq!(ladder(7, 7), [7]);
}

/// The library has no unit-test target (`test = false` in its manifest, see there), so a unit
/// test written under `src/` would never run: this keeps them out.
#[test]
fn the_library_keeps_its_tests_under_tests() {
    fn visit(dir: &std::path::Path, found: &mut Vec<String>) {
        for entry in std::fs::read_dir(dir).expect("src is readable") {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                visit(&path, found);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).expect("a source file");
                if text.contains("#[test]") || text.contains("#[cfg(test)]") {
                    found.push(path.display().to_string());
                }
            }
        }
    }
    let mut found = Vec::new();
    visit(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut found,
    );
    assert!(
        found.is_empty(),
        "unit tests that would never run: {found:?}"
    );
}

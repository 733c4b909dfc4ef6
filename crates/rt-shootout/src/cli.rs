//! What every subcommand of `cargo xtask` (and a shootout example's `main`) shares on its command
//! line, so that a flag means the same thing everywhere:
//!
//! - `-s, --structures A,B,...`: the rows, a comma-separated list, as `compare` names them.
//!   Commands that compare rows (`compare`, `scale`, `animate`, `render --heatmap`) default to
//!   several ([`MAIN_ROWS`]; `compare` to every row); commands that show one structure (`render`,
//!   `draw`, `explain`) default to [`DEFAULT_ROW`] and take each listed row in turn.
//! - `-o, --out PATH`: where output files go.
//! - `-j, --threads N`: worker threads.
//! - counts take size suffixes: `--points 1M`, `--check-rays 20k` ([`count`]); scenes take
//!   them too (`--scene terrain:500k`).
//! - closed sets of values are clap value enums, so `--help` lists them.
//! - bad input is one `error:` line and exit status 2 ([`exit_on_error`]).

/// The rows that commands comparing structures default to: one of each kind.
pub const MAIN_ROWS: &[&str] = &["bvh", "kdtree", "grid", "hgrid", "octree"];

/// The row that commands showing one structure default to.
pub const DEFAULT_ROW: &str = "bvh";

/// `--structures` as given, or `default` when it was not: the rows a command runs.
pub fn rows_or(given: &[String], default: &[&str]) -> Vec<String> {
    if given.is_empty() {
        default.iter().map(|s| (*s).to_owned()).collect()
    } else {
        given.to_vec()
    }
}

/// Parses a count: a whole number, or one with a size suffix (`k` for thousand, `M` for million,
/// either case; `1.5M` too) up to 100M. The value parser of every count flag.
///
/// # Errors
/// A message naming the text, for clap to print.
pub fn count(text: &str) -> Result<usize, String> {
    if let Ok(n) = text.parse::<usize>() {
        return Ok(n);
    }
    rt_scene::scenes::parse_size(text).ok_or_else(|| {
        format!("`{text}` is not a count (a whole number, or with k or M: 20k, 1.5M)")
    })
}

/// Parses a tile size `WxH` in pixels (`8x8`, `16x4`), each side 1 to 256.
///
/// ```
/// assert_eq!(rt_shootout::cli::tile("8x8"), Ok((8, 8)));
/// assert_eq!(rt_shootout::cli::tile("16X4"), Ok((16, 4)));
/// assert!(rt_shootout::cli::tile("8").is_err() && rt_shootout::cli::tile("0x8").is_err());
/// ```
pub fn tile(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{text}` is not a tile size (WxH in pixels, each 1 to 256: 8x8, 16x4)");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let side = |v: &str| v.parse::<u32>().ok().filter(|n| (1..=256).contains(n));
    Ok((side(w).ok_or_else(bad)?, side(h).ok_or_else(bad)?))
}

/// Prints a command-line error as one `error:` line and exits with status 2 (`--help` and
/// `--version` print as usual and exit 0). clap's own message spans several lines (the possible
/// values, a hint, a usage line); they are joined so that every bad input, clap's or ours, is one
/// line.
pub fn exit_on_error(error: clap::Error) -> ! {
    use clap::error::ErrorKind;
    if matches!(
        error.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        error.exit();
    }
    eprintln!("error: {}", one_line(&error.to_string()));
    std::process::exit(2)
}

/// clap's message on one line: without its `error: ` prefix, its usage line and its hint to try
/// `--help`.
pub fn one_line(message: &str) -> String {
    let parts: Vec<&str> = message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more"))
        .collect();
    let joined = parts.join(" ");
    joined.strip_prefix("error: ").unwrap_or(&joined).to_owned()
}

//! A report as a table, as JSON, and its disagreements as replayable rays.

use super::Args;
use super::points;
use crate::data::{BundleRow, Report, Row, three_digits};
use rt_core::Hit;
use std::fmt::Write as _;

/// The report as the table `compare` prints: a header naming the scene, rays and view, a row per
/// structure, and the bundle and disagreement tables where there are any.
pub fn to_table(r: &Report) -> String {
    let mut s = String::new();
    let (unit, units) = match r.ray_kind {
        points::KIND => ("query", "closest-point queries"),
        points::OVERLAP_KIND => ("query", "box overlap queries"),
        points::ALL_HITS_KIND => ("ray", "all-hits queries"),
        points::FILTERED_KIND => ("ray", "filtered queries (alpha mask)"),
        points::SIGNED_KIND => ("query", "signed-distance queries"),
        _ => ("ray", "rays"),
    };
    if points::is_query_kind(r.ray_kind) {
        let (on, verb) = match (r.view, r.ray_kind) {
            ("", points::SIGNED_KIND) => (String::new(), "inside"),
            ("", _) => (String::new(), "meet the mesh"),
            (rays, _) => (format!(" on {rays}"), "hit"),
        };
        let met = r
            .hit_share()
            .map_or(String::new(), |h| format!(" ({:.1}% {verb})", 100.0 * h));
        let _ = writeln!(
            s,
            "scene {} ({} triangles, {} valid), {} {units}{on}{met}, {} threads; {} checked against brute force",
            r.scene, r.triangles, r.valid_triangles, r.rays, r.threads, r.checked_rays
        );
    } else {
        let hits = r
            .hit_share()
            .map_or(String::new(), |h| format!(" ({:.1}% hit)", 100.0 * h));
        let view = if r.view.is_empty() {
            String::new()
        } else {
            format!(" from the {} view", r.view)
        };
        let _ = writeln!(
            s,
            "scene {} ({} triangles, {} valid), {} {} rays{view}{hits}, {} threads; {} rays checked against brute force",
            r.scene, r.triangles, r.valid_triangles, r.rays, r.ray_kind, r.threads, r.checked_rays
        );
    }
    if !r.note.is_empty() {
        let _ = writeln!(s, "{}", r.note);
    }
    let _ = writeln!(
        s,
        "\nCost and speed: build time, memory kept, and per {unit} the nodes or cells entered and the \
         primitives tested; speedup over brute force"
    );
    // The name column fits the longest row name.
    let w = r
        .rows
        .iter()
        .map(|row| row.name.len())
        .max()
        .unwrap_or(0)
        .max("structure".len());
    let _ = writeln!(
        s,
        "{:<w$} {:>9} {:>11} {:>12} {:>12} {:>11} {:>9} {:>10}",
        "structure",
        "build ms",
        "memory MiB",
        format!("visits/{unit}"),
        format!("tests/{unit}"),
        if unit == "ray" {
            "Mrays/s"
        } else {
            "Mqueries/s"
        },
        "speedup",
        "mismatches"
    );
    for row in &r.rows {
        let _ = writeln!(
            s,
            "{:<w$} {:>9.1} {:>11.2} {:>12.1} {:>12} {:>11} {:>8.0}x {:>10}",
            row.name,
            row.build_ms,
            row.memory_bytes as f64 / (1024.0 * 1024.0),
            row.avg_visits,
            // Three digits, since structures a user compares may differ by a few percent.
            three_digits(row.avg_prim_tests),
            three_digits(row.mrays_per_s),
            row.speedup,
            row.mismatches
        );
    }
    // The shape of each structure: what the build produced, independent of the rays.
    let _ = writeln!(
        s,
        "\nShape: nodes, depth, leaves and the share empty, primitives per non-empty leaf, \
         references per primitive, and the tests a mailbox skipped per {unit}"
    );
    let _ = writeln!(
        s,
        "{:<w$} {:>9} {:>5} {:>9} {:>7} {:>10} {:>9} {:>11}  other figures",
        "structure",
        "nodes",
        "depth",
        "leaves",
        "empty",
        "prims/leaf",
        "refs/prim",
        format!("skips/{unit}"),
    );
    for row in r.rows.iter().filter(|row| row.leaves > 0) {
        let _ = writeln!(
            s,
            "{:<w$} {:>9} {:>5} {:>9} {:>6.1}% {:>10.2} {:>9.2} {:>11}  {}",
            row.name,
            row.nodes,
            row.max_depth,
            row.leaves,
            100.0 * row.empty_leaves as f64 / row.leaves as f64,
            row.avg_leaf_prims,
            row.duplication,
            // Mailbox skips: tests a mailbox saved, so `tests/ray` plus this is what the
            // structure would test without one.
            three_digits(row.avg_mailbox_skips),
            row.extra
                .iter()
                .map(|(k, v)| format!("{k} {}", three_digits(*v)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    // What the SAH predicts for lines spread uniformly over the scene box, beside what these
    // rays did: how far the builders' cost model holds.
    let modelled: Vec<&Row> = r
        .rows
        .iter()
        .filter(|row| row.predicted.is_some())
        .collect();
    if !modelled.is_empty() {
        let _ = writeln!(
            s,
            "\nThe SAH's prediction against these {units}: expected visits and tests per ray for \
             lines spread uniformly over the scene box (scaled by the share that enter it), beside \
             what the {units} did; ratio = measured / predicted"
        );
        let _ = writeln!(
            s,
            "{:<w$} {:>14} {:>14} {:>7} {:>14} {:>14} {:>7}",
            "structure",
            "visits (SAH)",
            "visits (rays)",
            "ratio",
            "tests (SAH)",
            "tests (rays)",
            "ratio"
        );
        for row in modelled {
            let p = row.predicted.expect("filtered");
            let ratio = |m: f64, p: f64| if p > 0.0 { m / p } else { f64::NAN };
            let _ = writeln!(
                s,
                "{:<w$} {:>14} {:>14} {:>7.2} {:>14} {:>14} {:>7.2}",
                row.name,
                three_digits(p.visits),
                three_digits(row.avg_visits),
                ratio(row.avg_visits, p.visits),
                three_digits(p.tests),
                three_digits(row.avg_prim_tests),
                ratio(row.avg_prim_tests, p.tests)
            );
        }
    }
    batch_table(
        &mut s,
        w,
        r,
        |row| row.bundle.as_ref(),
        "Bundles: the same rays traced as bundles; speed, and its ratio to the row's single rays \
         measured in the same run; nodes or cells entered per ray (a bundle's step counts once), \
         tests per ray, the share of lanes active at a bundle's steps, the share of rays traced \
         singly, and answers that differ from the single ones in any bit",
    );
    batch_table(
        &mut s,
        w,
        r,
        |row| row.stream.as_ref(),
        "Streams: the same rays traced as streams; speed, and its ratio to the row's single rays \
         measured in the same run; nodes or cells tested per ray, tests per ray, and answers \
         that differ from the single ones in any bit",
    );
    if r.rows.len() > 1 && r.total_mismatches() == 0 {
        let _ = writeln!(s, "all answers agree");
    }
    s
}

/// The table of a batch pass (bundles or streams) beside the rows' single rays, if any row
/// has one.
fn batch_table(
    s: &mut String,
    w: usize,
    r: &Report,
    batch: impl Fn(&Row) -> Option<&BundleRow>,
    title: &str,
) {
    let rows: Vec<(&Row, &BundleRow)> = r
        .rows
        .iter()
        .filter_map(|row| batch(row).map(|b| (row, b)))
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n{title}");
    let _ = writeln!(
        s,
        "{:<w$} {:>11} {:>9} {:>10} {:>10} {:>9} {:>7} {:>11}",
        "structure",
        "Mrays/s",
        "x single",
        "visits/ray",
        "tests/ray",
        "lane use",
        "alone",
        "differences"
    );
    for (row, b) in rows {
        let _ = writeln!(
            s,
            "{:<w$} {:>11} {:>8.2}x {:>10} {:>10} {:>9} {:>6.1}% {:>11}",
            row.name,
            three_digits(b.mrays_per_s),
            b.over_single,
            three_digits(b.avg_visits),
            three_digits(b.avg_prim_tests),
            b.lane_utilisation
                .map_or("-".to_string(), |u| format!("{:.0}%", 100.0 * u)),
            100.0 * b.single_share,
            b.differences
        );
    }
}

fn hit_json(h: Option<Hit>, query_any: bool) -> serde_json::Value {
    match h {
        None if query_any => serde_json::Value::Bool(false),
        Some(_) if query_any => serde_json::Value::Bool(true),
        None => serde_json::Value::Null,
        Some(h) => serde_json::json!({ "prim": h.prim, "t": h.t, "u": h.u, "v": h.v }),
    }
}

pub(super) fn to_json(r: &Report) -> String {
    let any = r
        .rows
        .iter()
        .flat_map(|row| row.answers.iter())
        .flatten()
        .any(|h| h.prim == u32::MAX);
    let results: Vec<serde_json::Value> = r
        .rows
        .iter()
        .map(|row| {
            let mut v = serde_json::json!({
                "structure": row.name,
                "build_ms": row.build_ms,
                "memory_bytes": row.memory_bytes,
                "nodes": row.nodes,
                "max_depth": row.max_depth,
                "hits": row.hits,
                "mismatches": row.mismatches,
                "avg_visits": row.avg_visits,
                "avg_prim_tests": row.avg_prim_tests,
                "avg_mailbox_skips": row.avg_mailbox_skips,
                "extra": row.extra.iter().map(|(k, v)| ((*k).to_string(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
                "mrays_per_s": row.mrays_per_s,
                "speedup": row.speedup,
                "leaves": row.leaves,
                "empty_leaves": row.empty_leaves,
                "avg_leaf_prims": row.avg_leaf_prims,
                "prim_refs": row.prim_refs,
                "duplication": row.duplication,
                "rays_traced": row.rays_traced,
                "predicted_visits": row.predicted.map(|p| p.visits),
                "predicted_tests": row.predicted.map(|p| p.tests),
            });
            for (key, b) in [("bundle", &row.bundle), ("stream", &row.stream)] {
                let Some(b) = b else { continue };
                v[key] = serde_json::json!({
                    "mrays_per_s": b.mrays_per_s,
                    "over_single": b.over_single,
                    "avg_visits": b.avg_visits,
                    "avg_prim_tests": b.avg_prim_tests,
                    "lane_utilisation": b.lane_utilisation,
                    "single_share": b.single_share,
                    "differences": b.differences,
                });
            }
            if r.per_ray_answers {
                v["ray_hits"] = row.answers.iter().map(|&h| hit_json(h, any)).collect();
            }
            v
        })
        .collect();
    serde_json::json!({
        "scene": r.scene,
        "triangles": r.triangles,
        "valid_triangles": r.valid_triangles,
        "query": if points::is_query_kind(r.ray_kind) { r.ray_kind } else { "rays" },
        "ray_kind": r.ray_kind,
        "view": r.view,
        "rays": r.rays,
        "hit_share": r.hit_share(),
        "threads": r.threads,
        "checked_rays": r.checked_rays,
        "note": r.note,
        "results": results,
    })
    .to_string()
}

pub(super) fn describe_disagreements(r: &Report, args: &Args) -> String {
    let mut s = if r.query_disagreements.is_empty() {
        format!(
            "error: {} mismatches. First disagreeing rays (save the rays-file lines to a file and replay with \
             `cargo xtask compare --scene {} --rays-file FILE`, or paste the Rust into a test):\n",
            r.total_mismatches(),
            args.scene
        )
    } else {
        format!(
            "error: {} mismatches. First disagreeing {} queries (paste the Rust into a test on \
             the scene {}):\n",
            r.total_mismatches(),
            r.ray_kind,
            args.scene
        )
    };
    for d in &r.query_disagreements {
        let _ = writeln!(s, "  {} on query {}:", d.structure, d.index);
        let _ = writeln!(s, "    rust:      {}", d.rust);
        let _ = writeln!(s, "    brute-force: {}", d.expected);
        let _ = writeln!(s, "    {}: {}", d.structure, d.got);
    }
    for d in &r.disagreements {
        let _ = writeln!(s, "  {} on ray {}:", d.structure, d.ray_index);
        let _ = writeln!(s, "    rays-file: {}", d.ray.to_line());
        let _ = writeln!(s, "    rust:      {}", d.ray.to_rust());
        let _ = writeln!(s, "    brute-force: {:?}", d.expected);
        let _ = writeln!(s, "    {}: {:?}", d.structure, d.got);
    }
    s
}

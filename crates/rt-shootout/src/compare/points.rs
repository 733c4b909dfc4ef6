//! `compare --query closest-point`: the same shootout for closest-point queries.
//!
//! Every row answers the same points ([`raygen::query_points`]); brute force checks a random
//! subset, the rows are checked against each other on every point, and brute force settles
//! every point on which they disagree, as for rays.

use super::{Args, Report, Row, Source, build_fastest, checked_subset};
use crate::structures;
use rt_core::glam::Vec3;
use rt_core::{DynAccel, Triangle};
use rt_core::{PointHit, Primitive};
use rt_scene::raygen;
use std::time::{Duration, Instant};

/// The report's `ray_kind` for closest-point queries.
pub const KIND: &str = "closest-point";

/// A closest-point query on which a row disagreed with brute force.
#[derive(Debug)]
pub struct PointDisagreement {
    pub structure: String,
    pub index: usize,
    pub point: Vec3,
    pub max_distance: f32,
    pub expected: Option<PointHit>,
    pub got: Option<PointHit>,
}

pub(super) fn measure(
    args: &Args,
    threads: usize,
    entries: Vec<structures::Entry>,
) -> Result<Report, String> {
    if args.instances.is_some() {
        return Err(
            "--query closest-point runs on one mesh; leave out --instances (the library's \
             Instances answer closest points, compare does not field them yet)"
                .into(),
        );
    }
    let source = Source::load(args)?;
    let (scene, tris) = (source.label.clone(), source.mesh.clone());
    let valid = tris.iter().filter(|t| t.is_valid()).count();
    if valid == 0 {
        return Err(format!(
            "{scene}: no valid triangles (all {} are degenerate or non-finite)",
            tris.len()
        ));
    }
    if args.points == 0 {
        return Err("--points must be at least 1".into());
    }
    let max = args.max_distance.unwrap_or(f32::INFINITY);
    if max.is_nan() || max < 0.0 {
        return Err(format!("--max-distance must be at least 0, not {max}"));
    }
    let bounds = rt_core::valid_bounds(tris.iter());
    let queries: Vec<(Vec3, f32)> = raygen::query_points(&tris, &bounds, args.points, args.seed)
        .into_iter()
        .map(|p| (p, max))
        .collect();
    let subset = checked_subset(queries.len(), args.check_rays.unwrap_or(20_000), args.seed);
    let subset_queries: Vec<(Vec3, f32)> = subset.iter().map(|&i| queries[i]).collect();

    let mut rows = Vec::new();
    let mut answers = Vec::new();
    for entry in &entries {
        let (s, build_ms) = build_fastest(|| source.build(entry), args.repeats)?;
        let (row, found) = query_row(&entry.name, s.as_ref(), build_ms, &queries, args.repeats);
        rows.push(row);
        answers.push(found);
    }
    let (brute, build_ms) = build_fastest(|| source.build(&structures::brute_force()), 1)?;
    let (mut brute_row, brute_found) =
        query_row("brute-force", brute.as_ref(), build_ms, &subset_queries, 0);

    let mut disagreements = Vec::new();
    let mut record = |rows: &mut [Row], i: usize, expected: Option<PointHit>| {
        for (row, found) in rows.iter_mut().zip(&answers) {
            if !PointHit::agree(expected, found[i]) {
                row.mismatches += 1;
                if disagreements.len() < 8 {
                    disagreements.push(PointDisagreement {
                        structure: row.name.clone(),
                        index: i,
                        point: queries[i].0,
                        max_distance: queries[i].1,
                        expected,
                        got: found[i],
                    });
                }
            }
        }
    };
    let mut in_subset = vec![false; queries.len()];
    for (k, &i) in subset.iter().enumerate() {
        in_subset[i] = true;
        record(&mut rows, i, brute_found[k]);
    }
    // Outside the subset, brute force settles every point on which the rows disagree.
    let mut settled = 0;
    for i in (0..queries.len()).filter(|&i| !in_subset[i]) {
        let first = answers.first().map(|a| a[i]);
        if answers
            .iter()
            .any(|a| first.is_some_and(|f| !PointHit::agree(f, a[i])))
        {
            settled += 1;
            let (expected, _) = structures::closest_counted(&*brute, &queries[i..=i]);
            record(&mut rows, i, expected[0]);
        }
    }

    let base = brute_row.mrays_per_s;
    brute_row.speedup = 1.0;
    for r in &mut rows {
        r.speedup = r.mrays_per_s / base;
    }
    let mut all_rows = vec![brute_row];
    all_rows.extend(rows);
    Ok(Report {
        scene,
        triangles: tris.len(),
        valid_triangles: valid,
        ray_kind: KIND,
        view: "",
        rays: queries.len(),
        threads,
        checked_rays: subset.len() + settled,
        rows: all_rows,
        disagreements: Vec::new(),
        point_disagreements: disagreements,
        per_ray_answers: false,
    })
}

/// One row's figures: a counted pass, then `repeats` timed passes (the fastest counts; with
/// none, the counted pass is timed).
fn query_row(
    name: &str,
    s: &dyn DynAccel<Triangle>,
    build_ms: f64,
    queries: &[(Vec3, f32)],
    repeats: u32,
) -> (Row, Vec<Option<PointHit>>) {
    let t = Instant::now();
    let (found, counters) = structures::closest_counted(s, queries);
    let mut best = t.elapsed();
    let mut hits = found.iter().filter(|a| a.is_some()).count();
    if repeats > 0 {
        best = Duration::MAX;
    }
    for _ in 0..repeats {
        let t = Instant::now();
        hits = structures::closest_timed(s, queries);
        best = best.min(t.elapsed());
    }
    let row = Row::measured(name, s, build_ms, queries.len(), hits, counters, best);
    (row, found)
}

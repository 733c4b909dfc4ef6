//! `cargo xtask compare --out DIR`: the shootout as a Markdown report with SVG charts (speed,
//! cost per ray, memory, build time, and the SAH's prediction against the measured cost) and a
//! heatmap strip of primitive tests per scene.

use crate::compare::Args;
use crate::data::{Report, Row};
use crate::structures::{self, Entry};
use plotters::prelude::*;
use rt_render::CostMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Creates `dir` if needed and checks that files can be written there, before any measuring.
///
/// # Errors
/// One line naming the directory.
pub fn prepare(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("{}: cannot create report directory: {e}", dir.display()))?;
    let probe = dir.join(".rt-accel-write-test");
    std::fs::write(&probe, b"")
        .map_err(|e| format!("{}: cannot write the report there: {e}", dir.display()))?;
    std::fs::remove_file(&probe).ok();
    Ok(())
}

/// The cost of every pixel's primary ray on `scene` for each row that can render (built over
/// the scene's shapes), in order, labelled with the row's name: the panels of a heatmap strip.
/// `progress` gets the row's name, the tiles done and the total.
///
/// # Errors
/// One line for an unusable image size.
pub fn cost_panels(
    scene: &rt_render::RenderScene,
    rows: &[Entry],
    (width, height): (u32, u32),
    metric: rt_render::Metric,
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<Vec<(String, CostMap)>, String> {
    let shapes = scene.shapes();
    let mut panels = Vec::new();
    for entry in rows {
        let Some(build) = &entry.build_shapes else {
            continue;
        };
        let tracer = build(&shapes);
        let costs = rt_render::cost_map(scene, tracer.as_ref(), width, height, metric, &|d, t| {
            progress(&entry.name, d, t)
        })
        .map_err(|e| e.to_string())?;
        panels.push((entry.name.clone(), costs));
    }
    Ok(panels)
}

/// A name safe in a file name: letters, digits and `-`; a file scene by its file stem.
fn file_key(scene: &str) -> String {
    let stem = Path::new(scene)
        .file_stem()
        .map_or(scene.to_string(), |s| s.to_string_lossy().into_owned());
    stem.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

/// How charts and headings name a scene: a built-in by its name, a file by its file name.
fn scene_label(scene: &str) -> String {
    Path::new(scene)
        .file_name()
        .map_or(scene.to_string(), |n| n.to_string_lossy().into_owned())
}

/// One figure per structure row, as a chart shows it.
struct Figure {
    file: &'static str,
    title: &'static str,
    value: fn(&Row) -> f64,
}

const FIGURES: [Figure; 5] = [
    Figure {
        file: "mrays.svg",
        title: "million rays per second (higher is better)",
        value: |r| r.mrays_per_s,
    },
    Figure {
        file: "tests.svg",
        title: "primitive tests per ray",
        value: |r| r.avg_prim_tests,
    },
    Figure {
        file: "visits.svg",
        title: "nodes or cells entered per ray",
        value: |r| r.avg_visits,
    },
    Figure {
        file: "memory.svg",
        title: "memory, MiB",
        value: |r| r.memory_bytes as f64 / (1024.0 * 1024.0),
    },
    Figure {
        file: "build.svg",
        title: "build time, ms",
        value: |r| r.build_ms,
    },
];

/// Colours of the scenes' bars and points (Okabe & Ito's colour-blind-safe palette).
const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 114, 178),
    RGBColor(230, 159, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(213, 94, 0),
];

fn chart_error(file: &Path, e: impl std::fmt::Display) -> String {
    format!("{}: cannot draw chart: {e}", file.display())
}

/// Draws a chart's series labels, boxed, at `position`.
fn legend<'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, CT>,
    position: SeriesLabelPosition,
    path: &Path,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .position(position)
        .draw()
        .map_err(|e| chart_error(path, e))
}

/// The structure rows every report shows (brute force is the tables' baseline, not charted).
fn structure_rows(report: &Report) -> Vec<&Row> {
    report
        .rows
        .iter()
        .filter(|r| r.name != "brute-force")
        .collect()
}

/// A horizontal bar chart of one metric: a band per structure, a bar per scene, log scale.
fn bar_chart(path: &Path, metric: &Figure, reports: &[Report]) -> Result<(), String> {
    let names: Vec<String> = structure_rows(&reports[0])
        .iter()
        .map(|r| r.name.clone())
        .collect();
    let values: Vec<Vec<f64>> = reports
        .iter()
        .map(|rep| {
            structure_rows(rep)
                .iter()
                .map(|r| (metric.value)(r))
                .collect()
        })
        .collect();
    let positive = values.iter().flatten().copied().filter(|v| *v > 0.0);
    let lo = positive.clone().fold(f64::INFINITY, f64::min);
    let hi = positive.fold(0.0f64, f64::max);
    // Room on the right, past the longest bar, for the legend.
    let (lo, hi) = if lo.is_finite() && hi > 0.0 {
        (lo / 2.0, hi * 20.0)
    } else {
        (0.1, 10.0)
    };
    let n = names.len();
    let height = 90 + 22 * n as u32 * reports.len().max(1) as u32;
    let root = SVGBackend::new(path, (820, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_error(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(metric.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(150)
        .build_cartesian_2d((lo..hi).log_scale(), -0.5f64..n as f64 - 0.5)
        .map_err(|e| chart_error(path, e))?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(n + 1)
        .y_label_formatter(&|y| {
            let i = y.round();
            if (y - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < n {
                names[n - 1 - i as usize].clone()
            } else {
                String::new()
            }
        })
        .x_label_formatter(&|x| format!("{x}"))
        .draw()
        .map_err(|e| chart_error(path, e))?;
    let k = reports.len().max(1) as f64;
    let band = 0.8 / k;
    for (s, rep) in reports.iter().enumerate() {
        let color = PALETTE[s % PALETTE.len()];
        let bars = values[s].iter().enumerate().map(|(i, &v)| {
            // The first structure at the top.
            let y = (n - 1 - i) as f64 + 0.4 - band * s as f64;
            Rectangle::new([(lo, y - band * 0.9), (v.max(lo), y)], color.filled())
        });
        chart
            .draw_series(bars)
            .map_err(|e| chart_error(path, e))?
            .label(scene_label(&rep.scene))
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled()));
    }
    if reports.len() > 1 {
        legend(&mut chart, SeriesLabelPosition::UpperRight, path)?;
    }
    root.present().map_err(|e| chart_error(path, e))
}

/// Predicted (the SAH, for lines uniform over the scene box) against measured cost per ray, one
/// point per structure and scene, log–log, with the diagonal where the model would be exact.
fn model_chart(
    path: &Path,
    title: &str,
    reports: &[Report],
    pick: fn(&Row) -> Option<(f64, f64)>,
) -> Result<(), String> {
    let points: Vec<Vec<(f64, f64, String)>> = reports
        .iter()
        .map(|rep| {
            structure_rows(rep)
                .iter()
                .filter_map(|r| pick(r).map(|(p, m)| (p, m, r.name.clone())))
                .filter(|(p, m, _)| *p > 0.0 && *m > 0.0)
                .collect()
        })
        .collect();
    let all = points.iter().flatten();
    let lo = all
        .clone()
        .flat_map(|(p, m, _)| [*p, *m])
        .fold(f64::INFINITY, f64::min);
    let hi = all.flat_map(|(p, m, _)| [*p, *m]).fold(0.0f64, f64::max);
    let (lo, hi) = if lo.is_finite() && hi > 0.0 {
        (lo / 1.5, hi * 1.5)
    } else {
        (0.1, 10.0)
    };
    let root = SVGBackend::new(path, (720, 620)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_error(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(14)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((lo..hi).log_scale(), (lo..hi).log_scale())
        .map_err(|e| chart_error(path, e))?;
    chart
        .configure_mesh()
        .x_desc("predicted by the SAH (lines uniform over the scene box)")
        .y_desc("measured on the rays traced")
        .x_label_formatter(&|x| format!("{x}"))
        .y_label_formatter(&|y| format!("{y}"))
        .draw()
        .map_err(|e| chart_error(path, e))?;
    chart
        .draw_series(LineSeries::new([(lo, lo), (hi, hi)], BLACK.mix(0.4)))
        .map_err(|e| chart_error(path, e))?
        .label("measured = predicted")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 14, y)], BLACK.mix(0.4)));
    for (s, (rep, pts)) in reports.iter().zip(&points).enumerate() {
        let color = PALETTE[s % PALETTE.len()];
        chart
            .draw_series(pts.iter().map(|(p, m, name)| {
                EmptyElement::at((*p, *m))
                    + Circle::new((0, 0), 4, color.filled())
                    + Text::new(name.clone(), (6, -4), ("sans-serif", 11))
            }))
            .map_err(|e| chart_error(path, e))?
            .label(scene_label(&rep.scene))
            .legend(move |(x, y)| Circle::new((x + 6, y), 4, color.filled()));
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft, path)?;
    root.present().map_err(|e| chart_error(path, e))
}

/// The heatmap strip of primary-ray primitive tests on `scene` for the rows that ran and can
/// render, among the five default structures and any structure added to the built-in ones (a
/// student's), or `None` if there are none.
fn heatmap(
    dir: &Path,
    scene: &str,
    report: &Report,
    args: &Args,
    entries: &[structures::Entry],
) -> Result<Option<String>, String> {
    let defaults = ["bvh", "kdtree", "grid", "hgrid", "octree"];
    let built_in: Vec<String> = structures::all().into_iter().map(|e| e.name).collect();
    let names: Vec<&str> = report
        .rows
        .iter()
        .map(|r| r.name.as_str())
        .filter(|n| defaults.contains(n) || !built_in.iter().any(|b| b == n))
        .filter(|n| {
            entries
                .iter()
                .any(|e| e.name == *n && e.build_shapes.is_some())
        })
        .collect();
    if names.is_empty() {
        return Ok(None);
    }
    let (w, h) = (
        320,
        (320 * args.height.max(1) / args.width.max(1)).clamp(1, 960),
    );
    let render_scene = rt_render::scene(scene, w, h).map_err(|e| e.to_string())?;
    let rows: Vec<Entry> = names
        .iter()
        .map(|n| structures::find(entries, n))
        .collect::<Result<_, _>>()?;
    let panels = cost_panels(
        &render_scene,
        &rows,
        (w, h),
        rt_render::Metric::Tests,
        &|_, _, _| {},
    )?;
    let file = format!("heatmap-{}.png", file_key(scene));
    rt_render::heatmap_strip(&panels, rt_render::Metric::Tests)
        .save_png(&dir.join(&file))
        .map_err(|e| e.to_string())?;
    Ok(Some(file))
}

fn markdown_table(r: &Report) -> String {
    let mut s = String::from(
        "| structure | build ms | memory MiB | visits/ray | tests/ray | Mrays/s | speedup | visits (SAH) | tests (SAH) | mismatches |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for row in &r.rows {
        let sah = |f: fn(&rt_core::PredictedCost) -> f64| {
            row.predicted
                .as_ref()
                .map_or("–".to_string(), |p| format!("{:.2}", f(p)))
        };
        let _ = writeln!(
            s,
            "| {} | {:.1} | {:.2} | {:.1} | {:.2} | {:.3} | {:.0}× | {} | {} | {} |",
            row.name,
            row.build_ms,
            row.memory_bytes as f64 / (1024.0 * 1024.0),
            row.avg_visits,
            row.avg_prim_tests,
            row.mrays_per_s,
            row.speedup,
            sah(|p| p.visits),
            sah(|p| p.tests),
            row.mismatches
        );
    }
    s
}

/// Writes `DIR/report.md`, the charts and the heatmaps; returns the report's path.
///
/// # Errors
/// One line naming a file that could not be written.
pub fn write(
    dir: &Path,
    reports: &[Report],
    args: &Args,
    entries: &[structures::Entry],
) -> Result<PathBuf, String> {
    let mut md = String::from("# rt-accel shootout\n\n");
    let command: Vec<String> = std::env::args().skip(1).collect();
    let _ = writeln!(
        md,
        "Made by `cargo xtask {}` on {} threads. Every structure traced the same rays; every \
         answer was checked (brute force on a random subset, the structures against each other \
         on all rays). Times are the fastest of {} runs.\n",
        command.join(" "),
        reports.first().map_or(0, |r| r.threads),
        args.repeats.max(1)
    );
    for metric in &FIGURES {
        bar_chart(&dir.join(metric.file), metric, reports)?;
    }
    model_chart(
        &dir.join("model-tests.svg"),
        "primitive tests per ray: SAH prediction and measurement",
        reports,
        |r| r.predicted.map(|p| (p.tests, r.avg_prim_tests)),
    )?;
    model_chart(
        &dir.join("model-visits.svg"),
        "nodes or cells entered per ray: SAH prediction and measurement",
        reports,
        |r| r.predicted.map(|p| (p.visits, r.avg_visits)),
    )?;
    md.push_str("## Charts\n\nBrute force is left out of the charts (it is the tables' baseline); scales are logarithmic.\n\n");
    for metric in &FIGURES {
        let _ = writeln!(md, "![{}]({})\n", metric.title, metric.file);
    }
    md.push_str(
        "## The cost model against the rays\n\n\
         Each structure's expected cost per ray under the surface area heuristic's assumption \
         (lines spread uniformly over the scene box: a region is entered with probability \
         area(region) / area(box)), computed from the structure's own nodes or cells, against \
         what the traced rays did. Points below the diagonal cost less than the model says \
         (rays stop at their first hit, mailboxes skip repeats); points above it cost more \
         (the rays crowd where the model expects few, as a camera looking at the teapot in a \
         stadium does).\n\n\
         ![tests](model-tests.svg)\n\n![visits](model-visits.svg)\n\n",
    );
    for (scene, report) in args.scenes.iter().zip(reports) {
        let _ = writeln!(
            md,
            "## {}\n\n{} triangles ({} valid), {} {} rays, {} checked against brute force.\n",
            scene_label(&report.scene),
            report.triangles,
            report.valid_triangles,
            report.rays,
            report.ray_kind,
            report.checked_rays
        );
        md.push_str(&markdown_table(report));
        if let Some(file) = heatmap(dir, scene, report, args, entries)? {
            let _ = writeln!(
                md,
                "\nPrimitive tests of each pixel's primary ray (one shared colour scale):\n\n![heatmap of {}]({file})",
                scene_label(&report.scene)
            );
        }
        md.push('\n');
    }
    let path = dir.join("report.md");
    std::fs::write(&path, md).map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    Ok(path)
}

/// A log axis's label at `v`: only at 1, 2 and 5 times a power of ten (the axis marks every
/// tick), with `k` and `M` for counts.
fn log_label(v: f64, count: bool) -> String {
    if v.is_nan() || v <= 0.0 {
        return String::new();
    }
    let power = 10f64.powf(v.log10().floor());
    let m = v / power;
    if ![1.0, 2.0, 5.0].iter().any(|n| (m - n).abs() < 0.01) {
        return String::new();
    }
    match v {
        _ if count && v >= 1e6 => format!("{}M", v / 1e6),
        _ if count && v >= 1e3 => format!("{}k", v / 1e3),
        _ if v >= 1.0 => format!("{v:.0}"),
        _ => format!("{v}"),
    }
}

/// `scale`'s four curves against size, log-log, one line per row: build time per triangle,
/// trace time per ray, structure bytes per triangle, and the build's peak heap.
pub(crate) fn scale_chart(path: &Path, report: &crate::scale::ScaleReport) -> Result<(), String> {
    type Metric = fn(&crate::scale::Point) -> Option<f64>;
    let panels: [(&str, Metric); 4] = [
        ("build ns per triangle", |p| Some(p.build_ns_per_triangle())),
        ("trace ns per primary ray", |p| Some(p.trace_ns_per_ray)),
        ("structure bytes per triangle", |p| {
            Some(p.bytes_per_triangle())
        }),
        ("peak build heap, MiB", |p| {
            p.peak_build_bytes.map(|b| b as f64 / (1024.0 * 1024.0))
        }),
    ];
    let mut names: Vec<&str> = Vec::new();
    for p in &report.points {
        if !names.contains(&p.structure.as_str()) {
            names.push(&p.structure);
        }
    }
    let sizes = report.points.iter().map(|p| p.triangles as f64);
    let (x_lo, x_hi) = (
        sizes.clone().fold(f64::INFINITY, f64::min) / 1.3,
        sizes.fold(0.0f64, f64::max) * 1.3,
    );
    let root = SVGBackend::new(path, (1100, 820)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_error(path, e))?;
    let root = root
        .titled(
            &format!(
                "scale ladder on {}, {} threads",
                report.scene, report.threads
            ),
            ("sans-serif", 20),
        )
        .map_err(|e| chart_error(path, e))?;
    for (area, (title, metric)) in root.split_evenly((2, 2)).iter().zip(panels) {
        let values: Vec<f64> = report.points.iter().filter_map(metric).collect();
        let y_lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let y_hi = values.iter().copied().fold(0.0f64, f64::max);
        if values.is_empty() || y_lo.is_nan() || y_lo <= 0.0 || !y_hi.is_finite() {
            continue;
        }
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 15))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(
                (x_lo..x_hi).log_scale(),
                (y_lo / 1.5..y_hi * 1.5).log_scale(),
            )
            .map_err(|e| chart_error(path, e))?;
        chart
            .configure_mesh()
            .x_desc("triangles")
            .x_label_formatter(&|x| log_label(*x, true))
            .y_label_formatter(&|y| log_label(*y, false))
            .draw()
            .map_err(|e| chart_error(path, e))?;
        for (i, name) in names.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let line: Vec<(f64, f64)> = report
                .points
                .iter()
                .filter(|p| p.structure == *name)
                .filter_map(|p| metric(p).map(|v| (p.triangles as f64, v)))
                .collect();
            chart
                .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
                .map_err(|e| chart_error(path, e))?
                .label(*name)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 14, y)], color));
            chart
                .draw_series(line.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(|e| chart_error(path, e))?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperLeft, path)?;
    }
    root.present().map_err(|e| chart_error(path, e))
}

//! Which kernels trace rt-bvh's wide tree fastest on the CPU at hand: every instruction set this
//! CPU runs ([`Isa::all_available`]: portable, SSE2, AVX2, AVX-512), each forced with
//! [`Bvh::set_kernels`], on the same tree and the same rays, in one run. It prints Mrays/s per
//! instruction set, scene and ray kind (primary and shadow rays from the view each scene fills,
//! incoherent rays), each set's speed ÷ the one [`Isa::detect`] picks, and their geometric means:
//! the measurement behind the run-time choice, on every CPU it is run on.
//!
//! ```sh
//! cargo bench -p rt-benches --bench kernels                          # every scene
//! cargo bench -p rt-benches --bench kernels -- --scenes peers --passes 3 --json out.json
//! ```
//!
//! Method: as the peers benchmark's. Every contender traces every ray set `--passes` times (5 by
//! default), the passes of all contenders interleaved, after an untimed warm-up pass each; the
//! median pass counts. One thread. Every instruction set's answers must equal the portable
//! kernels' bit for bit (primitive, `t`, `u`, `v`; the run panics otherwise).

use rt_benches::{BenchScene, geomean, median};
use rt_bvh::{Bvh, BvhParams, Isa, Kernels};
use rt_core::{Accel, Hit, Ray, Triangle};
use rt_scene::raygen::RayKind;
use rt_scene::scenes::View;
use std::fmt::Write as _;
use std::time::Instant;

type Options = rt_benches::RunOptions;

const KINDS: [(&str, RayKind); 3] = [
    ("primary", RayKind::Primary),
    ("incoherent", RayKind::Incoherent),
    ("shadow", RayKind::Shadow),
];

/// The bits of an answer, for the exact comparison.
fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
}

/// One pass: the hits (or blocked rays) counted, so the work cannot be optimized away.
fn pass(bvh: &Bvh<Triangle>, rays: &[Ray], any: bool) -> usize {
    if any {
        rays.iter().filter(|r| bvh.occluded(r)).count()
    } else {
        rays.iter().filter(|r| bvh.intersect(r).is_some()).count()
    }
}

/// Mrays/s of each tree on `rays`, interleaved passes, medians.
fn time(trees: &[Bvh<Triangle>], rays: &[Ray], any: bool, passes: usize) -> Vec<f64> {
    for t in trees {
        std::hint::black_box(pass(t, rays, any));
    }
    let mut ms = vec![Vec::new(); trees.len()];
    for _ in 0..passes {
        for (i, t) in trees.iter().enumerate() {
            let start = Instant::now();
            std::hint::black_box(pass(t, rays, any));
            ms[i].push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    ms.into_iter()
        .map(|m| rays.len() as f64 / median(m) / 1e3)
        .collect()
}

struct Row {
    scene: &'static str,
    kind: &'static str,
    hit_share: f64,
    mrays: Vec<f64>,
}

fn bench_scene(scene: &BenchScene, isas: &[Isa], o: &Options, rows: &mut Vec<Row>) {
    let built = Bvh::build(&scene.triangles, &BvhParams::wide());
    let trees: Vec<Bvh<Triangle>> = isas
        .iter()
        .map(|&isa| {
            let mut t = built.clone();
            assert!(t.set_kernels(Kernels::Simd(isa)));
            t
        })
        .collect();
    for (kind_name, kind) in KINDS {
        let rays = scene.rays(kind, View::Filled, (o.width, o.height), |primary| {
            primary.iter().map(|r| built.intersect(r)).collect()
        });
        let any = kind.is_any_hit();
        // Every instruction set answers with the portable kernels' bits.
        let reference: Vec<_> = if any {
            rays.iter()
                .map(|r| trees[0].occluded(r).then_some((0, 0, 0, 0)))
                .collect()
        } else {
            rays.iter().map(|r| bits(trees[0].intersect(r))).collect()
        };
        for (isa, t) in isas.iter().zip(&trees).skip(1) {
            let differ = rays
                .iter()
                .zip(&reference)
                .filter(|(r, e)| {
                    let a = if any {
                        t.occluded(r).then_some((0, 0, 0, 0))
                    } else {
                        bits(t.intersect(r))
                    };
                    a != **e
                })
                .count();
            assert_eq!(
                differ,
                0,
                "{} differs from the portable kernels on {differ} {kind_name} rays of {}",
                isa.name(),
                scene.name
            );
        }
        let hit_share =
            reference.iter().filter(|h| h.is_some()).count() as f64 / rays.len().max(1) as f64;
        rows.push(Row {
            scene: scene.name,
            kind: kind_name,
            hit_share,
            mrays: time(&trees, &rays, any, o.passes),
        });
    }
}

fn report(isas: &[Isa], rows: &[Row], o: &Options) -> String {
    let detected = Isa::detect_ignoring_env();
    let base = isas.iter().position(|&i| i == detected).unwrap_or(0);
    let names: Vec<&str> = isas.iter().map(|i| i.name()).collect();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n{}: rt-bvh's wide tree, one thread, {}×{} rays per set, medians of {} interleaved \
         passes; the run-time choice here is `{}`\n",
        rt_shootout::measure::cpu_model(),
        o.width,
        o.height,
        o.passes,
        detected.name()
    );
    let _ = writeln!(
        s,
        "| scene | rays | hit | {} | fastest |",
        names
            .iter()
            .map(|n| format!("{n} Mrays/s"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(
        s,
        "| --- | --- | ---: |{}",
        " ---: |".repeat(names.len() + 1)
    );
    for r in rows {
        let best = (0..r.mrays.len())
            .max_by(|&a, &b| r.mrays[a].total_cmp(&r.mrays[b]))
            .unwrap_or(0);
        let _ = writeln!(
            s,
            "| {} | {} | {:.1}% | {} | {} |",
            r.scene,
            r.kind,
            100.0 * r.hit_share,
            r.mrays
                .iter()
                .map(|m| format!("{m:.2}"))
                .collect::<Vec<_>>()
                .join(" | "),
            names[best]
        );
    }
    let _ = writeln!(
        s,
        "\nGeometric means over the scenes, each instruction set's speed ÷ `{}`'s\n",
        detected.name()
    );
    let _ = writeln!(
        s,
        "| instruction set | {} |",
        KINDS.map(|(k, _)| k).join(" | ")
    );
    let _ = writeln!(s, "| --- |{}", " ---: |".repeat(KINDS.len()));
    for (i, n) in names.iter().enumerate() {
        let cells: Vec<String> = KINDS
            .iter()
            .map(|(k, _)| {
                let v: Vec<f64> = rows
                    .iter()
                    .filter(|r| r.kind == *k)
                    .map(|r| r.mrays[i] / r.mrays[base])
                    .collect();
                format!("{:.3}", geomean(&v))
            })
            .collect();
        let _ = writeln!(s, "| {n} | {} |", cells.join(" | "));
    }
    s
}

fn main() {
    let o = Options::from_args();
    let isas = Isa::all_available();
    let mut rows = Vec::new();
    for scene in o.scenes() {
        eprintln!("{}: {} triangles", scene.name, scene.triangles.len());
        bench_scene(&scene, &isas, &o, &mut rows);
    }
    print!("{}", report(&isas, &rows, &o));
    if let Some(path) = &o.json {
        let rows: Vec<serde_json::Value> = rows
            .iter()
            .map(|r| {
                serde_json::json!({
                    "scene": r.scene, "rays": r.kind, "hit_share": r.hit_share,
                    "mrays_per_s": r.mrays,
                })
            })
            .collect();
        let json = serde_json::json!({
            "cpu": rt_shootout::measure::cpu_model(),
            "detected": Isa::detect_ignoring_env().name(),
            "isas": isas.iter().map(|i| i.name()).collect::<Vec<_>>(),
            "width": o.width, "height": o.height, "passes": o.passes, "rows": rows,
        });
        std::fs::write(path, serde_json::to_string_pretty(&json).expect("JSON"))
            .expect("write the JSON file");
        eprintln!("wrote {path}");
    }
}

//! What each step from the binary BVH to the default wide one gains, measured: the same rays
//! traced single-threaded through seven configurations, each adding one step to the one before
//! (on a CPU without AVX2, or not x86-64, a step it cannot run repeats the one before it).
//!
//! ```sh
//! cargo run --release -p rt-bvh --example steps              # 1024×768 rays, 3 passes
//! cargo run --release -p rt-bvh --example steps -- 512 384 5 # width, height, passes
//! ```
//!
//! Scenes: the Stanford bunny and the Utah teapot (from `../shared/meshes`, when present), the
//! sphereflake and the teapot in a stadium. Rays: primary, incoherent and shadow, as
//! `cargo xtask compare` makes them from the view each scene fills (its default `--view
//! filled`). The passes of all configurations are interleaved and the median pass is reported;
//! every configuration must answer exactly like the first.

use rt_bvh::{Ablation, Bvh, BvhParams, Isa, Kernels};
use rt_core::{Accel, Hit, Primitive, Ray, Triangle};
use rt_scene::raygen::{self, RayKind};
use rt_scene::scenes;
use std::time::Instant;

/// The configurations, each with one more step than the one before.
/// The kernels of an instruction set this CPU may lack (then the portable ones).
fn simd(isa: Option<Isa>) -> Kernels {
    Kernels::Simd(isa.unwrap_or(Isa::Portable))
}

fn steps() -> Vec<(&'static str, BvhParams)> {
    let wide = |kernels, sort_children, any_hit_path| BvhParams {
        kernels,
        ablation: Ablation {
            sort_children,
            any_hit_path,
            stream_walk: false,
        },
        ..BvhParams::wide()
    };
    vec![
        ("binary (preset `binary`)", BvhParams::sah()),
        (
            "wide nodes, one 8-lane slab test per node; triangles one at a time",
            wide(Some(Kernels::Scalar), false, false),
        ),
        (
            "+ SoA triangle packs, four per test (plain arrays)",
            wide(Some(Kernels::Simd(Isa::Portable)), false, false),
        ),
        (
            "+ SSE2 intrinsics (x86-64 baseline)",
            wide(Some(simd(Isa::sse2())), false, false),
        ),
        (
            "+ AVX2 intrinsics (runtime dispatch)",
            wide(Some(simd(Isa::avx2())), false, false),
        ),
        (
            "+ nearest-first order of the children",
            wide(None, true, false),
        ),
        ("+ any-hit path (the default)", BvhParams::wide()),
    ]
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn answers<A: Accel>(a: &A, rays: &[Ray], any: bool) -> Vec<Option<Hit>> {
    rays.iter()
        .map(|r| {
            if any {
                a.occluded(r).then_some(Hit {
                    prim: u32::MAX,
                    t: 0.0,
                    u: 0.0,
                    v: 0.0,
                })
            } else {
                a.intersect(r)
            }
        })
        .collect()
}

fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| {
            a.parse().unwrap_or_else(|_| {
                eprintln!("error: `{a}` is not a number (width height passes)");
                std::process::exit(2)
            })
        })
        .collect();
    let (width, height) = (
        args.first().copied().unwrap_or(1024),
        args.get(1).copied().unwrap_or(768),
    );
    let passes = args.get(2).copied().unwrap_or(3).max(1) as usize;

    let mut scenes_: Vec<(String, String, Vec<Triangle>)> = Vec::new();
    if let Some(dir) = rt_conformance::shared_meshes_dir() {
        for (name, file) in [("bunny", "stanford-bunny.obj"), ("teapot", "teapot.obj")] {
            let path = dir.join(file);
            let mesh = rt_scene::load_obj(&path).unwrap_or_else(|e| {
                eprintln!("error: {e}");
                std::process::exit(2)
            });
            scenes_.push((name.into(), path.display().to_string(), mesh.triangles()));
        }
    }
    for name in ["sphereflake", "teapot-in-stadium"] {
        let mesh = scenes::builtin(name).expect("a built-in scene");
        scenes_.push((name.into(), name.into(), mesh.triangles()));
    }

    let configs = steps();
    println!(
        "Mrays/s, single-threaded, {width}×{height} rays, medians of {passes} interleaved passes \
         (in brackets: ÷ the binary tree)\n"
    );
    print!("| step |");
    for (name, _, _) in &scenes_ {
        print!(" {name}: primary / incoherent / shadow |");
    }
    println!();
    println!("| --- |{}", " --- |".repeat(scenes_.len()));
    // results[config][scene][kind]
    let mut results = vec![vec![[0.0f64; 3]; scenes_.len()]; configs.len()];
    for (si, (_, spec, tris)) in scenes_.iter().enumerate() {
        let built: Vec<Bvh<Triangle>> = configs.iter().map(|(_, p)| Bvh::build(tris, p)).collect();
        let bounds = tris
            .iter()
            .filter(|t| t.is_valid())
            .fold(rt_core::Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let camera = scenes::camera_for_view(spec, &bounds, width, height, scenes::View::Filled);
        for (ki, kind) in RayKind::ALL.into_iter().enumerate() {
            let rays =
                raygen::rays_of_kind(kind, tris, &camera, &bounds, (width, height), 1, |p| {
                    answers(&built[0], p, false)
                });
            let any = kind.is_any_hit();
            let expected = answers(&built[0], &rays, any);
            for (ci, b) in built.iter().enumerate() {
                let got = answers(b, &rays, any);
                let same = expected.iter().zip(&got).all(|(e, g)| Hit::agree(*e, *g));
                assert!(same, "step {ci} answers differently on {}", scenes_[si].0);
            }
            let mut times = vec![Vec::new(); built.len()];
            for _ in 0..passes {
                for (ci, b) in built.iter().enumerate() {
                    let t = Instant::now();
                    std::hint::black_box(answers(b, &rays, any).len());
                    times[ci].push(t.elapsed().as_secs_f64());
                }
            }
            for (ci, t) in times.into_iter().enumerate() {
                results[ci][si][ki] = rays.len() as f64 / median(t) / 1e6;
            }
        }
    }
    for (ci, (name, _)) in configs.iter().enumerate() {
        print!("| {name} |");
        for (row, base) in results[ci].iter().zip(&results[0]) {
            let cells: Vec<String> = row
                .iter()
                .zip(base)
                .map(|(v, b)| {
                    if ci == 0 {
                        format!("{v:.2}")
                    } else {
                        format!("{v:.2} ({:.2}×)", v / b)
                    }
                })
                .collect();
            print!(" {} |", cells.join(" / "));
        }
        println!();
    }
}

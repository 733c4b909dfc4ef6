//! How the build constants shape a kd-tree: nodes, duplication, visits and primitive tests per
//! primary ray, single-threaded build time and speed, from Wald & Havran's published constants to
//! the default.
//!
//! ```sh
//! cargo run --release -p rt-kdtree --example cost_sweep -- ../shared/meshes/stanford-bunny.obj
//! ```
//!
//! The rays are `cargo xtask compare`'s default primary rays (1024×768). The counts are
//! deterministic; a build time is the best of three single-threaded builds (`rt_shootout::measure`,
//! which also times three traces, on the calling thread), so compare the times only within one
//! run.

use rt_core::Accel;
use rt_kdtree::{KdParams, KdTree};
use rt_scene::Camera;
use rt_shootout::measure::measure;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "../shared/meshes/stanford-bunny.obj".into());
    let mesh = rt_scene::load_mesh(&path)?;
    let tris = mesh.triangles();
    let rays = Camera::framing(&mesh.bounds(), 1024, 768).primary_rays(1024, 768);
    println!(
        "{path}: {} triangles, {} primary rays",
        tris.len(),
        rays.len()
    );
    let wh = KdParams::wald_havran();
    let rows = [
        ("Wald & Havran (K_T 15)", wh.clone()),
        (
            "  with K_T 5",
            KdParams {
                traversal_cost: 5.0,
                ..wh.clone()
            },
        ),
        (
            "  with 1 bad refine",
            KdParams {
                max_bad_refines: 1,
                ..wh.clone()
            },
        ),
        (
            "K_T 25, 3 bad refines, depth 7+",
            KdParams {
                empty_cut: 0.0,
                ..KdParams::fewest_tests()
            },
        ),
        (
            "  with empty cut 0.25 (fewest-tests)",
            KdParams::fewest_tests(),
        ),
        ("  with leaf size 3 (sah, default)", KdParams::sah()),
    ];
    println!(
        "{:<32} {:>9} {:>5} {:>9} {:>10} {:>9} {:>8} {:>8}",
        "configuration",
        "nodes",
        "depth",
        "refs/prim",
        "visits/ray",
        "tests/ray",
        "build ms",
        "Mrays/s"
    );
    for (name, params) in rows {
        let params = KdParams {
            parallel: false,
            ..params
        };
        let m = measure::<KdTree<_>>(&tris, &params, &rays, 3);
        let s = m.accel.build_stats();
        println!(
            "{name:<32} {:>9} {:>5} {:>9.2} {:>10.1} {:>9.3} {:>8.0} {:>8.2}",
            s.nodes,
            s.max_depth,
            s.duplication(),
            m.per_ray(m.counters.node_visits),
            m.per_ray(m.counters.prim_tests),
            m.build_ms,
            m.mrays_per_s(),
        );
    }
    Ok(())
}

//! How the grid's density λ (cells per primitive) trades cells for primitive tests: cells,
//! references per primitive, memory, build time, and visits, tests and mailbox skips per primary
//! ray, with the speed of each.
//!
//! ```sh
//! cargo run --release -p rt-grid --example density_sweep -- ../shared/meshes/stanford-bunny.obj
//! cargo run --release -p rt-grid --example density_sweep -- random-soup
//! ```
//!
//! The argument is an OBJ file or a built-in scene. The rays are 512×384 primary rays; builds
//! and traces are single-threaded, and a time is the best of three, so compare times only within
//! one run.

use rt_core::Accel;
use rt_grid::{Grid, GridParams};
use rt_scene::Camera;
use rt_shootout::measure::measure;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "../shared/meshes/stanford-bunny.obj".into());
    let mesh = match rt_scene::scenes::builtin(&arg) {
        Some(mesh) => mesh,
        None => rt_scene::load_mesh(&arg)?,
    };
    let tris = mesh.triangles();
    let rays = Camera::framing(&mesh.bounds(), 512, 384).primary_rays(512, 384);
    println!(
        "{arg}: {} triangles, {} primary rays",
        tris.len(),
        rays.len()
    );
    println!(
        "{:>7} {:>9} {:>9} {:>7} {:>8} {:>10} {:>9} {:>10} {:>8}",
        "density",
        "cells",
        "refs/prim",
        "MiB",
        "build ms",
        "visits/ray",
        "tests/ray",
        "skips/ray",
        "Mrays/s"
    );
    for density in [1.0, 2.0, 4.0, 8.0, 16.0, 32.0] {
        let params = GridParams {
            density,
            parallel: false,
            ..GridParams::standard()
        };
        let m = measure::<Grid<_>>(&tris, &params, &rays, 3);
        let s = m.accel.build_stats();
        println!(
            "{density:>7} {:>9} {:>9.2} {:>7.1} {:>8.1} {:>10.1} {:>9.2} {:>10.2} {:>8.2}",
            s.nodes,
            s.duplication(),
            m.accel.memory_bytes() as f64 / (1024.0 * 1024.0),
            m.build_ms,
            m.per_ray(m.counters.node_visits),
            m.per_ray(m.counters.prim_tests),
            m.per_ray(m.counters.mailbox_skips),
            m.mrays_per_s(),
        );
    }
    Ok(())
}

//! How the octree's two knobs, the leaf threshold `max_prims` and the depth limit `max_depth`,
//! trade memory for work per ray: nodes, references per primitive, memory, build time, and
//! visits, tests and mailbox skips per primary ray, with the speed of each. The uniform grid's
//! default is the first row, as the baseline.
//!
//! ```sh
//! cargo run --release -p rt-octree --example threshold_sweep -- ../shared/meshes/stanford-bunny.obj
//! cargo run --release -p rt-octree --example threshold_sweep -- teapot-in-stadium
//! ```
//!
//! The argument is an OBJ file or a built-in scene (seen from its own camera). The rays are
//! 512×384 primary rays; builds and traces are single-threaded, and a time is the best of three,
//! so compare times only within one run.

use rt_core::raygen::Camera;
use rt_core::{Accel, Counters, Ray, Triangle};
use rt_grid::{Grid, GridParams};
use rt_octree::{Octree, OctreeParams};
use std::time::Instant;

/// Builds `A` (best of three), traces `rays` counted and timed, and prints one row.
fn row<A: Accel<Prim = Triangle>>(
    label: &str,
    tris: &[Triangle],
    rays: &[Ray],
    params: &A::Params,
) {
    let mut build_ms = f64::INFINITY;
    let mut built = None;
    for _ in 0..3 {
        let start = Instant::now();
        let a = A::build(tris, params);
        build_ms = build_ms.min(start.elapsed().as_secs_f64() * 1e3);
        built = Some(a);
    }
    let a = built.expect("built at least once");
    let mut c = Counters::default();
    for r in rays {
        a.intersect_with(r, &mut c);
    }
    let mut trace_s = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let hits = rays.iter().filter(|r| a.intersect(r).is_some()).count();
        trace_s = trace_s.min(start.elapsed().as_secs_f64());
        std::hint::black_box(hits);
    }
    let s = a.build_stats();
    let per_ray = |x: u64| x as f64 / rays.len() as f64;
    println!(
        "{label:>12} {:>9} {:>9.2} {:>7.2} {build_ms:>8.1} {:>10.2} {:>9.2} {:>10.2} {:>8.2}",
        s.nodes,
        s.duplication(),
        a.memory_bytes() as f64 / (1024.0 * 1024.0),
        per_ray(c.node_visits),
        per_ray(c.prim_tests),
        per_ray(c.mailbox_skips),
        rays.len() as f64 / trace_s / 1e6,
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "../shared/meshes/stanford-bunny.obj".into());
    let mesh = match rt_core::scenes::builtin(&arg) {
        Some(mesh) => mesh,
        None => rt_core::load_obj(&arg)?,
    };
    let tris = mesh.triangles();
    let camera = match rt_core::scenes::find(&arg) {
        Some(scene) => scene.camera(&mesh.bounds(), 512, 384),
        None => Camera::framing(&mesh.bounds(), 512, 384),
    };
    let rays = camera.primary_rays(512, 384);
    println!(
        "{arg}: {} triangles, {} primary rays",
        tris.len(),
        rays.len()
    );
    println!(
        "{:>12} {:>9} {:>9} {:>7} {:>8} {:>10} {:>9} {:>10} {:>8}",
        "prims/depth",
        "nodes",
        "refs/prim",
        "MiB",
        "build ms",
        "visits/ray",
        "tests/ray",
        "skips/ray",
        "Mrays/s"
    );
    let grid = GridParams {
        parallel: false,
        ..GridParams::standard()
    };
    row::<Grid<Triangle>>("grid", &tris, &rays, &grid);
    for max_depth in [8, 12, 16] {
        for max_prims in [4, 8, 16] {
            let params = OctreeParams {
                max_prims,
                max_depth,
                parallel: false,
                ..OctreeParams::standard()
            };
            row::<Octree<Triangle>>(&format!("{max_prims}/{max_depth}"), &tris, &rays, &params);
        }
    }
    Ok(())
}

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

use rt_core::{Accel, Ray, Triangle};
use rt_grid::{Grid, GridParams};
use rt_octree::{Octree, OctreeParams};
use rt_scene::Camera;
use rt_shootout::measure::measure;

/// Measures `A` (best of three builds and traces) and prints one row.
fn row<A: Accel<Prim = Triangle>>(
    label: &str,
    tris: &[Triangle],
    rays: &[Ray],
    params: &A::Params,
) {
    let m = measure::<A>(tris, params, rays, 3);
    let s = m.accel.build_stats();
    println!(
        "{label:>12} {:>9} {:>9.2} {:>7.2} {:>8.1} {:>10.2} {:>9.2} {:>10.2} {:>8.2}",
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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "../shared/meshes/stanford-bunny.obj".into());
    let mesh = match rt_scene::scenes::builtin(&arg) {
        Some(mesh) => mesh,
        None => rt_scene::load_mesh(&arg)?,
    };
    let tris = mesh.triangles();
    let camera = match rt_scene::scenes::find(&arg) {
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

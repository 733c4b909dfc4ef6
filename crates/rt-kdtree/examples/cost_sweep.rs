//! How the SAH constants shape a kd-tree: nodes, duplication, and visits and primitive tests per
//! primary ray, for a range of traversal costs and bad-refine allowances.
//!
//! ```sh
//! cargo run --release -p rt-kdtree --example cost_sweep -- ../shared/meshes/stanford-bunny.obj
//! ```
//!
//! The counts are deterministic; the build times are one single-threaded run each, so compare
//! them only within one run.

use rt_core::raygen::Camera;
use rt_core::{Accel, Counters};
use rt_kdtree::{KdParams, KdTree};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "../shared/meshes/stanford-bunny.obj".into());
    let mesh = rt_core::load_obj(&path)?;
    let tris = mesh.triangles();
    let rays = Camera::framing(&mesh.bounds(), 512, 384).primary_rays(512, 384);
    println!(
        "{path}: {} triangles, {} primary rays",
        tris.len(),
        rays.len()
    );
    println!("K_T  bad  nodes    depth  refs/prim  visits/ray  tests/ray  build ms");
    for bad in [0, 1] {
        for kt in [30.0, 15.0, 10.0, 7.0, 5.0] {
            let params = KdParams {
                traversal_cost: kt,
                max_bad_refines: bad,
                parallel: false,
                ..KdParams::sah()
            };
            let start = Instant::now();
            let tree = KdTree::build(&tris, &params);
            let ms = start.elapsed().as_secs_f64() * 1e3;
            let mut c = Counters::default();
            for r in &rays {
                tree.intersect_with(r, &mut c);
            }
            let s = tree.build_stats();
            let per_ray = |x: u64| x as f64 / rays.len() as f64;
            println!(
                "{kt:<4} {bad:<4} {:<8} {:<6} {:<10.2} {:<11.1} {:<10.3} {ms:.0}",
                s.nodes,
                s.max_depth,
                s.duplication(),
                per_ray(c.node_visits),
                per_ray(c.prim_tests),
            );
        }
    }
    Ok(())
}

//! How much faster is loading a saved structure than building it? For every structure on the
//! Stanford bunny, and for the BVH on the 10-million-triangle terrain: the build, `save_file`
//! and `load_file` (read the file, check its framing and checksum, validate every invariant),
//! each the median of three runs, on all threads (builds, and loading's reading and checks,
//! use rayon).
//! The file is written to the system's temporary folder and read back warm from the page cache,
//! as a program that saved its structure on an earlier run reads it. Every loaded structure
//! then traces the primary rays of a 128 × 128 camera filling the image with the mesh, and must
//! answer them bit for bit as the built one does (the hit share is printed beside).
//!
//! ```sh
//! cargo bench -p rt-benches --bench saved
//! cargo bench -p rt-benches --bench saved -- --terrain 1M   # a smaller terrain
//! ```

use rt_benches::{BenchScene, flag_values, shared};
use rt_bvh::Bvh;
use rt_core::{Accel, Hit, Ray, Triangle};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_persist::Persist;
use rt_scene::scenes::{View, resolve};
use std::time::Instant;

/// The median of three runs of `f`, in seconds, and the last run's result.
fn median3<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..3 {
        let t = Instant::now();
        last = Some(f());
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    (times[1], last.expect("three runs"))
}

fn bits(h: Option<Hit>) -> Option<[u32; 4]> {
    h.map(|h| [h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()])
}

/// One row: build, save, load and check structure `A` with its default parameters.
fn row<A: Accel<Prim = Triangle> + Persist>(name: &str, scene: &BenchScene, rays: &[Ray]) {
    let tris = &scene.triangles;
    let params = A::presets().remove(0).1;
    let (build_s, built) = median3(|| A::build(tris, &params));
    let path = std::env::temp_dir().join(format!("rt-saved-{}-{name}.bin", std::process::id()));
    let (save_s, ()) = median3(|| built.save_file(&path).expect("the file is written"));
    let bytes = std::fs::metadata(&path).map_or(0, |m| m.len());
    let (load_s, loaded) = median3(|| A::load_file(&path).expect("its own file loads"));
    let _ = std::fs::remove_file(&path);
    let hits = rays.iter().filter(|r| built.intersect(r).is_some()).count();
    let same = rays
        .iter()
        .all(|r| bits(built.intersect(r)) == bits(loaded.intersect(r)));
    println!(
        "| {} | {} | {name} | {build_s:.3} | {save_s:.3} | {load_s:.3} | {:.1}× | {:.1} | {:.1}% | {} |",
        scene.name,
        tris.len(),
        build_s / load_s,
        bytes as f64 / (1024.0 * 1024.0),
        100.0 * hits as f64 / rays.len() as f64,
        if same { "yes" } else { "NO" }
    );
    assert!(
        same,
        "{name} on {}: the loaded structure answers otherwise",
        scene.name
    );
}

fn main() {
    let terrain = flag_values()
        .into_iter()
        .rev()
        .find(|(f, _)| f == "--terrain")
        .map_or("10M".to_string(), |(_, v)| v);
    let spec = format!("terrain:{terrain}");
    let (builtin, size) = resolve(&spec)
        .unwrap_or_else(|e| panic!("{e}"))
        .expect("terrain is built in");
    println!(
        "| scene | triangles | structure | build s | save s | load s | build / load | file MiB | hits | same answers |"
    );
    println!("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |");
    if let Some(bunny) = shared("bunny", "stanford-bunny.obj") {
        let rays = bunny.camera(View::Filled, 128, 128).primary_rays(128, 128);
        row::<Bvh<Triangle>>("bvh", &bunny, &rays);
        row::<KdTree<Triangle>>("kdtree", &bunny, &rays);
        row::<Grid<Triangle>>("grid", &bunny, &rays);
        row::<HGrid<Triangle>>("hgrid", &bunny, &rays);
        row::<Octree<Triangle>>("octree", &bunny, &rays);
    } else {
        eprintln!("the shared meshes are not at ../shared/meshes: the bunny is left out");
    }
    let scene = BenchScene {
        name: "terrain",
        spec: spec.clone(),
        triangles: builtin.make(size).triangles(),
    };
    let rays = scene.camera(View::Filled, 128, 128).primary_rays(128, 128);
    row::<Bvh<Triangle>>("bvh", &scene, &rays);
}

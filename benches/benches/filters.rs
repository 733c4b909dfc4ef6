//! Does a hit filter that accepts everything compile away, and what does a real one cost? For
//! every structure, each primary ray of a filled view traced by `intersect` and by
//! `intersect_filtered` with three filters, the passes interleaved (A B A B ...), the median
//! pass reported with its ratio to the plain query and the geometric mean over the scenes:
//! - `accept-all`: `|_, _| true`, which must cost nothing (ratio within noise of 1);
//! - `mask`: a per-primitive mask read from memory, every bit set (same answers; the cost of a
//!   filter call that does some work);
//! - `alpha`: `compare --query filtered`'s checkerboard alpha mask, which cuts away half of
//!   each triangle (other answers; the rays go on through the holes).
//!
//! Shadow rays of the same view compare `occluded` with `occluded_filtered(|_, _| true)`: a
//! filtered any-hit query reads each hit's coordinates, so it cannot use the cheaper yes-or-no
//! test, and this row shows what that costs.
//!
//! ```sh
//! cargo bench -p rt-benches --bench filters            # 5 passes
//! cargo bench -p rt-benches --bench filters -- --passes 9
//! ```

use rt_benches::{BenchScene, peer_scenes};
use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, PrimHit, Ray, Triangle};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_scene::raygen::RayKind;
use rt_scene::scenes::View;
use rt_shootout::compare::alpha_mask;
use std::hint::black_box;
use std::time::Instant;

const WIDTH: u32 = 512;
const HEIGHT: u32 = 384;

/// The medians of `passes` interleaved passes of each of `runs` (seconds), the first the
/// baseline.
fn interleaved(runs: &[&dyn Fn() -> usize], passes: usize) -> Vec<f64> {
    let mut times = vec![Vec::new(); runs.len()];
    for _ in 0..passes {
        for (run, t) in runs.iter().zip(&mut times) {
            let start = Instant::now();
            black_box(run());
            t.push(start.elapsed().as_secs_f64());
        }
    }
    times
        .into_iter()
        .map(|mut t| {
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        })
        .collect()
}

/// One structure's ratios: closest hit with each filter over the plain query (primary rays),
/// and the filtered any hit over the plain one (shadow rays).
fn measure<A: Accel<Prim = Triangle>>(
    accel: &A,
    tris: usize,
    primary: &[Ray],
    shadow: &[Ray],
    passes: usize,
) -> [f64; 4] {
    let mask = vec![true; tris];
    let plain = || {
        primary
            .iter()
            .filter(|r| accel.intersect(black_box(r)).is_some())
            .count()
    };
    let accept_all = || {
        let f = |_: u32, _: &PrimHit| true;
        primary
            .iter()
            .filter(|r| accel.intersect_filtered(black_box(r), f).is_some())
            .count()
    };
    let masked = || {
        let f = |prim: u32, _: &PrimHit| mask[prim as usize];
        primary
            .iter()
            .filter(|r| accel.intersect_filtered(black_box(r), f).is_some())
            .count()
    };
    let alpha_masked = || {
        primary
            .iter()
            .filter(|r| accel.intersect_filtered(black_box(r), alpha_mask).is_some())
            .count()
    };
    // The filters that accept everything must answer as the plain query does.
    for r in primary {
        let want = accel.intersect(r).map(|h| (h.prim, h.t.to_bits()));
        let got = accel
            .intersect_filtered(r, |_, _| true)
            .map(|h| (h.prim, h.t.to_bits()));
        assert_eq!(want, got, "{}: accept-all answered differently", A::NAME);
    }
    let t = interleaved(&[&plain, &accept_all, &masked, &alpha_masked], passes);
    let occluded = || {
        shadow
            .iter()
            .filter(|r| accel.occluded(black_box(r)))
            .count()
    };
    let occluded_all = || {
        let f = |_: u32, _: &PrimHit| true;
        shadow
            .iter()
            .filter(|r| accel.occluded_filtered(black_box(r), f))
            .count()
    };
    assert_eq!(
        occluded(),
        occluded_all(),
        "{}: filtered any hit differs",
        A::NAME
    );
    let s = interleaved(&[&occluded, &occluded_all], passes);
    [t[1] / t[0], t[2] / t[0], t[3] / t[0], s[1] / s[0]]
}

fn rows(scene: &BenchScene, passes: usize) -> Vec<(&'static str, [f64; 4])> {
    let tris: &[Triangle] = &scene.triangles;
    let finder = Bvh::build(tris, &BvhParams::wide());
    let closest = |rays: &[Ray]| rays.iter().map(|r| finder.intersect(r)).collect();
    let primary = scene.rays(RayKind::Primary, View::Filled, (WIDTH, HEIGHT), closest);
    let shadow = scene.rays(RayKind::Shadow, View::Filled, (WIDTH, HEIGHT), closest);
    let hit = primary
        .iter()
        .filter(|r| finder.intersect(r).is_some())
        .count();
    let blocked = shadow.iter().filter(|r| finder.occluded(r)).count();
    eprintln!(
        "{}: {:.1}% of primary rays hit, {:.1}% of shadow rays are blocked",
        scene.name,
        100.0 * hit as f64 / primary.len() as f64,
        100.0 * blocked as f64 / shadow.len().max(1) as f64
    );
    let (n, p, s) = (tris.len(), &primary[..], &shadow[..]);
    vec![
        ("bvh", measure(&finder, n, p, s, passes)),
        (
            "kdtree",
            measure(&KdTree::build(tris, &Default::default()), n, p, s, passes),
        ),
        (
            "grid",
            measure(&Grid::build(tris, &Default::default()), n, p, s, passes),
        ),
        (
            "hgrid",
            measure(&HGrid::build(tris, &Default::default()), n, p, s, passes),
        ),
        (
            "octree",
            measure(&Octree::build(tris, &Default::default()), n, p, s, passes),
        ),
    ]
}

fn main() {
    let passes = rt_benches::passes_flag(5);
    println!(
        "Filtered queries against plain ones: primary and shadow rays of the filled view, \
         {WIDTH}×{HEIGHT}, one thread, median of {passes} interleaved passes; time ÷ the plain \
         query's\n"
    );
    println!("| scene | structure | accept-all | mask | alpha | any hit, accept-all |");
    println!("| --- | --- | ---: | ---: | ---: | ---: |");
    let mut all: Vec<(&'static str, Vec<[f64; 4]>)> = Vec::new();
    for scene in peer_scenes() {
        for (name, r) in rows(&scene, passes) {
            println!(
                "| {} | {name} | {:.3} | {:.3} | {:.3} | {:.3} |",
                scene.name, r[0], r[1], r[2], r[3]
            );
            match all.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => v.push(r),
                None => all.push((name, vec![r])),
            }
        }
    }
    println!("\n| structure | accept-all | mask | alpha | any hit, accept-all |");
    println!("| --- | ---: | ---: | ---: | ---: |");
    for (name, v) in all {
        let mean = |k: usize| (v.iter().map(|r| r[k].ln()).sum::<f64>() / v.len() as f64).exp();
        println!(
            "| {name} (geometric mean) | {:.3} | {:.3} | {:.3} | {:.3} |",
            mean(0),
            mean(1),
            mean(2),
            mean(3)
        );
    }
}

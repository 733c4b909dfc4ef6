//! Cost of one ray–triangle test: watertight (the default) against Möller–Trumbore, measured as
//! brute force over the same triangles and rays. Run with
//! `cargo bench -p rt-benches --bench primitives`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rt_core::{Accel, BruteForce, MtTriangle, Ray, Rng, Triangle, glam::Vec3};
use std::hint::black_box;

fn benches(c: &mut Criterion) {
    let tris = rt_scene::scenes::random_soup(1000, 3).triangles();
    let mut rng = Rng::new(5);
    let rays: Vec<Ray> = (0..1000)
        .map(|_| Ray::new(rng.in_box(Vec3::ZERO, Vec3::ONE), rng.unit_vector()))
        .collect();
    let wt = BruteForce::<Triangle>::build(&tris, &());
    let mt_tris: Vec<MtTriangle> = tris.iter().copied().map(MtTriangle).collect();
    let mt = BruteForce::<MtTriangle>::build(&mt_tris, &());
    let mut g = c.benchmark_group("triangle-test");
    g.throughput(Throughput::Elements((tris.len() * rays.len()) as u64));
    g.bench_function("watertight", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| black_box(&wt).intersect(r).is_some())
                .count()
        })
    });
    g.bench_function("moller-trumbore", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| black_box(&mt).intersect(r).is_some())
                .count()
        })
    });
    g.finish();
}

criterion_group!(primitives, benches);
criterion_main!(primitives);

//! Does the statistics sink compile away? Traces the same primary rays three ways:
//! - `no-stats`: `Bvh::intersect`, the generic traversal with the no-op sink;
//! - `counters`: the same traversal counting visits and tests;
//! - `no-sink-control`: a traversal written here without any sink at all, over the same nodes.
//!
//! `no-stats` should match `no-sink-control` (within noise) and `counters` cost a little more.
//! The wide tree's group (`stats-sink-wide`) compares `no-stats` with `counters` only.
//! Run with `cargo bench -p rt-benches --bench stats`.

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group, criterion_main};
use rt_benches::scenes;
use rt_bvh::{Bvh, BvhParams, MAX_DEPTH};
use rt_core::{Accel, Counters, Hit, Primitive, Ray, SLAB_FAR_SCALE, Triangle};
use std::hint::black_box;

/// The control: rt-bvh's traversal algorithm with no statistics calls at all. It mirrors
/// `rt_bvh::traverse` (closest hit only) so that the only difference is the sink.
fn control(bvh: &Bvh<Triangle>, ray: &Ray) -> Option<Hit> {
    let nodes = bvh.nodes();
    let (prims, ids) = (bvh.primitives(), bvh.primitive_ids());
    let mut best = Hit {
        prim: u32::MAX,
        t: ray.t_max,
        u: 0.0,
        v: 0.0,
    };
    if ids.is_empty() || nodes[0].bounds.intersect(ray, best.t).is_none() {
        return None;
    }
    let mut stack = [(0u32, 0.0f32); MAX_DEPTH];
    let (mut sp, mut current) = (0, 0usize);
    loop {
        let node = &nodes[current];
        if node.is_leaf() {
            for i in node.prim_range() {
                if let Some(h) = prims[i].intersect(ray, best.t)
                    && Hit::beats(h.t, ids[i], best.t, best.prim)
                {
                    best = Hit {
                        prim: ids[i],
                        t: h.t,
                        u: h.u,
                        v: h.v,
                    };
                }
            }
        } else {
            let (a, b) = (current + 1, node.index as usize);
            let ta = nodes[a].bounds.entry(ray, best.t);
            let tb = nodes[b].bounds.entry(ray, best.t);
            let (near, t_near, far, t_far) = if ta <= tb {
                (a, ta, b, tb)
            } else {
                (b, tb, a, ta)
            };
            if t_near != f32::INFINITY {
                if t_far != f32::INFINITY {
                    stack[sp] = (far as u32, t_far);
                    sp += 1;
                }
                current = near;
                continue;
            }
        }
        loop {
            if sp == 0 {
                return (best.prim != u32::MAX).then_some(best);
            }
            sp -= 1;
            let (index, t_entry) = stack[sp];
            if t_entry <= best.t * SLAB_FAR_SCALE {
                current = index as usize;
                break;
            }
        }
    }
}

/// The `no-stats` and `counters` rows of one tree: the same traversal with the no-op sink and
/// with counters.
fn sink_pair(g: &mut BenchmarkGroup<'_, WallTime>, tree: &Bvh<Triangle>, rays: &[Ray]) {
    g.bench_function("no-stats", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| black_box(tree).intersect(r).is_some())
                .count()
        })
    });
    g.bench_function("counters", |b| {
        b.iter(|| {
            let mut c = Counters::default();
            let hits = rays
                .iter()
                .filter(|r| black_box(tree).intersect_with(r, &mut c).is_some())
                .count();
            (hits, c)
        })
    });
}

fn benches(c: &mut Criterion) {
    for scene in scenes() {
        let rays = scene.primary_rays(512, 384);
        let bvh = Bvh::build(&scene.triangles, &BvhParams::sah());
        // The control must answer exactly like the structure, or the comparison means nothing.
        for r in &rays {
            assert_eq!(control(&bvh, r), bvh.intersect(r));
        }
        let mut g = c.benchmark_group(format!("stats-sink/{}", scene.name));
        g.sample_size(20);
        g.throughput(Throughput::Elements(rays.len() as u64));
        sink_pair(&mut g, &bvh, &rays);
        g.bench_function("no-sink-control", |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|r| control(black_box(&bvh), r).is_some())
                    .count()
            })
        });
        g.finish();

        // The wide traversal: counting must cost something, not counting nothing (its pack loop
        // calls the sink once per triangle a pack holds, a loop that must vanish with NoStats).
        let wide = Bvh::build(&scene.triangles, &BvhParams::wide());
        let mut g = c.benchmark_group(format!("stats-sink-wide/{}", scene.name));
        g.sample_size(20);
        g.throughput(Throughput::Elements(rays.len() as u64));
        sink_pair(&mut g, &wide, &rays);
        g.finish();
    }
}

criterion_group!(stats, benches);
criterion_main!(stats);

//! Build and primary-ray trace times of rt-bvh, rt-kdtree, rt-grid, rt-hgrid and rt-octree against the
//! `obvhs` and `bvh` crates, on the same triangles and the same rays; traces single-threaded.
//! Run with `cargo bench -p rt-benches --bench trace`. (Embree: `--bench peers`.)

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rt_benches::{BenchScene, scenes};
use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, MtTriangle, Ray, Triangle};
use rt_grid::{Grid, GridParams};
use rt_hgrid::{HGrid, HGridParams};
use rt_kdtree::{KdParams, KdTree};
use rt_octree::{Octree, OctreeParams};
use std::hint::black_box;
use std::time::Duration;

const WIDTH: u32 = 512;
const HEIGHT: u32 = 384;

/// The triangles as obvhs's. obvhs resolves its own glam version (any from 0.33 up), so the
/// vertices cross as arrays rather than as one shared `Vec3A` type.
fn to_obvhs(tris: &[Triangle]) -> Vec<obvhs::triangle::Triangle> {
    tris.iter()
        .map(|t| obvhs::triangle::Triangle {
            v0: t.v0.to_array().into(),
            v1: t.v1.to_array().into(),
            v2: t.v2.to_array().into(),
        })
        .collect()
}

fn obvhs_build(
    tris: &[obvhs::triangle::Triangle],
    params: obvhs::BvhBuildParams,
) -> obvhs::bvh2::Bvh2 {
    obvhs::bvh2::builder::build_bvh2_from_tris(tris, params, &mut Duration::default())
}

/// A triangle for the `bvh` crate, which needs its shapes to remember their node.
struct PeerTri {
    a: nalgebra::Point3<f32>,
    b: nalgebra::Point3<f32>,
    c: nalgebra::Point3<f32>,
    node: usize,
}

impl bvh::aabb::Bounded<f32, 3> for PeerTri {
    fn aabb(&self) -> bvh::aabb::Aabb<f32, 3> {
        bvh::aabb::Aabb::empty()
            .grow(&self.a)
            .grow(&self.b)
            .grow(&self.c)
    }
}

impl bvh::bounding_hierarchy::BHShape<f32, 3> for PeerTri {
    fn set_bh_node_index(&mut self, i: usize) {
        self.node = i;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

fn to_peer(tris: &[Triangle]) -> Vec<PeerTri> {
    let p = |v: rt_core::glam::Vec3| nalgebra::Point3::new(v.x, v.y, v.z);
    tris.iter()
        .map(|t| PeerTri {
            a: p(t.v0),
            b: p(t.v1),
            c: p(t.v2),
            node: 0,
        })
        .collect()
}

fn bench_build(c: &mut Criterion, scene: &BenchScene) {
    let mut g = c.benchmark_group(format!("build/{}", scene.name));
    g.sample_size(10);
    g.throughput(Throughput::Elements(scene.triangles.len() as u64));
    for (preset, params) in Bvh::<Triangle>::presets() {
        g.bench_function(BenchmarkId::new("rt-bvh", preset), |b| {
            b.iter(|| Bvh::build(black_box(&scene.triangles), &params));
        });
        let sequential = BvhParams {
            parallel: false,
            ..params
        };
        g.bench_function(
            BenchmarkId::new("rt-bvh", format!("{preset}-1-thread")),
            |b| {
                b.iter(|| Bvh::build(black_box(&scene.triangles), &sequential));
            },
        );
    }
    // rt-bvh's presets above build on rayon's threads (the default); the structures below are
    // timed single-threaded unless a row says parallel.
    for (preset, params) in [
        ("sah", KdParams::sah()),
        ("fewest-tests", KdParams::fewest_tests()),
        ("wald-havran", KdParams::wald_havran()),
        ("noclip", KdParams::noclip()),
        ("pbrt", KdParams::pbrt()),
    ] {
        let params = KdParams {
            parallel: false,
            ..params
        };
        g.bench_function(BenchmarkId::new("rt-kdtree", preset), |b| {
            b.iter(|| KdTree::build(black_box(&scene.triangles), &params));
        });
    }
    g.bench_function(BenchmarkId::new("rt-kdtree", "sah-parallel"), |b| {
        b.iter(|| KdTree::build(black_box(&scene.triangles), &KdParams::sah()));
    });
    let grid = GridParams {
        parallel: false,
        ..GridParams::standard()
    };
    g.bench_function(BenchmarkId::new("rt-grid", "standard"), |b| {
        b.iter(|| Grid::build(black_box(&scene.triangles), &grid));
    });
    let hgrid = HGridParams {
        parallel: false,
        ..HGridParams::standard()
    };
    g.bench_function(BenchmarkId::new("rt-hgrid", "standard"), |b| {
        b.iter(|| HGrid::build(black_box(&scene.triangles), &hgrid));
    });
    for parallel in [false, true] {
        let octree = OctreeParams {
            parallel,
            ..OctreeParams::standard()
        };
        let label = if parallel {
            "standard-parallel"
        } else {
            "standard"
        };
        g.bench_function(BenchmarkId::new("rt-octree", label), |b| {
            b.iter(|| Octree::build(black_box(&scene.triangles), &octree));
        });
    }
    let otris = to_obvhs(&scene.triangles);
    g.bench_function(BenchmarkId::new("obvhs", "medium"), |b| {
        b.iter(|| obvhs_build(black_box(&otris), obvhs::BvhBuildParams::medium_build()));
    });
    g.bench_function(BenchmarkId::new("bvh-crate", "sah"), |b| {
        b.iter_batched(
            || to_peer(&scene.triangles),
            |mut shapes| bvh::bvh::Bvh::build(&mut shapes),
            criterion::BatchSize::LargeInput,
        );
    });
    g.finish();
}

fn count_hits<A: Accel>(accel: &A, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| accel.intersect(r).is_some()).count()
}

fn bench_trace(c: &mut Criterion, scene: &BenchScene) {
    let rays = scene.primary_rays(WIDTH, HEIGHT);
    let mut g = c.benchmark_group(format!("trace-primary/{}", scene.name));
    g.sample_size(10);
    g.throughput(Throughput::Elements(rays.len() as u64));

    // rt-bvh's default (the wide tree) is the reference the other structures must agree with.
    let bvh = Bvh::build(&scene.triangles, &BvhParams::wide());
    let expected = count_hits(&bvh, &rays);
    g.bench_function("rt-bvh/wide", |b| {
        b.iter(|| count_hits(black_box(&bvh), &rays))
    });
    let binary = Bvh::build(&scene.triangles, &BvhParams::sah());
    assert_eq!(count_hits(&binary, &rays), expected, "rt-bvh/binary");
    g.bench_function("rt-bvh/binary", |b| {
        b.iter(|| count_hits(black_box(&binary), &rays))
    });
    for (label, params) in [
        ("rt-kdtree/stack", KdParams::sah()),
        ("rt-kdtree/fewest-tests", KdParams::fewest_tests()),
        ("rt-kdtree/wald-havran", KdParams::wald_havran()),
        ("rt-kdtree/restart", KdParams::restart()),
    ] {
        let kd = KdTree::build(&scene.triangles, &params);
        assert_eq!(count_hits(&kd, &rays), expected, "{label}");
        g.bench_function(label, |b| b.iter(|| count_hits(black_box(&kd), &rays)));
    }
    let grid = Grid::build(&scene.triangles, &GridParams::standard());
    assert_eq!(count_hits(&grid, &rays), expected, "rt-grid");
    g.bench_function("rt-grid", |b| {
        b.iter(|| count_hits(black_box(&grid), &rays))
    });
    let hgrid = HGrid::build(&scene.triangles, &HGridParams::standard());
    assert_eq!(count_hits(&hgrid, &rays), expected, "rt-hgrid");
    g.bench_function("rt-hgrid", |b| {
        b.iter(|| count_hits(black_box(&hgrid), &rays))
    });
    let octree = Octree::build(&scene.triangles, &OctreeParams::standard());
    assert_eq!(count_hits(&octree, &rays), expected, "rt-octree");
    g.bench_function("rt-octree", |b| {
        b.iter(|| count_hits(black_box(&octree), &rays))
    });
    let mt: Vec<MtTriangle> = scene.triangles.iter().copied().map(MtTriangle).collect();
    for (label, params) in [
        ("rt-bvh/wide-mt", BvhParams::wide()),
        ("rt-bvh/binary-mt", BvhParams::sah()),
    ] {
        let bvh_mt = Bvh::build(&mt, &params);
        g.bench_function(label, |b| b.iter(|| count_hits(black_box(&bvh_mt), &rays)));
    }

    // obvhs: its own Möller–Trumbore test, triangles reordered to leaf order as its examples
    // recommend (no index indirection in the hot loop).
    let otris = to_obvhs(&scene.triangles);
    let orays: Vec<obvhs::ray::Ray> = rays
        .iter()
        .map(|r| obvhs::ray::Ray::new_inf(r.origin.to_array().into(), r.dir().to_array().into()))
        .collect();
    for (label, params) in [
        ("medium", obvhs::BvhBuildParams::medium_build()),
        ("slow", obvhs::BvhBuildParams::slow_build()),
    ] {
        let obvh = obvhs_build(&otris, params);
        let ordered: Vec<obvhs::triangle::Triangle> = obvh
            .primitive_indices
            .iter()
            .map(|&i| otris[i as usize])
            .collect();
        let trace = |rays: &[obvhs::ray::Ray]| {
            rays.iter()
                .filter(|r| {
                    let mut hit = obvhs::ray::RayHit::none();
                    obvh.ray_traverse(**r, &mut hit, |ray, id| ordered[id].intersect(ray))
                })
                .count()
        };
        let got = trace(&orays);
        // Different triangle tests may disagree on a handful of edge rays, never on more.
        assert!(
            got.abs_diff(expected) <= rays.len() / 1000,
            "obvhs hits {got}, rt-bvh {expected}"
        );
        g.bench_function(format!("obvhs/{label}"), |b| {
            b.iter(|| trace(black_box(&orays)))
        });
    }

    // The `bvh` crate: its iterator yields every leaf shape whose box the ray enters (no
    // front-to-back pruning), tested with its Möller–Trumbore.
    let mut shapes = to_peer(&scene.triangles);
    let peer = bvh::bvh::Bvh::build(&mut shapes);
    let prays: Vec<bvh::ray::Ray<f32, 3>> = rays
        .iter()
        .map(|r| {
            bvh::ray::Ray::new(
                nalgebra::Point3::new(r.origin.x, r.origin.y, r.origin.z),
                nalgebra::Vector3::new(r.dir().x, r.dir().y, r.dir().z),
            )
        })
        .collect();
    let peer_trace = |rays: &[bvh::ray::Ray<f32, 3>]| {
        rays.iter()
            .filter(|r| {
                peer.traverse_iterator(*r, &shapes)
                    .map(|s| r.intersects_triangle(&s.a, &s.b, &s.c).distance)
                    .fold(f32::INFINITY, f32::min)
                    .is_finite()
            })
            .count()
    };
    g.bench_function("bvh-crate", |b| b.iter(|| peer_trace(black_box(&prays))));
    g.finish();
}

fn benches(c: &mut Criterion) {
    for scene in scenes() {
        bench_build(c, &scene);
        bench_trace(c, &scene);
    }
}

criterion_group!(trace, benches);
criterion_main!(trace);

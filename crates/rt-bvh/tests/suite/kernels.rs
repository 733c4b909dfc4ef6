//! Each SIMD kernel against the scalar one on the same tree: every answer (primitive, and `t`,
//! `u`, `v` to the bit), every occlusion answer and every counted event must be the same, over
//! millions of rays chosen where kernels go wrong: `±0` direction components, rays through
//! shared edges and vertices, rays lying in the faces of node boxes, and random rays.
//!
//! The SSE2 kernels are compared on x86-64, the AVX2 ones when this CPU runs them (the test says
//! so on stderr when it cannot, and fails under `CI=true` if the CPU is x86-64 with AVX2 and
//! they were not run).

use rt_bvh::{Bvh, BvhParams, Kernels};
use rt_core::glam::Vec3;
use rt_core::{Accel, Counters, Hit, MtTriangle, Primitive, Ray, Rng, Triangle};
use rt_scene::scenes;

/// Rays aimed at the features of `tris` and along the planes of the tree's boxes.
fn rays_for(tris: &[Triangle], boxes: &[rt_core::Aabb], n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let bounds = tris
        .iter()
        .fold(rt_core::Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let (lo, hi) = (
        bounds.min - bounds.extent() * 0.25,
        bounds.max + bounds.extent() * 0.25,
    );
    let zero = |rng: &mut Rng| if rng.f32() < 0.5 { 0.0 } else { -0.0 };
    let mut rays = Vec::with_capacity(n);
    while rays.len() < n {
        let t = tris[rng.below(tris.len() as u32) as usize];
        let kind = rng.below(6);
        let target = match kind {
            // A vertex, shared by its neighbours.
            0 => [t.v0, t.v1, t.v2][rng.below(3) as usize],
            // A point on an edge, exactly representable at the midpoint.
            1 => {
                let (a, b) = [(t.v0, t.v1), (t.v1, t.v2), (t.v2, t.v0)][rng.below(3) as usize];
                if rng.f32() < 0.5 {
                    0.5 * (a + b)
                } else {
                    a + rng.f32() * (b - a)
                }
            }
            // Inside the triangle.
            _ => {
                let (u, v) = (rng.f32(), rng.f32());
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                t.v0 + u * (t.v1 - t.v0) + v * (t.v2 - t.v0)
            }
        };
        let origin = rng.in_box(lo, hi);
        let mut dir = target - origin;
        match rng.below(4) {
            // One or two direction components ±0: the ray runs parallel to box faces.
            0 => {
                let a = rng.below(3) as usize;
                dir[a] = zero(&mut rng);
            }
            1 => {
                let a = rng.below(3) as usize;
                dir[a] = zero(&mut rng);
                dir[(a + 1) % 3] = zero(&mut rng);
            }
            // In the face plane of a node box, with that component ±0.
            2 if !boxes.is_empty() => {
                let b = boxes[rng.below(boxes.len() as u32) as usize];
                let a = rng.below(3) as usize;
                let mut o = rng.in_box(b.min, b.max);
                o[a] = if rng.f32() < 0.5 { b.min[a] } else { b.max[a] };
                let mut d = rng.unit_vector();
                d[a] = zero(&mut rng);
                if d != Vec3::ZERO && d.is_finite() {
                    rays.push(Ray::new(o - d * 3.0 * bounds.extent().length(), d));
                }
                continue;
            }
            _ => {}
        }
        let ray = Ray::new(origin, dir);
        if ray.is_valid() {
            rays.push(ray);
        }
    }
    rays
}

/// The boxes of the tree's children: faces for rays to lie in.
fn child_boxes<P: Primitive>(bvh: &Bvh<P>) -> Vec<rt_core::Aabb> {
    bvh.wide_nodes()
        .iter()
        .flat_map(|n| (0..rt_bvh::WIDTH).map(move |i| n.child_bounds(i)))
        .filter(|b| !b.is_empty())
        .collect()
}

fn same(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.prim == b.prim
                && a.t.to_bits() == b.t.to_bits()
                && a.u.to_bits() == b.u.to_bits()
                && a.v.to_bits() == b.v.to_bits()
        }
        _ => false,
    }
}

/// Compares `kernels` with the scalar kernels on one tree over `rays`; returns the number of
/// hits (so the caller can check the rays exercised the kernels).
fn compare<P: Primitive>(tree: &Bvh<P>, kernels: Kernels, rays: &[Ray]) -> usize {
    let mut simd = tree.clone();
    assert!(simd.set_kernels(kernels), "{kernels:?} unavailable");
    let mut scalar = tree.clone();
    assert!(scalar.set_kernels(Kernels::Scalar));
    let mut hits = 0;
    for ray in rays {
        let (mut cs, mut cr) = (Counters::default(), Counters::default());
        let (s, r) = (
            simd.intersect_with(ray, &mut cs),
            scalar.intersect_with(ray, &mut cr),
        );
        assert!(
            same(s, r),
            "{kernels:?} closest hit {s:?}, scalar {r:?}\n  ray: {}",
            ray.to_rust()
        );
        assert_eq!(
            cs,
            cr,
            "{kernels:?} counted events\n  ray: {}",
            ray.to_rust()
        );
        // A bundle of one ray writes its answer in place through its own entry to each kernel.
        let mut one = [None];
        simd.intersect_bundle(std::slice::from_ref(ray), &mut one);
        assert!(
            same(one[0], r),
            "{kernels:?} bundle of one {:?}, scalar {r:?}\n  ray: {}",
            one[0],
            ray.to_rust()
        );
        let (s, r) = (simd.occluded(ray), scalar.occluded(ray));
        assert_eq!(s, r, "{kernels:?} any hit\n  ray: {}", ray.to_rust());
        hits += usize::from(s);
    }
    hits
}

/// The SIMD kernels this machine runs: every instruction set it has.
fn simd_kernels() -> Vec<Kernels> {
    let isas = rt_simd::Isa::all_available();
    let k: Vec<Kernels> = isas.iter().map(|&i| Kernels::Simd(i)).collect();
    if rt_simd::Isa::avx2().is_none() {
        #[cfg(target_arch = "x86_64")]
        {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true");
            assert!(
                !(ci && std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")),
                "the CPU has AVX2 and FMA but the AVX2 kernels are unavailable"
            );
        }
        eprintln!("note: this CPU lacks AVX2 or FMA; only the portable kernels are compared");
    }
    k
}

/// Triangles with shared edges and vertices and axis-aligned ones: the sphereflake (shared edges
/// everywhere, a ground quad in an axis plane), lattice triangles (axis planes, shared lattice
/// vertices) and a soup.
fn scenes_for_kernels() -> Vec<(&'static str, Vec<Triangle>)> {
    vec![
        ("sphereflake", scenes::sphereflake(2, 5, 8).triangles()),
        ("lattice", rt_conformance::lattice_triangles(3, 400)),
        ("soup", scenes::random_soup(3_000, 11).triangles()),
    ]
}

#[test]
fn simd_kernels_answer_bit_for_bit_like_the_scalar_ones() {
    // 3 scenes × 2 tests × 3 kernel sets (on AVX2 machines) × 200k rays: 3.6 million rays,
    // each traced four times (closest and any hit, SIMD and scalar).
    const RAYS: usize = 200_000;
    let kernels = simd_kernels();
    for (name, tris) in scenes_for_kernels() {
        let wt = Bvh::build(&tris, &BvhParams::wide());
        let rays = rays_for(&tris, &child_boxes(&wt), RAYS, 7);
        let mt_tris: Vec<MtTriangle> = tris.iter().copied().map(MtTriangle).collect();
        let mt = Bvh::build(&mt_tris, &BvhParams::wide());
        for &k in &kernels {
            let hits = compare(&wt, k, &rays);
            assert!(hits > RAYS / 4, "{name}: only {hits} of {RAYS} rays hit");
            compare(&mt, k, &rays);
        }
    }
}

#[test]
fn rays_through_a_quad_diagonal_and_its_corners() {
    // A grid of quads split along their diagonals, hit exactly on the diagonals, edges and
    // corners from many directions: the watertight kernel must find a hit for every ray (the
    // rays cross the grid's interior) and agree with the scalar test bit for bit.
    let mut tris = Vec::new();
    for i in 0..16 {
        for j in 0..16 {
            let p = |a: i32, b: i32| Vec3::new((i + a) as f32, (j + b) as f32, 0.0);
            tris.push(Triangle::new(p(0, 0), p(1, 0), p(1, 1)));
            tris.push(Triangle::new(p(0, 0), p(1, 1), p(0, 1)));
        }
    }
    let bvh = Bvh::build(&tris, &BvhParams::wide());
    let mut rng = Rng::new(3);
    let mut rays = Vec::new();
    for _ in 0..100_000 {
        let (i, j) = (1 + rng.below(14), 1 + rng.below(14));
        let s = rng.below(9) as f32 / 8.0;
        let target = match rng.below(3) {
            0 => Vec3::new(i as f32 + s, j as f32 + s, 0.0),
            1 => Vec3::new(i as f32 + s, j as f32, 0.0),
            _ => Vec3::new(i as f32, j as f32, 0.0),
        };
        let o = Vec3::new(
            rng.range(-4.0, 20.0),
            rng.range(-4.0, 20.0),
            rng.range(0.5, 9.0),
        );
        rays.push(Ray::new(o, target - o));
    }
    for k in simd_kernels() {
        let hits = compare(&bvh, k, &rays);
        assert_eq!(
            hits,
            rays.len(),
            "{k:?}: a ray slipped between two triangles"
        );
    }
}

//! The SIMD layer against its reference: every lane operation of every instruction set this
//! CPU runs gives [`Portable`]'s bits, the one watertight kernel gives the scalar test's bits at
//! every width, and `RT_ACCEL_PORTABLE=1` forces the portable kernels.

use rt_core::glam::Vec3;
use rt_core::{Hit, NoStats, Primitive, Ray, Rng, Shear, Triangle};
use rt_simd::bundle::{Group, for_each_bundle};
use rt_simd::{Isa, Lanes, Portable, Simd, watertight};

/// Values where lane operations differ if they are not exactly the reference's: signed zeros,
/// infinities, NaN, subnormals, and ordinary numbers.
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // only x86-64 has other sets
fn awkward(rng: &mut Rng) -> f32 {
    const SPECIAL: [f32; 9] = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1.0e-40,
        -3.0e38,
    ];
    if rng.below(3) == 0 {
        SPECIAL[rng.below(SPECIAL.len() as u32) as usize]
    } else {
        (rng.f32() - 0.5) * 10.0
    }
}

/// [`Portable`] seen as `N` lanes only, so that its methods name one width.
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // only x86-64 has other sets
fn portable<const N: usize>() -> impl Simd<N, V = [f32; N], M = u32> {
    Portable
}

/// Every operation of `s` on `N` lanes against [`Portable`]'s, bit for bit (masks as bits).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // only x86-64 has other sets
fn ops_match_portable<const N: usize, S: Simd<N>>(s: S, what: &str) {
    let p = portable::<N>();
    let mut rng = Rng::new(3);
    for case in 0..2000 {
        let v: [[f32; N]; 6] = std::array::from_fn(|_| std::array::from_fn(|_| awkward(&mut rng)));
        let bits = |a: [f32; N]| a.map(f32::to_bits);
        let (a, b, c) = (v[0], v[1], v[2]);
        let sv = |x: [f32; N]| s.load(&x);
        let pv = |x: [f32; N]| p.load(&x);
        let same = |op: &str, got: S::V, want: [f32; N]| {
            assert_eq!(
                bits(s.store(got)),
                bits(want),
                "{what} {op}, case {case}: {v:?}"
            );
        };
        same("load/store", sv(a), a);
        same("splat", s.splat(a[0]), [a[0]; N]);
        same("add", s.add(sv(a), sv(b)), p.add(pv(a), pv(b)));
        same("sub", s.sub(sv(a), sv(b)), p.sub(pv(a), pv(b)));
        same("mul", s.mul(sv(a), sv(b)), p.mul(pv(a), pv(b)));
        same("div", s.div(sv(a), sv(b)), p.div(pv(a), pv(b)));
        same("min", s.min(sv(a), sv(b)), p.min(pv(a), pv(b)));
        same("max", s.max(sv(a), sv(b)), p.max(pv(a), pv(b)));
        let masks: [(&str, u32, u32); 6] = [
            ("eq", s.bits(s.eq(sv(a), sv(b))), p.bits(p.eq(pv(a), pv(b)))),
            (
                "ne_ordered",
                s.bits(s.ne_ordered(sv(a), sv(b))),
                p.bits(p.ne_ordered(pv(a), pv(b))),
            ),
            ("lt", s.bits(s.lt(sv(a), sv(b))), p.bits(p.lt(pv(a), pv(b)))),
            ("gt", s.bits(s.gt(sv(a), sv(b))), p.bits(p.gt(pv(a), pv(b)))),
            ("le", s.bits(s.le(sv(a), sv(b))), p.bits(p.le(pv(a), pv(b)))),
            ("ge", s.bits(s.ge(sv(a), sv(b))), p.bits(p.ge(pv(a), pv(b)))),
        ];
        for (op, got, want) in masks {
            assert_eq!(got, want, "{what} {op}, case {case}: {v:?}");
        }
        let (ma, mb) = (s.lt(sv(a), sv(b)), s.gt(sv(b), sv(c)));
        let (qa, qb) = (p.lt(pv(a), pv(b)), p.gt(pv(b), pv(c)));
        assert_eq!(
            s.bits(s.and(ma, mb)),
            p.bits(p.and(qa, qb)),
            "{what} and, case {case}"
        );
        assert_eq!(
            s.bits(s.or(ma, mb)),
            p.bits(p.or(qa, qb)),
            "{what} or, case {case}"
        );
        assert_eq!(
            s.bits(s.andnot(ma, mb)),
            p.bits(p.andnot(qa, qb)),
            "{what} andnot, case {case}"
        );
        same(
            "select",
            s.select(ma, sv(b), sv(c)),
            p.select(qa, pv(b), pv(c)),
        );
        same(
            "select_sign",
            s.select_sign(sv(a), sv(b), sv(c)),
            p.select_sign(pv(a), pv(b), pv(c)),
        );
        let [x, y, z] = s.edges_f64(sv(v[0]), sv(v[1]), sv(v[2]), sv(v[3]), sv(v[4]), sv(v[5]));
        let [px, py, pz] = p.edges_f64(v[0], v[1], v[2], v[3], v[4], v[5]);
        same("edges_f64 0", x, px);
        same("edges_f64 1", y, py);
        same("edges_f64 2", z, pz);
    }
}

#[test]
fn every_instruction_set_computes_the_portable_bits() {
    let isas = Isa::all_available();
    assert!(isas.len() > 1 || !cfg!(target_arch = "x86_64"), "{isas:?}");
    for isa in isas {
        match isa {
            Isa::Portable => {}
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2(s) => {
                ops_match_portable::<4, _>(s, "sse2");
                ops_match_portable::<8, _>(s, "sse2");
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(s) => {
                ops_match_portable::<4, _>(s, "avx2");
                ops_match_portable::<8, _>(s, "avx2");
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(s) => ops_match_portable::<16, _>(s, "avx512"),
        }
    }
}

/// A triangle that the ray from the origin along +z misses, but whose edge function against
/// `b` and `c` rounds to exactly zero in `f32`: exactly, `cx·by − cy·bx = 2⁻²⁴`, while
/// `(1 + 2⁻¹²)²` rounds (to even) onto `1 + 2⁻¹¹`. The other two edge functions are negative,
/// so only the recomputation in `f64` finds the miss; a kernel without it reports a hit.
fn rounded_to_an_edge() -> Triangle {
    let (e11, e12) = (1.0 + 2f32.powi(-11), 1.0 + 2f32.powi(-12));
    Triangle::new(
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(e12, 1.0, 1.0),
        Vec3::new(-e11, -e12, 1.0),
    )
}

#[test]
fn the_rounded_edge_case_needs_the_f64_recomputation() {
    let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    assert_eq!(rounded_to_an_edge().intersect(&ray, ray.t_max), None);
    let (e11, e12) = (1.0 + 2f32.powi(-11), 1.0 + 2f32.powi(-12));
    assert_eq!(
        -e11 * 1.0 - -e12 * e12,
        0.0,
        "the edge function rounds to zero in f32"
    );
}

/// Triangles and rays where the watertight test is hard: a lattice of shared edges and
/// vertices hit exactly (edge functions of exactly zero, decided in `f64`), copies, huge and
/// degenerate triangles, and random ones.
fn cases() -> (Vec<Triangle>, Vec<Ray>) {
    let mut rng = Rng::new(7);
    let mut tris = vec![
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
        Triangle::new(Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y),
        Triangle::new(Vec3::ZERO, Vec3::Z, Vec3::Y),
        Triangle::new(
            Vec3::splat(3e38),
            Vec3::new(-3e38, 3e38, 0.0),
            Vec3::new(0.0, -3e38, 3e38),
        ),
        Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE),
        rounded_to_an_edge(),
    ];
    for _ in 0..40 {
        let c = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
        tris.push(Triangle::new(
            c + rng.unit_vector(),
            c + rng.unit_vector(),
            c + rng.unit_vector(),
        ));
    }
    // The ray that `rounded_to_an_edge` misses by 2⁻²⁴ of an edge function.
    let mut rays = vec![Ray::new(Vec3::ZERO, Vec3::Z)];
    let origin = Vec3::new(0.25, 0.5, -3.0);
    for k in 0..=8 {
        for l in 0..=8 {
            let to = Vec3::new(k as f32 * 0.125, l as f32 * 0.125, 0.0);
            rays.push(Ray::new(origin, to - origin));
            rays.push(Ray::new(to - Vec3::Z, Vec3::Z));
        }
    }
    for _ in 0..400 {
        let o = rng.in_box(Vec3::splat(-4.0), Vec3::splat(4.0));
        let t = tris[rng.below(tris.len() as u32) as usize];
        let aim = t.v0 + (t.v1 - t.v0) * rng.f32() * 0.5 + (t.v2 - t.v0) * rng.f32() * 0.5;
        rays.push(Ray::with_interval(
            o,
            aim - o,
            rng.f32() * 0.5,
            0.5 + rng.f32() * 2.0,
        ));
    }
    (tris, rays)
}

/// [`watertight`] with `N` different triangles in the lanes and one ray (as a BVH's packs run
/// it), against [`Triangle::intersect_sheared`] lane by lane, bit for bit.
fn watertight_matches_scalar<const N: usize, S: Simd<N>>(s: S, what: &str) {
    let (tris, rays) = cases();
    for ray in &rays {
        let shear = Shear::new(ray.dir());
        let k = [shear.kx, shear.ky, shear.kz];
        let o = ray.origin.to_array();
        for group in tris.chunks(N) {
            // Unused lanes hold NaN, which never hits.
            let lane = |i: usize, v: usize, a: usize| {
                group
                    .get(i)
                    .map_or(f32::NAN, |t| [t.v0, t.v1, t.v2][v][k[a]])
            };
            let vert =
                |v: usize| [0, 1, 2].map(|a| s.load(&std::array::from_fn(|i| lane(i, v, a))));
            let hits = watertight(
                s,
                [vert(0), vert(1), vert(2)],
                k.map(|a| s.splat(o[a])),
                [shear.sx, shear.sy, shear.sz].map(|x| s.splat(x)),
                s.splat(ray.t_min),
                s.splat(ray.t_max),
                if N == 32 { u32::MAX } else { (1 << N) - 1 },
            );
            let (t, u, v) = (s.store(hits.t), s.store(hits.u), s.store(hits.v));
            for (i, tri) in group.iter().enumerate() {
                let want = tri.intersect_sheared(&shear, ray, ray.t_max);
                let got = (hits.mask >> i & 1 != 0).then(|| (t[i], u[i], v[i]));
                let bits = |h: Option<(f32, f32, f32)>| {
                    h.map(|(t, u, v)| (t.to_bits(), u.to_bits(), v.to_bits()))
                };
                assert_eq!(
                    bits(got),
                    bits(want.map(|h| (h.t, h.u, h.v))),
                    "{what}, {N} lanes: triangle {tri:?}, ray {ray:?}"
                );
            }
        }
    }
}

#[test]
fn the_watertight_kernel_answers_as_the_scalar_test_at_every_width() {
    watertight_matches_scalar::<4, _>(Portable, "portable");
    watertight_matches_scalar::<8, _>(Portable, "portable");
    watertight_matches_scalar::<16, _>(Portable, "portable");
    for isa in Isa::all_available() {
        match isa {
            Isa::Portable => {}
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2(s) => {
                watertight_matches_scalar::<4, _>(s, "sse2");
                watertight_matches_scalar::<8, _>(s, "sse2");
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(s) => {
                watertight_matches_scalar::<4, _>(s, "avx2");
                watertight_matches_scalar::<8, _>(s, "avx2");
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(s) => watertight_matches_scalar::<16, _>(s, "avx512"),
        }
    }
}

/// Every lane of every bundle, on every instruction set, gets the scalar test's answer bit
/// for bit: closest hits over all triangles (ties to the smaller index), and any hits.
#[test]
fn lanes_answer_as_the_scalar_test_on_every_instruction_set() {
    let (tris, rays) = cases();
    let isas = Isa::all_available();
    assert!(isas.len() > 1 || !cfg!(target_arch = "x86_64"), "{isas:?}");
    for isa in isas {
        for_each_bundle(&rays, |group| {
            let Group::Bundle(b) = group else { return };
            let mut lanes = Lanes::with_isa(b, isa);
            let mut any = Lanes::with_isa(b, isa);
            let mut blocked = 0u64;
            for (id, tri) in tris.iter().enumerate() {
                lanes.intersect(tri, id as u32, b.all_lanes(), &mut NoStats);
                blocked |= any.occluded(tri, id as u32, b.all_lanes() & !blocked, &mut NoStats);
            }
            for i in 0..b.len() {
                let ray = b.ray(i);
                let mut best = Hit {
                    prim: u32::MAX,
                    t: ray.t_max,
                    u: 0.0,
                    v: 0.0,
                };
                for (id, tri) in tris.iter().enumerate() {
                    if let Some(h) = tri.intersect(&ray, best.t)
                        && Hit::beats(h.t, id as u32, best.t, best.prim)
                    {
                        best = Hit {
                            prim: id as u32,
                            t: h.t,
                            u: h.u,
                            v: h.v,
                        };
                    }
                }
                let want = (best.prim != u32::MAX).then_some(best);
                let got = lanes.hit(i);
                let bits = |h: Option<Hit>| {
                    h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
                };
                assert_eq!(bits(got), bits(want), "{isa:?}, lane {i}, ray {ray:?}");
                let occluded = tris.iter().any(|t| t.intersect(&ray, ray.t_max).is_some());
                assert_eq!(
                    blocked >> i & 1 != 0,
                    occluded,
                    "{isa:?}, lane {i}, ray {ray:?}"
                );
                // The answer a walk reads for the lane, too: `Some` exactly when blocked.
                assert_eq!(
                    any.hit(i).is_some(),
                    occluded,
                    "{isa:?}, lane {i}, ray {ray:?}"
                );
            }
        });
    }
}

/// The test binary started again with `RT_SIMD_CHILD` set reports what [`Isa::detect`] finds;
/// run alone, this test starts it with and without `RT_ACCEL_PORTABLE=1`.
#[test]
fn rt_accel_portable_forces_the_portable_kernels() {
    if std::env::var_os("RT_SIMD_CHILD").is_some() {
        println!("detected={}", Isa::detect().name());
        return;
    }
    let run = |portable: bool| {
        let mut cmd = std::process::Command::new(std::env::current_exe().unwrap());
        cmd.args([
            "--exact",
            "rt_accel_portable_forces_the_portable_kernels",
            "--nocapture",
        ])
        .env("RT_SIMD_CHILD", "1");
        if portable {
            cmd.env("RT_ACCEL_PORTABLE", "1");
        } else {
            cmd.env_remove("RT_ACCEL_PORTABLE");
        }
        let out = cmd.output().expect("the test binary starts again");
        assert!(out.status.success(), "{out:?}");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let forced = run(true);
    assert!(forced.contains("detected=portable"), "{forced}");
    let best = run(false);
    let want = format!("detected={}", Isa::detect_ignoring_env().name());
    assert!(best.contains(&want), "{best}");
}

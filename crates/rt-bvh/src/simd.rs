//! Runtime CPU dispatch for the wide layout and its AVX2 kernels: the only module of the crate
//! allowed `unsafe`.
//!
//! - [`Avx2`] implements the kernels' [`Simd`] operations with AVX2 intrinsics, and [`Sse2`]
//!   with SSE2 ones, the fallback on x86-64 CPUs without AVX2 (every x86-64 CPU runs SSE2). An intrinsic
//!   needs the CPU feature it is compiled for, so each call sits in an `unsafe` block; they are
//!   sound because an `Avx2` value can only be made by [`Avx2::detect`], after the CPU reported
//!   AVX2 and FMA. The wide traversal (`traverse::wide`) is compiled once inside [`wide_avx2`]
//!   (a `#[target_feature(enable = "avx2,fma")]` function, where the intrinsics inline) and once
//!   for the baseline target with [`Portable`]; the bundle traversal (`bundle::wide_bundle`)
//!   likewise, inside [`bundle_avx2`]. A plain `cargo build` without `RUSTFLAGS`
//!   therefore runs AVX2 code on CPUs that have it and baseline code elsewhere (SSE2 on x86-64;
//!   aarch64 compiles the portable kernels only).
#![allow(unsafe_code)]

use crate::bundle::wide_bundle;
use crate::kernels::Portable;
#[cfg(target_arch = "x86_64")]
use crate::kernels::Simd;
use crate::node::WideNode;
use crate::traverse::{Leaves, wide};
use rt_core::bundle::{Bundle, Lanes};
use rt_core::{ClosestHit, Hit, Ray, RayQuery, Stats};

/// The instruction set the wide traversal runs with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Isa {
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
    #[cfg(target_arch = "x86_64")]
    Sse2,
    Portable,
}

impl Isa {
    /// SSE2, on x86-64 (where every CPU has it), else `None`.
    pub fn sse2() -> Option<Isa> {
        #[cfg(target_arch = "x86_64")]
        return Some(Isa::Sse2);
        #[cfg(not(target_arch = "x86_64"))]
        None
    }

    /// AVX2 with FMA when this CPU has both, else `None`.
    pub fn avx2() -> Option<Isa> {
        #[cfg(target_arch = "x86_64")]
        if let Some(a) = Avx2::detect() {
            return Some(Isa::Avx2(a));
        }
        None
    }
}

/// Runs the wide traversal with the instruction set `isa`.
#[inline(always)]
pub(crate) fn dispatch<L: Leaves, S: Stats, Q: RayQuery>(
    isa: Isa,
    nodes: &[WideNode],
    leaves: &L,
    ray: &Ray,
    sort: bool,
    q: &mut Q,
    stats: &mut S,
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an `Avx2` value exists only if `Avx2::detect` found AVX2 and FMA on this CPU,
        // which is all `wide_avx2` requires.
        Isa::Avx2(simd) => unsafe { wide_avx2(simd, nodes, leaves, ray, sort, q, stats) },
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => wide(Sse2, nodes, leaves, ray, sort, q, stats),
        Isa::Portable => wide(Portable, nodes, leaves, ray, sort, q, stats),
    }
}

/// The wide traversal, compiled with AVX2 and FMA enabled so the intrinsics inline.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn wide_avx2<L: Leaves, S: Stats, Q: RayQuery>(
    simd: Avx2,
    nodes: &[WideNode],
    leaves: &L,
    ray: &Ray,
    sort: bool,
    q: &mut Q,
    stats: &mut S,
) {
    wide(simd, nodes, leaves, ray, sort, q, stats);
}

/// [`dispatch`] for a closest hit written into `out`, the caller's slot: the path of a bundle of
/// one ray.
///
/// A returned answer comes back through a hidden pointer, field by field in 4-byte stores. A
/// caller that copies it on into a slice reads it back at once with wider loads, which the CPU
/// cannot forward from those stores, so the copy waits for the stores to retire. Written in
/// place, there is no copy to wait for. The single-ray query keeps its return value: routed
/// through an answer slot of its own, it is the one that copies (2.5% slower on the bunny).
// PERF: a bundle of one ray over a single-ray call, wide tree, geometric mean of four scenes
// (`cargo bench -p rt-benches --bench bundle_of_one`): 1.043 with the copy, 1.007 in place.
#[inline(always)]
pub(crate) fn dispatch_into<L: Leaves, S: Stats>(
    isa: Isa,
    nodes: &[WideNode],
    leaves: &L,
    ray: &Ray,
    sort: bool,
    stats: &mut S,
    out: &mut Option<Hit>,
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as in `dispatch`: `Avx2` proves the CPU has AVX2 and FMA.
        Isa::Avx2(simd) => unsafe {
            wide_avx2_into::<L, S>(simd, nodes, leaves, ray, sort, stats, out)
        },
        _ => {
            let mut q = ClosestHit::new(ray);
            dispatch(isa, nodes, leaves, ray, sort, &mut q, stats);
            *out = q.hit();
        }
    }
}

/// [`wide_avx2`] for a closest hit written into `out`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn wide_avx2_into<L: Leaves, S: Stats>(
    simd: Avx2,
    nodes: &[WideNode],
    leaves: &L,
    ray: &Ray,
    sort: bool,
    stats: &mut S,
    out: &mut Option<Hit>,
) {
    let mut q = ClosestHit::new(ray);
    wide(simd, nodes, leaves, ray, sort, &mut q, stats);
    *out = q.hit();
}

/// Runs the bundle traversal with the instruction set `isa`.
#[inline(always)]
pub(crate) fn dispatch_bundle<L: Leaves, S: Stats, const ANY: bool>(
    isa: Isa,
    nodes: &[WideNode],
    leaves: &L,
    b: &Bundle,
    lanes: &mut Lanes,
    stats: &mut S,
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an `Avx2` value exists only if `Avx2::detect` found AVX2 and FMA on this CPU,
        // which is all `bundle_avx2` requires.
        Isa::Avx2(simd) => unsafe {
            bundle_avx2::<L, S, ANY>(simd, nodes, leaves, b, lanes, stats)
        },
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => wide_bundle::<Sse2, L, S, ANY>(Sse2, nodes, leaves, b, lanes, stats),
        Isa::Portable => {
            wide_bundle::<Portable, L, S, ANY>(Portable, nodes, leaves, b, lanes, stats)
        }
    }
}

/// The bundle traversal, compiled with AVX2 and FMA enabled so the intrinsics inline.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn bundle_avx2<L: Leaves, S: Stats, const ANY: bool>(
    simd: Avx2,
    nodes: &[WideNode],
    leaves: &L,
    b: &Bundle,
    lanes: &mut Lanes,
    stats: &mut S,
) {
    wide_bundle::<Avx2, L, S, ANY>(simd, nodes, leaves, b, lanes, stats);
}

#[cfg(target_arch = "x86_64")]
pub(crate) use sse2::Sse2;
#[cfg(target_arch = "x86_64")]
pub(crate) use x86::Avx2;

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::Simd;
    use std::arch::x86_64::*;

    /// Proof that this CPU runs AVX2 and FMA; the kernels' operations as AVX2 intrinsics.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub(crate) struct Avx2(());

    impl Avx2 {
        /// `Some` when the CPU has AVX2 and FMA; the only way to make an `Avx2`.
        pub fn detect() -> Option<Self> {
            (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"))
                .then_some(Self(()))
        }
    }

    /// An operation of [`Simd`] as one intrinsic call.
    macro_rules! op {
        ($name:ident($($arg:ident: $ty:ty),*) -> $ret:ty, $body:expr) => {
            #[inline(always)]
            fn $name(self, $($arg: $ty),*) -> $ret {
                // SAFETY: `self` is an `Avx2`, which exists only after `Avx2::detect` found AVX2
                // and FMA on this CPU: every intrinsic used here needs at most AVX2. Loads and
                // stores go through references to arrays of the vector's exact size.
                unsafe { $body }
            }
        };
    }

    impl Simd for Avx2 {
        type F8 = __m256;
        type F4 = __m128;
        type M4 = __m128;

        op!(load8(v: &[f32; 8]) -> __m256, _mm256_loadu_ps(v.as_ptr()));
        op!(splat8(x: f32) -> __m256, _mm256_set1_ps(x));
        op!(sub8(a: __m256, b: __m256) -> __m256, _mm256_sub_ps(a, b));
        op!(mul8(a: __m256, b: __m256) -> __m256, _mm256_mul_ps(a, b));
        // `maxps a, b` is `a > b ? a : b`, NaN in `a` giving `b`: exactly the slab test's `if`.
        op!(max8(a: __m256, b: __m256) -> __m256, _mm256_max_ps(a, b));
        op!(min8(a: __m256, b: __m256) -> __m256, _mm256_min_ps(a, b));
        op!(le_bits8(a: __m256, b: __m256) -> u32,
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(a, b)) as u32);
        // `blendvps` takes its second operand where the mask's sign bit is set.
        op!(select_sign8(sign: __m256, neg: __m256, pos: __m256) -> __m256,
            _mm256_blendv_ps(pos, neg, sign));
        op!(store8(a: __m256) -> [f32; 8], {
            let mut out = [0.0f32; 8];
            _mm256_storeu_ps(out.as_mut_ptr(), a);
            out
        });
        op!(load4(v: &[f32; 4]) -> __m128, _mm_loadu_ps(v.as_ptr()));
        op!(splat4(x: f32) -> __m128, _mm_set1_ps(x));
        op!(add4(a: __m128, b: __m128) -> __m128, _mm_add_ps(a, b));
        op!(sub4(a: __m128, b: __m128) -> __m128, _mm_sub_ps(a, b));
        op!(mul4(a: __m128, b: __m128) -> __m128, _mm_mul_ps(a, b));
        op!(div4(a: __m128, b: __m128) -> __m128, _mm_div_ps(a, b));
        op!(eq4(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_EQ_OQ>(a, b));
        op!(ne_ordered4(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_NEQ_OQ>(a, b));
        op!(lt4(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_LT_OQ>(a, b));
        op!(gt4(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_GT_OQ>(a, b));
        op!(le4(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_LE_OQ>(a, b));
        op!(ge4(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_GE_OQ>(a, b));
        op!(and4(a: __m128, b: __m128) -> __m128, _mm_and_ps(a, b));
        op!(or4(a: __m128, b: __m128) -> __m128, _mm_or_ps(a, b));
        op!(andnot4(a: __m128, b: __m128) -> __m128, _mm_andnot_ps(a, b));
        op!(bits4(m: __m128) -> u32, _mm_movemask_ps(m) as u32);
        op!(store4(a: __m128) -> [f32; 4], {
            let mut out = [0.0f32; 4];
            _mm_storeu_ps(out.as_mut_ptr(), a);
            out
        });
        op!(select4(m: __m128, a: __m128, b: __m128) -> __m128, _mm_blendv_ps(b, a, m));
        op!(edges_f64(ax: __m128, ay: __m128, bx: __m128, by: __m128, cx: __m128, cy: __m128)
            -> [__m128; 3], {
            let d = |v: __m128| _mm256_cvtps_pd(v);
            let (ax, ay, bx, by, cx, cy) = (d(ax), d(ay), d(bx), d(by), d(cx), d(cy));
            let e = |a, b, c, d| _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_mul_pd(a, b), _mm256_mul_pd(c, d)));
            [e(cx, by, cy, bx), e(ax, cy, ay, cx), e(bx, ay, by, ax)]
        });
    }
}

#[cfg(target_arch = "x86_64")]
mod sse2 {
    use super::Simd;
    use std::arch::x86_64::*;

    /// The kernels' operations as SSE2 intrinsics, which every x86-64 CPU runs: the fallback
    /// when AVX2 is missing, with no detection. Eight lanes are two four-lane halves.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub(crate) struct Sse2;

    /// An expression of SSE/SSE2 intrinsics.
    macro_rules! sse {
        ($body:expr) => {
            // SAFETY: SSE and SSE2 belong to the x86-64 baseline, so every CPU this module is
            // compiled for runs them; loads and stores go through references to arrays of the
            // vector's exact size.
            unsafe { $body }
        };
    }

    /// Four f32 lanes widened to f64, in two halves.
    #[inline(always)]
    fn widen(v: __m128) -> [__m128d; 2] {
        sse!([_mm_cvtps_pd(v), _mm_cvtps_pd(_mm_movehl_ps(v, v))])
    }

    impl Simd for Sse2 {
        type F8 = [__m128; 2];
        type F4 = __m128;
        type M4 = __m128;

        #[inline(always)]
        fn load8(self, v: &[f32; 8]) -> [__m128; 2] {
            sse!([_mm_loadu_ps(v.as_ptr()), _mm_loadu_ps(v[4..].as_ptr())])
        }
        #[inline(always)]
        fn splat8(self, x: f32) -> [__m128; 2] {
            sse!([_mm_set1_ps(x); 2])
        }
        #[inline(always)]
        fn sub8(self, a: [__m128; 2], b: [__m128; 2]) -> [__m128; 2] {
            sse!([_mm_sub_ps(a[0], b[0]), _mm_sub_ps(a[1], b[1])])
        }
        #[inline(always)]
        fn mul8(self, a: [__m128; 2], b: [__m128; 2]) -> [__m128; 2] {
            sse!([_mm_mul_ps(a[0], b[0]), _mm_mul_ps(a[1], b[1])])
        }
        #[inline(always)]
        fn max8(self, a: [__m128; 2], b: [__m128; 2]) -> [__m128; 2] {
            // `maxps a, b` is `a > b ? a : b`, NaN in `a` giving `b`, as the slab test's `if`.
            sse!([_mm_max_ps(a[0], b[0]), _mm_max_ps(a[1], b[1])])
        }
        #[inline(always)]
        fn min8(self, a: [__m128; 2], b: [__m128; 2]) -> [__m128; 2] {
            sse!([_mm_min_ps(a[0], b[0]), _mm_min_ps(a[1], b[1])])
        }
        #[inline(always)]
        fn le_bits8(self, a: [__m128; 2], b: [__m128; 2]) -> u32 {
            let lo = sse!(_mm_movemask_ps(_mm_cmple_ps(a[0], b[0]))) as u32;
            let hi = sse!(_mm_movemask_ps(_mm_cmple_ps(a[1], b[1]))) as u32;
            lo | hi << 4
        }
        #[inline(always)]
        fn select_sign8(
            self,
            sign: [__m128; 2],
            neg: [__m128; 2],
            pos: [__m128; 2],
        ) -> [__m128; 2] {
            // SSE2 has no blend: the sign bit spread over the lane by an arithmetic shift
            // masks `neg` in and `pos` out.
            let pick = |s: __m128, n: __m128, p: __m128| {
                sse!({
                    let m = _mm_castsi128_ps(_mm_srai_epi32::<31>(_mm_castps_si128(s)));
                    _mm_or_ps(_mm_and_ps(m, n), _mm_andnot_ps(m, p))
                })
            };
            [pick(sign[0], neg[0], pos[0]), pick(sign[1], neg[1], pos[1])]
        }
        #[inline(always)]
        fn store8(self, a: [__m128; 2]) -> [f32; 8] {
            let mut out = [0.0f32; 8];
            sse!({
                _mm_storeu_ps(out.as_mut_ptr(), a[0]);
                _mm_storeu_ps(out[4..].as_mut_ptr(), a[1]);
            });
            out
        }
        #[inline(always)]
        fn load4(self, v: &[f32; 4]) -> __m128 {
            sse!(_mm_loadu_ps(v.as_ptr()))
        }
        #[inline(always)]
        fn splat4(self, x: f32) -> __m128 {
            sse!(_mm_set1_ps(x))
        }
        #[inline(always)]
        fn add4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_add_ps(a, b))
        }
        #[inline(always)]
        fn sub4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_sub_ps(a, b))
        }
        #[inline(always)]
        fn mul4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_mul_ps(a, b))
        }
        #[inline(always)]
        fn div4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_div_ps(a, b))
        }
        #[inline(always)]
        fn eq4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_cmpeq_ps(a, b))
        }
        #[inline(always)]
        fn ne_ordered4(self, a: __m128, b: __m128) -> __m128 {
            // `cmpneqps` is true for NaN; and-ing with `cmpordps` leaves the ordered lanes.
            sse!(_mm_and_ps(_mm_cmpneq_ps(a, b), _mm_cmpord_ps(a, b)))
        }
        #[inline(always)]
        fn lt4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_cmplt_ps(a, b))
        }
        #[inline(always)]
        fn gt4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_cmpgt_ps(a, b))
        }
        #[inline(always)]
        fn le4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_cmple_ps(a, b))
        }
        #[inline(always)]
        fn ge4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_cmpge_ps(a, b))
        }
        #[inline(always)]
        fn and4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_and_ps(a, b))
        }
        #[inline(always)]
        fn or4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_or_ps(a, b))
        }
        #[inline(always)]
        fn andnot4(self, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_andnot_ps(a, b))
        }
        #[inline(always)]
        fn bits4(self, m: __m128) -> u32 {
            sse!(_mm_movemask_ps(m)) as u32
        }
        #[inline(always)]
        fn store4(self, a: __m128) -> [f32; 4] {
            let mut out = [0.0f32; 4];
            sse!(_mm_storeu_ps(out.as_mut_ptr(), a));
            out
        }
        #[inline(always)]
        fn select4(self, m: __m128, a: __m128, b: __m128) -> __m128 {
            sse!(_mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)))
        }
        #[inline(always)]
        fn edges_f64(
            self,
            ax: __m128,
            ay: __m128,
            bx: __m128,
            by: __m128,
            cx: __m128,
            cy: __m128,
        ) -> [__m128; 3] {
            let (ax, ay, bx, by, cx, cy) = (
                widen(ax),
                widen(ay),
                widen(bx),
                widen(by),
                widen(cx),
                widen(cy),
            );
            let e = |a: [__m128d; 2], b: [__m128d; 2], c: [__m128d; 2], d: [__m128d; 2]| {
                let h = |k: usize| {
                    sse!(_mm_cvtpd_ps(_mm_sub_pd(
                        _mm_mul_pd(a[k], b[k]),
                        _mm_mul_pd(c[k], d[k])
                    )))
                };
                sse!(_mm_movelh_ps(h(0), h(1)))
            };
            [e(cx, by, cy, bx), e(ax, cy, ay, cx), e(bx, ay, by, ax)]
        }
    }
}

//! The x86-64 instruction sets: proofs that the CPU runs them ([`Sse2`], [`Avx2`], [`Avx512`]),
//! their [`Simd`] operations as intrinsics, the frames compiled with their features that
//! kernels run in, and the few kernels written for one instruction set (the transpose that
//! fills a bundle, the tie rule as masked stores). The crate's only `unsafe`.
//!
//! An intrinsic needs the CPU feature it is compiled for, so each call sits in an `unsafe`
//! block. They are sound because a proof can only be made after the CPU reported its features
//! ([`Avx2::detect`], [`Avx512::detect`]; SSE2 is part of every x86-64 CPU), and every method
//! is `#[inline(always)]`: it runs inside a frame compiled with the features, where the
//! intrinsics inline.
#![allow(unsafe_code)]

use crate::columns::{FillTarget, RayColumns, Sealed};
use crate::vector::{Simd, fold_hi, fold_lo};
use rt_core::Ray;
use std::arch::x86_64::*;

/// SSE2, which every x86-64 CPU runs: four lanes in one register, eight in two. The fallback
/// of x86-64 CPUs without AVX2, with no detection.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sse2;

/// Proof that this CPU runs AVX2 and FMA: eight lanes in one register, four in a half.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Avx2(());

/// Proof that this CPU runs AVX-512F and AVX-512VL (with AVX2 and FMA): sixteen lanes in one
/// register, and the eight-lane AVX2 operations with mask registers and thirty-two vector
/// registers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Avx512(());

impl Avx2 {
    /// `Some` when the CPU has AVX2 and FMA; the only way to make an `Avx2`.
    #[inline]
    pub fn detect() -> Option<Self> {
        (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")).then_some(Self(()))
    }
}

impl Avx512 {
    /// `Some` when the CPU has AVX-512F, AVX-512VL, AVX2 and FMA; the only way to make an
    /// `Avx512`. (Every CPU with AVX-512 this project meets, Intel's since Skylake-SP and AMD's
    /// Zen 4 and Zen 5, has VL.)
    #[inline]
    pub fn detect() -> Option<Self> {
        (Avx2::detect().is_some()
            && is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512vl"))
        .then_some(Self(()))
    }

    /// The AVX2 proof an AVX-512 CPU carries.
    #[inline(always)]
    pub fn avx2(self) -> Avx2 {
        Avx2(())
    }
}

/// An operation of [`Simd`] as one expression of intrinsics.
macro_rules! op {
    ($name:ident($($arg:ident: $ty:ty),*) -> $ret:ty, $body:expr) => {
        #[inline(always)]
        fn $name(self, $($arg: $ty),*) -> $ret {
            // SAFETY: `self` is a proof that this CPU runs the instruction set every intrinsic
            // here needs (made only after detection, or SSE2, which every x86-64 CPU runs).
            // Loads and stores go through references to arrays of the vector's exact size.
            unsafe { $body }
        }
    };
}

/// The four-lane operations that SSE2 and AVX2 compute with the same intrinsics (compiled with
/// VEX encodings inside an AVX2 frame): loads, stores, arithmetic, and the masks' bit operations.
macro_rules! m128_arithmetic {
    () => {
        op!(load(v: &[f32; 4]) -> __m128, _mm_loadu_ps(v.as_ptr()));
        op!(splat(x: f32) -> __m128, _mm_set1_ps(x));
        op!(store(a: __m128) -> [f32; 4], {
            let mut out = [0.0f32; 4];
            _mm_storeu_ps(out.as_mut_ptr(), a);
            out
        });
        op!(add(a: __m128, b: __m128) -> __m128, _mm_add_ps(a, b));
        op!(sub(a: __m128, b: __m128) -> __m128, _mm_sub_ps(a, b));
        op!(mul(a: __m128, b: __m128) -> __m128, _mm_mul_ps(a, b));
        op!(div(a: __m128, b: __m128) -> __m128, _mm_div_ps(a, b));
        // `minps a, b` is `a < b ? a : b`, NaN in either giving `b`, as the trait says.
        op!(min(a: __m128, b: __m128) -> __m128, _mm_min_ps(a, b));
        op!(max(a: __m128, b: __m128) -> __m128, _mm_max_ps(a, b));
    };
}

/// The four-lane masks' bit operations, the same for SSE2 and AVX2.
macro_rules! m128_masks {
    () => {
        op!(and(a: __m128, b: __m128) -> __m128, _mm_and_ps(a, b));
        op!(or(a: __m128, b: __m128) -> __m128, _mm_or_ps(a, b));
        op!(andnot(a: __m128, b: __m128) -> __m128, _mm_andnot_ps(a, b));
        op!(bits(m: __m128) -> u32, _mm_movemask_ps(m) as u32);
    };
}

/// The watertight test's edge functions in `f64` for four lanes in one SSE register, in two
/// halves of two.
#[inline(always)]
fn edges_f64_sse(v: [__m128; 6]) -> [__m128; 3] {
    // SAFETY: SSE2 is part of every x86-64 CPU.
    unsafe {
        let widen = |v: __m128| [_mm_cvtps_pd(v), _mm_cvtps_pd(_mm_movehl_ps(v, v))];
        let [ax, ay, bx, by, cx, cy] = v.map(widen);
        let e = |a: [__m128d; 2], b: [__m128d; 2], c: [__m128d; 2], d: [__m128d; 2]| {
            let h =
                |k: usize| _mm_cvtpd_ps(_mm_sub_pd(_mm_mul_pd(a[k], b[k]), _mm_mul_pd(c[k], d[k])));
            _mm_movelh_ps(h(0), h(1))
        };
        [e(cx, by, cy, bx), e(ax, cy, ay, cx), e(bx, ay, by, ax)]
    }
}

impl Simd<4> for Sse2 {
    type V = __m128;
    type M = __m128;

    m128_arithmetic!();
    op!(eq(a: __m128, b: __m128) -> __m128, _mm_cmpeq_ps(a, b));
    // `cmpneqps` is true for NaN; and-ing with `cmpordps` leaves the ordered lanes.
    op!(ne_ordered(a: __m128, b: __m128) -> __m128,
        _mm_and_ps(_mm_cmpneq_ps(a, b), _mm_cmpord_ps(a, b)));
    op!(lt(a: __m128, b: __m128) -> __m128, _mm_cmplt_ps(a, b));
    op!(gt(a: __m128, b: __m128) -> __m128, _mm_cmpgt_ps(a, b));
    op!(le(a: __m128, b: __m128) -> __m128, _mm_cmple_ps(a, b));
    op!(ge(a: __m128, b: __m128) -> __m128, _mm_cmpge_ps(a, b));
    m128_masks!();
    // SSE2 has no blend: the mask selects by and, andnot and or.
    op!(select(m: __m128, a: __m128, b: __m128) -> __m128,
        _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)));
    // The sign bit spread over the lane by an arithmetic shift masks `neg` in and `pos` out.
    op!(select_sign(sign: __m128, neg: __m128, pos: __m128) -> __m128, {
        let m = _mm_castsi128_ps(_mm_srai_epi32::<31>(_mm_castps_si128(sign)));
        _mm_or_ps(_mm_and_ps(m, neg), _mm_andnot_ps(m, pos))
    });
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
        edges_f64_sse([ax, ay, bx, by, cx, cy])
    }
}

/// Eight lanes as two four-lane halves of `S`: every operation on each half, the masks' bits
/// joined (for SSE2, which has no eight-lane register).
macro_rules! pairs {
    ($s:ty) => {
        impl Simd<8> for $s {
            type V = [<$s as Simd<4>>::V; 2];
            type M = [<$s as Simd<4>>::M; 2];

            #[inline(always)]
            fn load(self, v: &[f32; 8]) -> Self::V {
                let (h, _) = v.as_chunks::<4>();
                [Simd::<4>::load(self, &h[0]), Simd::<4>::load(self, &h[1])]
            }
            #[inline(always)]
            fn splat(self, x: f32) -> Self::V {
                [Simd::<4>::splat(self, x); 2]
            }
            #[inline(always)]
            fn store(self, a: Self::V) -> [f32; 8] {
                let (lo, hi) = (Simd::<4>::store(self, a[0]), Simd::<4>::store(self, a[1]));
                std::array::from_fn(|i| if i < 4 { lo[i] } else { hi[i - 4] })
            }
            pairs!(@v $s, add, sub, mul, div, min, max);
            pairs!(@m $s, eq, ne_ordered, lt, gt, le, ge);
            pairs!(@mm $s, and, or, andnot);
            #[inline(always)]
            fn bits(self, m: Self::M) -> u32 {
                Simd::<4>::bits(self, m[0]) | Simd::<4>::bits(self, m[1]) << 4
            }
            #[inline(always)]
            fn select(self, m: Self::M, a: Self::V, b: Self::V) -> Self::V {
                [0, 1].map(|k| Simd::<4>::select(self, m[k], a[k], b[k]))
            }
            #[inline(always)]
            fn select_sign(self, sign: Self::V, neg: Self::V, pos: Self::V) -> Self::V {
                [0, 1].map(|k| Simd::<4>::select_sign(self, sign[k], neg[k], pos[k]))
            }
            #[inline(always)]
            fn edges_f64(
                self,
                ax: Self::V,
                ay: Self::V,
                bx: Self::V,
                by: Self::V,
                cx: Self::V,
                cy: Self::V,
            ) -> [Self::V; 3] {
                let h = |k: usize| Simd::<4>::edges_f64(self, ax[k], ay[k], bx[k], by[k], cx[k], cy[k]);
                let (lo, hi) = (h(0), h(1));
                [[lo[0], hi[0]], [lo[1], hi[1]], [lo[2], hi[2]]]
            }
        }
    };
    (@v $s:ty, $($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self, a: Self::V, b: Self::V) -> Self::V {
            [Simd::<4>::$f(self, a[0], b[0]), Simd::<4>::$f(self, a[1], b[1])]
        }
    )*};
    (@m $s:ty, $($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self, a: Self::V, b: Self::V) -> Self::M {
            [Simd::<4>::$f(self, a[0], b[0]), Simd::<4>::$f(self, a[1], b[1])]
        }
    )*};
    (@mm $s:ty, $($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self, a: Self::M, b: Self::M) -> Self::M {
            [Simd::<4>::$f(self, a[0], b[0]), Simd::<4>::$f(self, a[1], b[1])]
        }
    )*};
}

pairs!(Sse2);

impl Simd<4> for Avx2 {
    type V = __m128;
    type M = __m128;

    m128_arithmetic!();
    op!(eq(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_EQ_OQ>(a, b));
    op!(ne_ordered(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_NEQ_OQ>(a, b));
    op!(lt(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_LT_OQ>(a, b));
    op!(gt(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_GT_OQ>(a, b));
    op!(le(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_LE_OQ>(a, b));
    op!(ge(a: __m128, b: __m128) -> __m128, _mm_cmp_ps::<_CMP_GE_OQ>(a, b));
    m128_masks!();
    // `blendvps` takes its second operand where the mask's sign bit is set.
    op!(select(m: __m128, a: __m128, b: __m128) -> __m128, _mm_blendv_ps(b, a, m));
    op!(select_sign(sign: __m128, neg: __m128, pos: __m128) -> __m128,
        _mm_blendv_ps(pos, neg, sign));
    op!(edges_f64(ax: __m128, ay: __m128, bx: __m128, by: __m128, cx: __m128, cy: __m128)
        -> [__m128; 3], {
        let d = |v: __m128| _mm256_cvtps_pd(v);
        let (ax, ay, bx, by, cx, cy) = (d(ax), d(ay), d(bx), d(by), d(cx), d(cy));
        let e = |a, b, c, d| _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_mul_pd(a, b), _mm256_mul_pd(c, d)));
        [e(cx, by, cy, bx), e(ax, cy, ay, cx), e(bx, ay, by, ax)]
    });
}

impl Simd<8> for Avx2 {
    type V = __m256;
    type M = __m256;

    op!(load(v: &[f32; 8]) -> __m256, _mm256_loadu_ps(v.as_ptr()));
    op!(splat(x: f32) -> __m256, _mm256_set1_ps(x));
    op!(store(a: __m256) -> [f32; 8], {
        let mut out = [0.0f32; 8];
        _mm256_storeu_ps(out.as_mut_ptr(), a);
        out
    });
    op!(add(a: __m256, b: __m256) -> __m256, _mm256_add_ps(a, b));
    op!(sub(a: __m256, b: __m256) -> __m256, _mm256_sub_ps(a, b));
    op!(mul(a: __m256, b: __m256) -> __m256, _mm256_mul_ps(a, b));
    op!(div(a: __m256, b: __m256) -> __m256, _mm256_div_ps(a, b));
    op!(min(a: __m256, b: __m256) -> __m256, _mm256_min_ps(a, b));
    op!(max(a: __m256, b: __m256) -> __m256, _mm256_max_ps(a, b));
    op!(eq(a: __m256, b: __m256) -> __m256, _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b));
    op!(ne_ordered(a: __m256, b: __m256) -> __m256, _mm256_cmp_ps::<_CMP_NEQ_OQ>(a, b));
    op!(lt(a: __m256, b: __m256) -> __m256, _mm256_cmp_ps::<_CMP_LT_OQ>(a, b));
    op!(gt(a: __m256, b: __m256) -> __m256, _mm256_cmp_ps::<_CMP_GT_OQ>(a, b));
    op!(le(a: __m256, b: __m256) -> __m256, _mm256_cmp_ps::<_CMP_LE_OQ>(a, b));
    op!(ge(a: __m256, b: __m256) -> __m256, _mm256_cmp_ps::<_CMP_GE_OQ>(a, b));
    op!(and(a: __m256, b: __m256) -> __m256, _mm256_and_ps(a, b));
    op!(or(a: __m256, b: __m256) -> __m256, _mm256_or_ps(a, b));
    op!(andnot(a: __m256, b: __m256) -> __m256, _mm256_andnot_ps(a, b));
    op!(bits(m: __m256) -> u32, _mm256_movemask_ps(m) as u32);
    op!(select(m: __m256, a: __m256, b: __m256) -> __m256, _mm256_blendv_ps(b, a, m));
    op!(select_sign(sign: __m256, neg: __m256, pos: __m256) -> __m256,
        _mm256_blendv_ps(pos, neg, sign));
    op!(edges_f64(ax: __m256, ay: __m256, bx: __m256, by: __m256, cx: __m256, cy: __m256)
        -> [__m256; 3], {
        let halves = |v: __m256| {
            [_mm256_cvtps_pd(_mm256_castps256_ps128(v)), _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(v))]
        };
        let (ax, ay, bx, by, cx, cy) =
            (halves(ax), halves(ay), halves(bx), halves(by), halves(cx), halves(cy));
        let e = |a: [__m256d; 2], b: [__m256d; 2], c: [__m256d; 2], d: [__m256d; 2]| {
            let h = |k: usize| {
                _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_mul_pd(a[k], b[k]), _mm256_mul_pd(c[k], d[k])))
            };
            _mm256_set_m128(h(1), h(0))
        };
        [e(cx, by, cy, bx), e(ax, cy, ay, cx), e(bx, ay, by, ax)]
    });
}

impl Simd<16> for Avx512 {
    type V = __m512;
    type M = __mmask16;

    op!(load(v: &[f32; 16]) -> __m512, _mm512_loadu_ps(v.as_ptr()));
    op!(splat(x: f32) -> __m512, _mm512_set1_ps(x));
    op!(store(a: __m512) -> [f32; 16], {
        let mut out = [0.0f32; 16];
        _mm512_storeu_ps(out.as_mut_ptr(), a);
        out
    });
    op!(add(a: __m512, b: __m512) -> __m512, _mm512_add_ps(a, b));
    op!(sub(a: __m512, b: __m512) -> __m512, _mm512_sub_ps(a, b));
    op!(mul(a: __m512, b: __m512) -> __m512, _mm512_mul_ps(a, b));
    op!(div(a: __m512, b: __m512) -> __m512, _mm512_div_ps(a, b));
    op!(min(a: __m512, b: __m512) -> __m512, _mm512_min_ps(a, b));
    op!(max(a: __m512, b: __m512) -> __m512, _mm512_max_ps(a, b));
    op!(eq(a: __m512, b: __m512) -> __mmask16, _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b));
    op!(ne_ordered(a: __m512, b: __m512) -> __mmask16, _mm512_cmp_ps_mask::<_CMP_NEQ_OQ>(a, b));
    op!(lt(a: __m512, b: __m512) -> __mmask16, _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b));
    op!(gt(a: __m512, b: __m512) -> __mmask16, _mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b));
    op!(le(a: __m512, b: __m512) -> __mmask16, _mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b));
    op!(ge(a: __m512, b: __m512) -> __mmask16, _mm512_cmp_ps_mask::<_CMP_GE_OQ>(a, b));
    #[inline(always)]
    fn and(self, a: __mmask16, b: __mmask16) -> __mmask16 {
        a & b
    }
    #[inline(always)]
    fn or(self, a: __mmask16, b: __mmask16) -> __mmask16 {
        a | b
    }
    #[inline(always)]
    fn andnot(self, a: __mmask16, b: __mmask16) -> __mmask16 {
        !a & b
    }
    #[inline(always)]
    fn bits(self, m: __mmask16) -> u32 {
        u32::from(m)
    }
    // `_mm512_mask_blend_ps(k, b, a)` takes `a` where `k` is set.
    op!(select(m: __mmask16, a: __m512, b: __m512) -> __m512, _mm512_mask_blend_ps(m, b, a));
    // The sign bit set is the lane read as an integer below zero.
    op!(select_sign(sign: __m512, neg: __m512, pos: __m512) -> __m512, {
        let m = _mm512_cmplt_epi32_mask(_mm512_castps_si512(sign), _mm512_setzero_si512());
        _mm512_mask_blend_ps(m, pos, neg)
    });
    op!(edges_f64(ax: __m512, ay: __m512, bx: __m512, by: __m512, cx: __m512, cy: __m512)
        -> [__m512; 3], {
        let halves = |v: __m512| {
            let hi = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v)));
            [_mm512_cvtps_pd(_mm512_castps512_ps256(v)), _mm512_cvtps_pd(hi)]
        };
        let (ax, ay, bx, by, cx, cy) =
            (halves(ax), halves(ay), halves(bx), halves(by), halves(cx), halves(cy));
        let e = |a: [__m512d; 2], b: [__m512d; 2], c: [__m512d; 2], d: [__m512d; 2]| {
            let h = |k: usize| {
                _mm512_cvtpd_ps(_mm512_sub_pd(_mm512_mul_pd(a[k], b[k]), _mm512_mul_pd(c[k], d[k])))
            };
            let lo = _mm512_castps256_ps512(h(0));
            _mm512_castpd_ps(_mm512_insertf64x4::<1>(_mm512_castps_pd(lo), _mm256_castps_pd(h(1))))
        };
        [e(cx, by, cy, bx), e(ax, cy, ay, cx), e(bx, ay, by, ax)]
    });
}

/// Calls `f` in a function compiled with AVX2 and FMA, where `f` and what it inlines are
/// compiled with them too.
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(crate) fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Calls `f` in a function compiled with AVX-512F as well as AVX2 and FMA.
#[target_feature(enable = "avx2,fma,avx512f")]
#[inline]
pub(crate) fn with_avx512<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Runs `w` with the AVX2 proof, compiled with AVX2 and FMA enabled so that the operations
/// `w` inlines are AVX2 instructions.
#[target_feature(enable = "avx2,fma")]
pub(crate) fn wide_avx2<W: crate::WithLanes>(w: W, s: Avx2) -> W::Out {
    w.run(s)
}

/// Runs `f` in a frame compiled for `s`'s instruction set: AVX2 and FMA.
#[inline(always)]
pub(crate) fn run_avx2<R>(_: Avx2, f: impl FnOnce() -> R) -> R {
    // SAFETY: an `Avx2` exists only if this CPU runs AVX2 and FMA, all `with_avx2` requires.
    unsafe { with_avx2(f) }
}

/// Runs `f` in a frame compiled with AVX-512F as well.
#[inline(always)]
pub(crate) fn run_avx512<R>(_: Avx512, f: impl FnOnce() -> R) -> R {
    // SAFETY: an `Avx512` exists only if this CPU runs AVX-512F, AVX2 and FMA, all
    // `with_avx512` requires.
    unsafe { with_avx512(f) }
}

/// Runs `w` with the AVX2 proof, compiled with AVX-512F and AVX-512VL as well: the same
/// eight-lane operations, which the compiler may encode with mask registers and thirty-two
/// vector registers.
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
pub(crate) fn wide_avx512<W: crate::WithLanes>(w: W, s: Avx2) -> W::Out {
    w.run(s)
}

/// Runs `w` with the AVX2 operations in a frame compiled for AVX-512F and AVX-512VL.
#[inline(always)]
pub(crate) fn run_wide_avx512<W: crate::WithLanes>(s: Avx512, w: W) -> W::Out {
    // SAFETY: an `Avx512` exists only if this CPU runs AVX-512F, AVX-512VL, AVX2 and FMA, all
    // `wide_avx512` requires.
    unsafe { wide_avx512(w, s.avx2()) }
}

/// Runs `w` with the AVX2 proof in its frame.
#[inline(always)]
pub(crate) fn run_wide_avx2<W: crate::WithLanes>(s: Avx2, w: W) -> W::Out {
    // SAFETY: an `Avx2` exists only if this CPU runs AVX2 and FMA, all `wide_avx2` requires.
    unsafe { wide_avx2(w, s) }
}

/// Asks the CPU to bring the cache lines at bytes `64 * first .. 64 * (first + lines)` of `v`
/// into its caches, those that lie inside `v`; a hint only, which changes no value.
#[inline(always)]
pub(crate) fn prefetch_lines<T>(v: &[T], first: usize, lines: usize) {
    let size = size_of_val(v);
    for line in first..first.saturating_add(lines) {
        let Some(offset) = line.checked_mul(64).filter(|&offset| offset < size) else {
            break;
        };
        // SAFETY: the address lies inside `v` (`offset` is less than its size in bytes); a
        // prefetch reads nothing a program sees and never faults.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(v.as_ptr().cast::<i8>().add(offset)) };
    }
}

/// Sixteen lanes' best hits so far, as `Lanes` keeps them.
pub(crate) struct Best16<'a> {
    pub t: &'a mut [f32; 16],
    pub prim: &'a mut [u32; 16],
    pub u: &'a mut [f32; 16],
    pub v: &'a mut [f32; 16],
}

/// `ray_columns8`'s transpose, with AVX2 (which the caller's proof shows).
#[inline(always)]
pub(crate) fn ray_columns8_avx2(_: Avx2, rays: &[Ray; 8]) -> RayColumns {
    // SAFETY: an `Avx2` exists only if this CPU runs AVX2.
    unsafe { ray_columns8(rays) }
}

/// `fill_sealed` with AVX2, or with AVX-512VL as well where the CPU has it.
#[inline(always)]
pub(crate) fn fill_sealed_avx2(
    _: Avx2,
    vl: bool,
    b: FillTarget<'_>,
    rays: &[[Ray; 8]],
    octant: usize,
    order: [[usize; 3]; 3],
) -> Sealed {
    if vl && is_x86_feature_detected!("avx512vl") && is_x86_feature_detected!("avx512f") {
        // SAFETY: AVX-512F and AVX-512VL are checked just above; an `Avx2` shows AVX2.
        unsafe { fill_sealed_vl(b, rays, octant, order) }
    } else {
        // SAFETY: an `Avx2` exists only if this CPU runs AVX2.
        unsafe { fill_sealed(b, rays, octant, order) }
    }
}

/// `keep16`, which the caller's proof allows.
#[inline(always)]
pub(crate) fn keep16_avx512(
    _: Avx512,
    out: [&[f32; 16]; 3],
    id: u32,
    lanes: u16,
    best: Best16<'_>,
) -> u16 {
    // SAFETY: an `Avx512` exists only if this CPU runs AVX-512F.
    unsafe { keep16(out, id, lanes, best) }
}

/// Eight rays transposed into their lanes' columns (what the bundle module's portable
/// `ray_columns8` makes field by field), as an 8×8 transpose of the rays' first eight fields and
/// a 4×8 one of their last four.
// PERF: written field by field, filling a bundle with the rays of a camera's 8×8 tile was
// the largest part of the time around a bundle walk; see `Bundle::fill`.
#[target_feature(enable = "avx2")]
#[inline]
fn ray_columns8(rays: &[Ray; 8]) -> RayColumns {
    let mut c = [[0.0f32; 8]; 11];
    let v = columns8(rays);
    for (c, v) in c.iter_mut().zip(v) {
        // SAFETY: the store writes eight `f32` into an array of eight; unaligned stores need
        // no alignment.
        unsafe { _mm256_storeu_ps(c.as_mut_ptr(), v) };
    }
    c
}

/// The transpose of [`ray_columns8`], in registers.
#[target_feature(enable = "avx2")]
#[inline]
fn columns8(rays: &[Ray; 8]) -> [__m256; 11] {
    // SAFETY: `Ray` is `repr(C)`, eleven `f32` with no padding (asserted beside it), so
    // each ray's fields 0..8 and 7..11 are 32 and 16 bytes inside it; unaligned loads need
    // no alignment.
    unsafe {
        let row = |i: usize| (&raw const rays[i]).cast::<f32>();
        let r: [__m256; 8] = std::array::from_fn(|i| _mm256_loadu_ps(row(i)));
        // Pairs of rays interleaved, then fours, then the halves of eight joined.
        let lo = |a, b| _mm256_unpacklo_ps(a, b);
        let hi = |a, b| _mm256_unpackhi_ps(a, b);
        let (t0, t1, t2, t3) = (
            lo(r[0], r[1]),
            hi(r[0], r[1]),
            lo(r[2], r[3]),
            hi(r[2], r[3]),
        );
        let (t4, t5, t6, t7) = (
            lo(r[4], r[5]),
            hi(r[4], r[5]),
            lo(r[6], r[7]),
            hi(r[6], r[7]),
        );
        let even = |a, b| _mm256_shuffle_ps::<0x44>(a, b);
        let odd = |a, b| _mm256_shuffle_ps::<0xEE>(a, b);
        let s = [even(t0, t2), odd(t0, t2), even(t1, t3), odd(t1, t3)];
        let u = [even(t4, t6), odd(t4, t6), even(t5, t7), odd(t5, t7)];
        let mut c = [_mm256_setzero_ps(); 11];
        for k in 0..4 {
            c[k] = _mm256_permute2f128_ps::<0x20>(s[k], u[k]);
            c[k + 4] = _mm256_permute2f128_ps::<0x31>(s[k], u[k]);
        }
        // Fields 7..11 of ray `i` in the low half and of ray `i + 4` in the high half.
        let tail = |i: usize| {
            let q = |i: usize| _mm_loadu_ps(row(i).add(7));
            _mm256_set_m128(q(i + 4), q(i))
        };
        let (q0, q1, q2, q3) = (tail(0), tail(1), tail(2), tail(3));
        let (a, b) = (lo(q0, q1), hi(q0, q1));
        let (d, e) = (lo(q2, q3), hi(q2, q3));
        c[8] = odd(a, d);
        c[9] = even(b, e);
        c[10] = odd(b, e);
        c
    }
}

/// A bundle's fill with AVX2: for each group of eight rays, the
/// transpose of [`columns8`] stored into the bundle's lanes; the conditions of
/// `Bundle::all_bundle_in` as vector comparisons (each false for NaN, as the scalar
/// comparisons are); the running minima and maxima of `Bundle::seal`, with the same
/// comparisons (`_mm256_min_ps(a, b)` is `if a < b { a } else { b }`) and the same final
/// folds; and each lane's shear as `Bundle::shear_lanes` makes it, by the same comparisons,
/// selects and two products.
#[target_feature(enable = "avx2")]
#[inline]
fn fill_sealed(
    b: FillTarget<'_>,
    rays: &[[Ray; 8]],
    octant: usize,
    order: [[usize; 3]; 3],
) -> Sealed {
    let splat = _mm256_set1_ps;
    let abs = |x: __m256| _mm256_andnot_ps(splat(-0.0), x);
    let le = |a: __m256, b: __m256| _mm256_cmp_ps::<_CMP_LE_OQ>(a, b);
    let ge = |a: __m256, b: __m256| _mm256_cmp_ps::<_CMP_GE_OQ>(a, b);
    let finite = |x: __m256| _mm256_cmp_ps::<_CMP_LT_OQ>(abs(x), splat(f32::INFINITY));
    let and = |a: __m256, b: __m256| _mm256_and_ps(a, b);
    let bits = |m: __m256| _mm256_movemask_ps(m) as u32;
    let (dir_lo, dir_hi) = (*Ray::DIR_RANGE.start(), *Ray::DIR_RANGE.end());
    let mut bad = 0u32;
    let (mut lo, mut hi) = ([_mm256_setzero_ps(); 7], [_mm256_setzero_ps(); 6]);
    *b.by_axis = [0; 3];
    for (g, eight) in rays.iter().enumerate() {
        let c = columns8(eight);
        let lanes = g * 8..g * 8 + 8;
        let store = |v: &mut [f32; 64], x: __m256| {
            // SAFETY: `lanes` is eight lanes of an array of `BUNDLE_LANES` (`g` < 8, as
            // the caller checks); unaligned stores need no alignment.
            unsafe { _mm256_storeu_ps(v[lanes.clone()].as_mut_ptr(), x) }
        };
        for a in 0..3 {
            store(&mut b.origin[a], c[a]);
            store(&mut b.dir[a], c[3 + a]);
            store(&mut b.inv_dir[a], c[6 + a]);
        }
        store(b.t_min, c[9]);
        store(b.t_max, c[10]);
        // `bundles_ray`, lane by lane, and the octant's signs.
        let (d, t0, t1) = ([c[3], c[4], c[5]], c[9], c[10]);
        let mut ok = finite(t0);
        for a in 0..3 {
            ok = and(ok, le(abs(c[a]), splat(Ray::MAX_ORIGIN)));
            ok = and(ok, finite(d[a]));
            ok = and(ok, _mm256_cmp_ps::<_CMP_NEQ_OQ>(d[a], _mm256_setzero_ps()));
            ok = and(ok, finite(c[6 + a]));
            let negative = if octant >> a & 1 != 0 { 0xff } else { 0 };
            bad |= bits(d[a]) ^ negative;
        }
        let largest = _mm256_max_ps(_mm256_max_ps(abs(d[0]), abs(d[1])), abs(d[2]));
        ok = and(
            ok,
            and(ge(largest, splat(dir_lo)), le(largest, splat(dir_hi))),
        );
        ok = and(ok, and(ge(t0, _mm256_setzero_ps()), le(t0, t1)));
        bad |= !bits(ok) & 0xff;
        // The bounds over the lanes.
        let low = [c[0], c[1], c[2], c[6], c[7], c[8], c[9]];
        for k in 0..7 {
            lo[k] = if g == 0 {
                low[k]
            } else {
                _mm256_min_ps(lo[k], low[k])
            };
        }
        for k in 0..6 {
            hi[k] = if g == 0 {
                low[k]
            } else {
                _mm256_max_ps(hi[k], low[k])
            };
        }
        // Each lane's shear: x if its magnitude is at least both others', else y if at
        // least z's, else z; the factors from the components in that axis order.
        let (ax, ay, az) = (abs(d[0]), abs(d[1]), abs(d[2]));
        let x = and(ge(ax, ay), ge(ax, az));
        let y = _mm256_andnot_ps(x, ge(ay, az));
        let pick = |k: usize| {
            let yz = _mm256_blendv_ps(d[order[2][k]], d[order[1][k]], y);
            _mm256_blendv_ps(yz, d[order[0][k]], x)
        };
        // `1 / d[kz]` is the ray's own reciprocal of that component (`Ray::inv_dir` is
        // made by the same division), so it is picked rather than divided again.
        let inv = [c[6], c[7], c[8]];
        let yz = _mm256_blendv_ps(inv[order[2][2]], inv[order[1][2]], y);
        let sz = _mm256_blendv_ps(yz, inv[order[0][2]], x);
        store(&mut b.shear[0], _mm256_mul_ps(pick(0), sz));
        store(&mut b.shear[1], _mm256_mul_ps(pick(1), sz));
        store(&mut b.shear[2], sz);
        let (on_x, on_y) = (u64::from(bits(x)), u64::from(bits(y)));
        b.by_axis[0] |= on_x << (g * 8);
        b.by_axis[1] |= on_y << (g * 8);
        b.by_axis[2] |= (!(on_x | on_y) & 0xff) << (g * 8);
    }
    let out = |v: __m256| {
        let mut a = [0.0f32; 8];
        // SAFETY: the store writes eight `f32` into an array of eight.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), v) };
        a
    };
    let lows: [f32; 7] = std::array::from_fn(|k| fold_lo(out(lo[k])));
    let highs: [f32; 6] = std::array::from_fn(|k| fold_hi(out(hi[k])));
    Sealed {
        good: bad == 0,
        origin_lo: [lows[0], lows[1], lows[2]],
        origin_hi: [highs[0], highs[1], highs[2]],
        inv_lo: [lows[3], lows[4], lows[5]],
        inv_hi: [highs[3], highs[4], highs[5]],
        t_min_lo: lows[6],
    }
}

/// `fill_sealed` compiled with AVX-512VL as well: the same AVX2 instructions, with
/// thirty-two vector registers instead of sixteen, so that the running bounds stay in
/// registers.
// PERF: with sixteen registers, a third of the bounds and masks went to the stack and back
// for every group of eight rays. Filling bundles alone (`for_each_bundle`, the teapot's
// filled view at half the distance, primary rays in 8×8 tiles, one thread, a private
// harness): 2.62 -> 2.13 ns a ray with the rays in the caches, 3.15 -> 2.57 from memory.
// The wide BVH's bundles there, medians of five alternating runs, Mrays/s: the teapot
// 68.9 -> 69.1, the bunny 51.7 -> 52.5, the sphereflake 40.1 -> 40.2, the teapot in a
// stadium 70.2 -> 71.7.
#[target_feature(enable = "avx2,avx512f,avx512vl")]
fn fill_sealed_vl(
    b: FillTarget<'_>,
    rays: &[[Ray; 8]],
    octant: usize,
    order: [[usize; 3]; 3],
) -> Sealed {
    fill_sealed(b, rays, octant, order)
}

/// The tie rule `Hit::beats` of sixteen lanes as two comparisons and a masked store of each
/// of the four outputs.
#[target_feature(enable = "avx512f")]
#[inline]
fn keep16(out: [&[f32; 16]; 3], id: u32, lanes: u16, best: Best16<'_>) -> u16 {
    // SAFETY: every load reads sixteen 32-bit values of an array of sixteen, and every
    // masked store writes at most sixteen into one; unaligned accesses need no alignment.
    unsafe {
        let t = _mm512_loadu_ps(out[0].as_ptr());
        let best_t = _mm512_loadu_ps(best.t.as_ptr());
        let best_prim = _mm512_loadu_si512(best.prim.as_ptr().cast());
        let id_v = _mm512_set1_epi32(id as i32);
        // `t < best_t || (t == best_t && id < best_prim)`, unsigned as the `u32`s compare.
        let closer = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(lanes, t, best_t);
        let tie = _mm512_mask_cmp_ps_mask::<_CMP_EQ_OQ>(lanes, t, best_t)
            & _mm512_cmplt_epu32_mask(id_v, best_prim);
        let keep = closer | tie;
        _mm512_mask_storeu_ps(best.t.as_mut_ptr(), keep, t);
        _mm512_mask_storeu_epi32(best.prim.as_mut_ptr().cast(), keep, id_v);
        _mm512_mask_storeu_ps(best.u.as_mut_ptr(), keep, _mm512_loadu_ps(out[1].as_ptr()));
        _mm512_mask_storeu_ps(best.v.as_mut_ptr(), keep, _mm512_loadu_ps(out[2].as_ptr()));
        keep
    }
}

//! Lane vectors: [`Simd<N>`], the operations every kernel is written with, for `N` lanes of
//! `f32`, and [`Portable`], its implementation on plain arrays.
//!
//! A kernel is written once, generic over `S: Simd<N>`, and runs with every instruction set
//! that implements `Simd<N>` for its width: [`Portable`] for any width and target, and on
//! x86-64 the proofs of [`Isa`](crate::Isa) support ([`Sse2`](crate::Sse2),
//! [`Avx2`](crate::Avx2), [`Avx512`](crate::Avx512)) with intrinsics. Every implementation
//! computes each lane with the IEEE operation its method names, with Rust's operators'
//! comparison semantics (false when a lane is NaN) and no fused multiply-add, so a kernel
//! gives the same bits on every instruction set, and the same bits as the scalar function it
//! mirrors (the tests compare them exactly).

/// The lane operations of `N` lanes of `f32`.
///
/// A value of an implementing type is a proof that the CPU runs its instructions; its methods
/// are `#[inline(always)]` in every implementation, so a kernel generic over `S` compiles to
/// that instruction set's instructions where it is inlined into a frame compiled for it
/// ([`Isa::run`](crate::Isa::run), [`Isa::wide`](crate::Isa::wide)).
pub trait Simd<const N: usize>: Copy {
    /// `N` lanes of `f32`.
    type V: Copy;
    /// The result of a comparison of `N` lanes.
    type M: Copy;

    /// Loads `N` lanes.
    fn load(self, v: &[f32; N]) -> Self::V;
    /// `x` in every lane.
    fn splat(self, x: f32) -> Self::V;
    /// The lanes, as an array.
    fn store(self, a: Self::V) -> [f32; N];
    /// `a + b`, lane by lane.
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a - b`, lane by lane.
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a * b`, lane by lane (never fused with an addition).
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a / b`, lane by lane (IEEE division).
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// Per lane `if a < b { a } else { b }` (so `b` where either is NaN).
    fn min(self, a: Self::V, b: Self::V) -> Self::V;
    /// Per lane `if a > b { a } else { b }` (so `b` where either is NaN).
    fn max(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a == b`.
    fn eq(self, a: Self::V, b: Self::V) -> Self::M;
    /// `a != b` and neither is NaN.
    fn ne_ordered(self, a: Self::V, b: Self::V) -> Self::M;
    /// `a < b`.
    fn lt(self, a: Self::V, b: Self::V) -> Self::M;
    /// `a > b`.
    fn gt(self, a: Self::V, b: Self::V) -> Self::M;
    /// `a <= b`.
    fn le(self, a: Self::V, b: Self::V) -> Self::M;
    /// `a >= b`.
    fn ge(self, a: Self::V, b: Self::V) -> Self::M;
    /// `a & b` of two masks.
    fn and(self, a: Self::M, b: Self::M) -> Self::M;
    /// `a | b` of two masks.
    fn or(self, a: Self::M, b: Self::M) -> Self::M;
    /// `!a & b` of two masks.
    fn andnot(self, a: Self::M, b: Self::M) -> Self::M;
    /// Bit `i` set when lane `i` of the mask is.
    fn bits(self, m: Self::M) -> u32;
    /// Per lane `if m { a } else { b }`.
    fn select(self, m: Self::M, a: Self::V, b: Self::V) -> Self::V;
    /// Per lane `neg` where `sign`'s sign bit is set (`-0` and negative NaN included), else
    /// `pos`.
    fn select_sign(self, sign: Self::V, neg: Self::V, pos: Self::V) -> Self::V;
    /// The watertight test's edge functions recomputed in `f64` and rounded to `f32`, per lane:
    /// `(cx·by − cy·bx, ax·cy − ay·cx, bx·ay − by·ax)`.
    #[allow(clippy::too_many_arguments)]
    fn edges_f64(
        self,
        ax: Self::V,
        ay: Self::V,
        bx: Self::V,
        by: Self::V,
        cx: Self::V,
        cy: Self::V,
    ) -> [Self::V; 3];
}

/// The lane operations on plain arrays, for any width and any target: what the compiler makes
/// of loops over `N` lanes (SSE2 or NEON vectors for the baseline target, AVX2 ones inside a
/// frame compiled with AVX2). The reference the intrinsics match bit for bit, and what every
/// target without intrinsics runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Portable;

#[inline(always)]
fn map<const N: usize>(a: [f32; N], b: [f32; N], f: impl Fn(f32, f32) -> f32) -> [f32; N] {
    std::array::from_fn(|i| f(a[i], b[i]))
}

/// Bit `i` set when `f(a[i], b[i])`.
#[inline(always)]
fn cmp<const N: usize>(a: [f32; N], b: [f32; N], f: impl Fn(f32, f32) -> bool) -> u32 {
    let mut m = 0;
    for i in 0..N {
        m |= (f(a[i], b[i]) as u32) << i;
    }
    m
}

impl<const N: usize> Simd<N> for Portable {
    type V = [f32; N];
    /// Masks are bit masks, `N` at most 32: the bit operations are one instruction each, and no
    /// lane-by-lane gathering is left for the tests of a mask. PERF: as `[bool; 4]`, the
    /// portable kernels traced the teapot's primary rays slower than the binary tree (15.0
    /// against 18.7 Mrays/s).
    type M = u32;

    #[inline(always)]
    fn load(self, v: &[f32; N]) -> [f32; N] {
        *v
    }
    #[inline(always)]
    fn splat(self, x: f32) -> [f32; N] {
        [x; N]
    }
    #[inline(always)]
    fn store(self, a: [f32; N]) -> [f32; N] {
        a
    }
    #[inline(always)]
    fn add(self, a: [f32; N], b: [f32; N]) -> [f32; N] {
        map(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, a: [f32; N], b: [f32; N]) -> [f32; N] {
        map(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, a: [f32; N], b: [f32; N]) -> [f32; N] {
        map(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn div(self, a: [f32; N], b: [f32; N]) -> [f32; N] {
        map(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn min(self, a: [f32; N], b: [f32; N]) -> [f32; N] {
        map(a, b, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn max(self, a: [f32; N], b: [f32; N]) -> [f32; N] {
        map(a, b, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn eq(self, a: [f32; N], b: [f32; N]) -> u32 {
        cmp(a, b, |a, b| a == b)
    }
    #[inline(always)]
    fn ne_ordered(self, a: [f32; N], b: [f32; N]) -> u32 {
        cmp(a, b, |a, b| a != b && !a.is_nan() && !b.is_nan())
    }
    #[inline(always)]
    fn lt(self, a: [f32; N], b: [f32; N]) -> u32 {
        cmp(a, b, |a, b| a < b)
    }
    #[inline(always)]
    fn gt(self, a: [f32; N], b: [f32; N]) -> u32 {
        cmp(a, b, |a, b| a > b)
    }
    #[inline(always)]
    fn le(self, a: [f32; N], b: [f32; N]) -> u32 {
        cmp(a, b, |a, b| a <= b)
    }
    #[inline(always)]
    fn ge(self, a: [f32; N], b: [f32; N]) -> u32 {
        cmp(a, b, |a, b| a >= b)
    }
    #[inline(always)]
    fn and(self, a: u32, b: u32) -> u32 {
        a & b
    }
    #[inline(always)]
    fn or(self, a: u32, b: u32) -> u32 {
        a | b
    }
    #[inline(always)]
    fn andnot(self, a: u32, b: u32) -> u32 {
        !a & b
    }
    #[inline(always)]
    fn bits(self, m: u32) -> u32 {
        const { assert!(N <= 32, "portable masks hold at most 32 lanes") };
        if N == 32 { m } else { m & ((1 << N) - 1) }
    }
    #[inline(always)]
    fn select(self, m: u32, a: [f32; N], b: [f32; N]) -> [f32; N] {
        std::array::from_fn(|i| if m >> i & 1 != 0 { a[i] } else { b[i] })
    }
    #[inline(always)]
    fn select_sign(self, sign: [f32; N], neg: [f32; N], pos: [f32; N]) -> [f32; N] {
        std::array::from_fn(|i| {
            if sign[i].is_sign_negative() {
                neg[i]
            } else {
                pos[i]
            }
        })
    }
    #[inline(always)]
    fn edges_f64(
        self,
        ax: [f32; N],
        ay: [f32; N],
        bx: [f32; N],
        by: [f32; N],
        cx: [f32; N],
        cy: [f32; N],
    ) -> [[f32; N]; 3] {
        let d = |v: [f32; N]| v.map(f64::from);
        let (ax, ay, bx, by, cx, cy) = (d(ax), d(ay), d(bx), d(by), d(cx), d(cy));
        [
            std::array::from_fn(|i| (cx[i] * by[i] - cy[i] * bx[i]) as f32),
            std::array::from_fn(|i| (ax[i] * cy[i] - ay[i] * cx[i]) as f32),
            std::array::from_fn(|i| (bx[i] * ay[i] - by[i] * ax[i]) as f32),
        ]
    }
}

/// The smallest of eight lanes (as a bundle's lane bounds fold them).
#[inline(always)]
pub(crate) fn fold_lo(v: [f32; 8]) -> f32 {
    v.into_iter().fold(f32::INFINITY, f32::min)
}

/// The largest of eight lanes.
#[inline(always)]
pub(crate) fn fold_hi(v: [f32; 8]) -> f32 {
    v.into_iter().fold(f32::NEG_INFINITY, f32::max)
}

//! Run-time choice of vector instructions for the bundle kernels ([`Lanes`](crate::bundle::Lanes)),
//! the filling of bundles ([`fill_sealed`]) and the bundle walks ([`Isa::run`]).
//!
//! The only `unsafe` of rt-core besides `pod_struct!` and [`Stack`](crate::Stack): the AVX2
//! and AVX-512 kernels and the frames the bundle walks run in, each called only when the CPU
//! was found to have the features it is compiled with ([`Isa::available`]). Each kernel here has a portable twin in
//! plain arrays ([`watertight8_portable`]; `Bundle::fill_sealed`'s passes) that it matches
//! bit for bit: the same IEEE operations in the same order, no fused multiply-add.
#![allow(unsafe_code)]

use crate::Ray;
use crate::lanes::{Out8, Step8, watertight8_portable};
#[cfg(target_arch = "x86_64")]
use crate::lanes::{Out16, Step16};

/// The instruction set the kernels run with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Plain arrays, whatever the compiler makes of them for the build's target.
    Portable,
    /// AVX2 and FMA (x86-64), found on this CPU at run time.
    #[cfg(target_arch = "x86_64")]
    Avx2,
    /// AVX-512 (its foundation, with AVX2 and FMA) on x86-64, found on this CPU at run time:
    /// the watertight kernel tests sixteen lanes per step.
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Isa {
    /// The best this CPU has; `RT_ACCEL_PORTABLE=1` in the environment forces the portable one
    /// (the tests run both).
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if portable_forced() {
            return Isa::Portable;
        }
        Self::detect_ignoring_env()
    }

    /// The best this CPU has, whatever the environment says.
    pub(crate) fn detect_ignoring_env() -> Self {
        #[cfg(target_arch = "x86_64")]
        if Isa::Avx512.available() {
            return Isa::Avx512;
        }
        #[cfg(target_arch = "x86_64")]
        if Isa::Avx2.available() {
            return Isa::Avx2;
        }
        Isa::Portable
    }

    /// Whether this CPU runs this instruction set.
    pub fn available(self) -> bool {
        match self {
            Isa::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => Isa::Avx2.available() && std::arch::is_x86_feature_detected!("avx512f"),
        }
    }

    /// Every instruction set this CPU runs, the portable one first (for tests that compare
    /// them).
    pub fn all_available() -> Vec<Isa> {
        #[cfg_attr(not(target_arch = "x86_64"), allow(unused_mut))]
        let mut isas = vec![Isa::Portable];
        #[cfg(target_arch = "x86_64")]
        isas.extend(
            [Isa::Avx2, Isa::Avx512]
                .into_iter()
                .filter(|i| i.available()),
        );
        isas
    }

    /// Runs `f` compiled for this instruction set where the CPU has it (else as the build's
    /// target has it): with [`Isa::Avx2`] or [`Isa::Avx512`], inside a function compiled with
    /// AVX2 and FMA enabled, so that the code `f` inlines (a bundle walk's loops over eight
    /// lanes, the eight-lane kernel) is vectorised with them, eight lanes to a register and
    /// with mask moves, instead of the baseline's four-lane SSE2. The sixteen-lane AVX-512
    /// kernel is called from there, not inlined.
    ///
    /// The answers do not change: the same IEEE operations run in the same order, and Rust
    /// never fuses a multiply and an add on its own, so enabling FMA adds no fused operation.
    // PERF: bundles ÷ single rays, before and after the bundle walks ran inside this (their
    // own crate's harness, medians of 3 alternating passes, one thread, filled views, 8×8
    // tiles; bunny, sphereflake, teapot in a stadium, rocker arm): kd-tree primary 1.84 1.70
    // 2.09 2.06 -> 1.99 1.85 2.31 2.30, shadow 1.73 1.42 2.16 2.00 -> 2.02 1.55 2.46 2.33;
    // octree primary 3.77 3.57 5.05 4.98 -> 4.25 4.03 5.64 5.35; the hierarchical grid and
    // the binary BVH unchanged within ±3%.
    // PERF: the frame compiled with AVX-512F as well (the sixteen-lane kernel inlined) made
    // the bundle walks slower, not faster: the teapot's close view, primary rays in 8×8 tiles,
    // one thread, three alternating runs, Mrays/s with the AVX2 frame and the eight-lane kernel
    // -> the AVX-512 frame and the sixteen-lane kernel: wide BVH 31.4 31.0 30.4 -> 27.3 27.2
    // 28.0, kd-tree 29.0 28.8 29.2 -> 27.4 26.5 27.3, octree 24.1 24.6 22.8 -> 23.3 22.4 23.3.
    #[inline(always)]
    pub fn run<R>(self, f: impl FnOnce() -> R) -> R {
        match self {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 if Isa::Avx2.available() => {
                // SAFETY: this CPU has AVX2 and FMA (checked just above), which is all
                // `x86::with_avx2` requires.
                unsafe { x86::with_avx2(f) }
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 if Isa::Avx512.available() => {
                // SAFETY: this CPU has AVX-512F, AVX2 and FMA (checked just above); the frame
                // requires AVX2 and FMA.
                unsafe { x86::with_avx2(f) }
            }
            _ => f(),
        }
    }
}

/// Whether the environment asks for the portable kernels, read once.
#[cfg(target_arch = "x86_64")]
fn portable_forced() -> bool {
    static FORCED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FORCED.get_or_init(|| std::env::var_os("RT_ACCEL_PORTABLE").is_some_and(|v| v == "1"))
}

/// The watertight test of eight lanes with instruction set `isa`.
#[inline(always)]
pub(crate) fn watertight8(isa: Isa, verts: &[f32; 9], input: &Step8) -> Out8 {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Lanes` holds `Isa::Avx2` or `Isa::Avx512` only when `Isa::available` found
        // this CPU runs it, and both include AVX2.
        Isa::Avx2 | Isa::Avx512 => unsafe { x86::watertight8(verts, input) },
        Isa::Portable => watertight8_portable(verts, input),
    }
}

/// The watertight test of sixteen lanes in one AVX-512 step; `None` for any other `isa`
/// (`Lanes` calls it only with `Isa::Avx512`, and tests eight lanes at a time otherwise).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn watertight16(isa: Isa, verts: &[f32; 9], input: &Step16) -> Option<Out16> {
    match isa {
        // SAFETY: `Lanes` holds `Isa::Avx512` only when `Isa::available` found this CPU runs it.
        Isa::Avx512 => Some(unsafe { x86::watertight16(verts, input) }),
        _ => None,
    }
}

/// Sixteen lanes' best hits so far, as [`Lanes`](crate::bundle::Lanes) keeps them.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Best16<'a> {
    pub t: &'a mut [f32; 16],
    pub prim: &'a mut [u32; 16],
    pub u: &'a mut [f32; 16],
    pub v: &'a mut [f32; 16],
}

/// Keeps the hits of `out` on primitive `id` in the lanes of `lanes` where they beat the
/// lane's best by the tie rule ([`Hit::beats`](crate::Hit::beats)), all sixteen at once;
/// returns the lanes whose best they became. `None` for any other `isa` than AVX-512.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn keep16(isa: Isa, out: &Out16, id: u32, lanes: u16, best: Best16<'_>) -> Option<u16> {
    match isa {
        // SAFETY: `Lanes` holds `Isa::Avx512` only when `Isa::available` found this CPU runs it.
        Isa::Avx512 => Some(unsafe { x86::keep16(out, id, lanes, best) }),
        _ => None,
    }
}

/// Eight rays as the eleven vectors of their lanes: origin x, y, z, direction x, y, z,
/// reciprocal direction x, y, z, `t_min`, `t_max` (the order of [`Ray`]'s fields).
pub(crate) type RayColumns = [[f32; 8]; 11];

/// Eight rays transposed into [`RayColumns`] with instruction set `isa`: the same values
/// either way, only moved.
#[inline(always)]
pub(crate) fn ray_columns8(isa: Isa, rays: &[Ray; 8]) -> RayColumns {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: callers hold `Isa::Avx2` or `Isa::Avx512` only when `Isa::available` found
        // this CPU runs it (`Isa::detect`), and both include AVX2.
        Isa::Avx2 | Isa::Avx512 => unsafe { x86::ray_columns8(rays) },
        Isa::Portable => ray_columns8_portable(rays),
    }
}

/// [`ray_columns8`] field by field.
#[inline(always)]
pub(crate) fn ray_columns8_portable(rays: &[Ray; 8]) -> RayColumns {
    let mut c = [[0.0; 8]; 11];
    for (i, r) in rays.iter().enumerate() {
        let (o, d, inv) = (r.origin, r.dir(), r.inv_dir());
        for a in 0..3 {
            c[a][i] = o[a];
            c[3 + a][i] = d[a];
            c[6 + a][i] = inv[a];
        }
        c[9][i] = r.t_min;
        c[10][i] = r.t_max;
    }
    c
}

/// Asks the CPU to bring cache line `line` of the rays `rays` (the one at byte `64 * line`)
/// into its caches, if the rays reach it; a hint only, which changes no value.
#[inline(always)]
pub(crate) fn prefetch_line(rays: &[Ray], line: usize) {
    let offset = line * 64;
    #[cfg(target_arch = "x86_64")]
    if offset < size_of_val(rays) {
        // SAFETY: the address lies inside `rays` (`offset` is less than its size in bytes); a
        // prefetch reads nothing a program sees and never faults.
        unsafe {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            _mm_prefetch::<_MM_HINT_T0>(rays.as_ptr().cast::<i8>().add(offset));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (rays, offset);
}

/// What [`fill_sealed`] finds over a bundle's lanes: whether every lane bundles in its octant,
/// and the bounds [`Bundle::lane_bounds`](crate::bundle::Bundle::lane_bounds) reports.
pub(crate) struct Sealed {
    pub good: bool,
    pub origin_lo: [f32; 3],
    pub origin_hi: [f32; 3],
    pub inv_lo: [f32; 3],
    pub inv_hi: [f32; 3],
    pub t_min_lo: f32,
}

/// Fills `b`'s lanes with `rays` (one to eight groups of eight), each lane's shear and the
/// lanes by dominant axis with them, and finds what [`Sealed`] holds, in one pass with AVX2;
/// `None` with the portable instructions, which make the same in passes of their own
/// (`Bundle::fill_sealed`).
#[inline(always)]
pub(crate) fn fill_sealed(
    isa: Isa,
    b: &mut crate::bundle::Bundle,
    rays: &[[Ray; 8]],
    octant: usize,
) -> Option<Sealed> {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512
            if !rays.is_empty()
                && rays.len() <= 8
                && std::arch::is_x86_feature_detected!("avx512vl") =>
        {
            // SAFETY: callers hold `Isa::Avx512` only when `Isa::available` found this CPU
            // runs AVX-512F and AVX2 (`Isa::detect`); AVX-512VL is checked just above.
            Some(unsafe { x86::fill_sealed_vl(b, rays, octant) })
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 | Isa::Avx512 if !rays.is_empty() && rays.len() <= 8 => {
            // SAFETY: callers hold `Isa::Avx2` or `Isa::Avx512` only when `Isa::available`
            // found this CPU runs it (`Isa::detect`), and both include AVX2.
            Some(unsafe { x86::fill_sealed(b, rays, octant) })
        }
        _ => {
            let _ = (b, rays, octant);
            None
        }
    }
}

/// Runs `f` compiled with AVX-512F where `isa` is [`Isa::Avx512`] (else as it is), so that
/// the sixteen-lane kernel inlines into the code `f` inlines.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn in_avx512<R>(isa: Isa, f: impl FnOnce() -> R) -> R {
    match isa {
        // SAFETY: `Lanes` holds `Isa::Avx512` only when `Isa::available` found this CPU runs
        // AVX-512F, AVX2 and FMA, which is all `x86::with_avx512` requires.
        Isa::Avx512 => unsafe { x86::with_avx512(f) },
        _ => f(),
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{Best16, Out8, Out16, RayColumns, Step8, Step16};
    use crate::Ray;
    use std::arch::x86_64::*;

    /// Calls `f` in a function compiled with AVX2 and FMA, where `f` and what it inlines are
    /// compiled with them too.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub(super) fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    /// Calls `f` in a function compiled with AVX-512F as well as AVX2 and FMA.
    #[target_feature(enable = "avx2,fma,avx512f")]
    #[inline]
    pub(super) fn with_avx512<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    /// [`ray_columns8_portable`](super::ray_columns8_portable) as an 8×8 transpose of the
    /// rays' first eight fields and a 4×8 one of their last four.
    // PERF: written field by field, filling a bundle with the rays of a camera's 8×8 tile was
    // the largest part of the time around a bundle walk; see `Bundle::fill`.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(super) fn ray_columns8(rays: &[Ray; 8]) -> RayColumns {
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

    /// [`fill_sealed`](super::fill_sealed) with AVX2: for each group of eight rays, the
    /// transpose of [`columns8`] stored into the bundle's lanes; the conditions of
    /// `Bundle::all_bundle_in` as vector comparisons (each false for NaN, as the scalar
    /// comparisons are); the running minima and maxima of `Bundle::seal`, with the same
    /// comparisons (`_mm256_min_ps(a, b)` is `if a < b { a } else { b }`) and the same final
    /// folds; and each lane's shear as `Bundle::shear_lanes` makes it, by the same comparisons,
    /// selects and two products.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(super) fn fill_sealed(
        b: &mut crate::bundle::Bundle,
        rays: &[[Ray; 8]],
        octant: usize,
    ) -> super::Sealed {
        use crate::bundle::{fold_hi, fold_lo, shear_orders};
        let order = shear_orders(octant);
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
        b.by_axis = [0; 3];
        for (g, eight) in rays.iter().enumerate() {
            let c = columns8(eight);
            let lanes = g * 8..g * 8 + 8;
            let store = |v: &mut [f32; crate::bundle::BUNDLE_LANES], x: __m256| {
                // SAFETY: `lanes` is eight lanes of an array of `BUNDLE_LANES` (`g` < 8, as
                // the caller checks); unaligned stores need no alignment.
                unsafe { _mm256_storeu_ps(v[lanes.clone()].as_mut_ptr(), x) }
            };
            for a in 0..3 {
                store(&mut b.origin[a], c[a]);
                store(&mut b.dir[a], c[3 + a]);
                store(&mut b.inv_dir[a], c[6 + a]);
            }
            store(&mut b.t_min, c[9]);
            store(&mut b.t_max, c[10]);
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
        super::Sealed {
            good: bad == 0,
            origin_lo: [lows[0], lows[1], lows[2]],
            origin_hi: [highs[0], highs[1], highs[2]],
            inv_lo: [lows[3], lows[4], lows[5]],
            inv_hi: [highs[3], highs[4], highs[5]],
            t_min_lo: lows[6],
        }
    }

    /// [`fill_sealed`] compiled with AVX-512VL as well: the same AVX2 instructions, with
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
    pub(super) fn fill_sealed_vl(
        b: &mut crate::bundle::Bundle,
        rays: &[[Ray; 8]],
        octant: usize,
    ) -> super::Sealed {
        fill_sealed(b, rays, octant)
    }

    /// [`watertight8_portable`](crate::lanes::watertight8_portable) in AVX2: the same
    /// operations on eight lanes at once.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(super) fn watertight8(verts: &[f32; 9], input: &Step8) -> Out8 {
        // SAFETY: every load reads eight `f32` of an array of eight, and every store writes
        // eight into one; unaligned loads and stores need no alignment.
        unsafe {
            let load = |a: &[f32; 8]| _mm256_loadu_ps(a.as_ptr());
            let [ox, oy, oz] = input.origin.map(load);
            let [sx, sy, sz] = input.shear.map(load);
            let rel = |k: usize| {
                (
                    _mm256_sub_ps(_mm256_set1_ps(verts[k]), ox),
                    _mm256_sub_ps(_mm256_set1_ps(verts[k + 1]), oy),
                    _mm256_sub_ps(_mm256_set1_ps(verts[k + 2]), oz),
                )
            };
            let (ax, ay, az) = rel(0);
            let (bx, by, bz) = rel(3);
            let (cx, cy, cz) = rel(6);
            let shear = |x: __m256, s: __m256, z: __m256| _mm256_sub_ps(x, _mm256_mul_ps(s, z));
            let (ax, ay) = (shear(ax, sx, az), shear(ay, sy, az));
            let (bx, by) = (shear(bx, sx, bz), shear(by, sy, bz));
            let (cx, cy) = (shear(cx, sx, cz), shear(cy, sy, cz));
            let cross = |p: __m256, q: __m256, r: __m256, s: __m256| {
                _mm256_sub_ps(_mm256_mul_ps(p, q), _mm256_mul_ps(r, s))
            };
            let u = cross(cx, by, cy, bx);
            let v = cross(ax, cy, ay, cx);
            let w = cross(bx, ay, by, ax);
            let zero = _mm256_setzero_ps();
            let eq0 = |x| _mm256_cmp_ps::<_CMP_EQ_OQ>(x, zero);
            let lt0 = |x| _mm256_cmp_ps::<_CMP_LT_OQ>(x, zero);
            let gt0 = |x| _mm256_cmp_ps::<_CMP_GT_OQ>(x, zero);
            let any_zero = _mm256_or_ps(_mm256_or_ps(eq0(u), eq0(v)), eq0(w));
            let neg = _mm256_or_ps(_mm256_or_ps(lt0(u), lt0(v)), lt0(w));
            let pos = _mm256_or_ps(_mm256_or_ps(gt0(u), gt0(v)), gt0(w));
            let outside = _mm256_and_ps(neg, pos);
            // PERF: most lanes a triangle is tested against pass outside one of its edges;
            // when all the active ones do (and none needs the scalar test), the division and
            // the distance are skipped. The answer is the same: those lanes are not inside
            // either way, and the caller reads no lane outside `active`. Bunny primary rays in
            // 8×8 tiles, one thread, two alternating runs of 3 passes: the uniform grid's
            // bundles 5.26 and 5.31 Mrays/s without, 5.40 and 5.44 with; the hierarchical
            // grid's 4.09, 4.14 and 4.14, 4.19; the kd-tree's 11.26, 11.34 and 11.32, 11.54.
            let zero_bits = _mm256_movemask_ps(any_zero) as u8;
            let outside_bits = _mm256_movemask_ps(outside) as u8;
            if (!outside_bits | zero_bits) & input.active == 0 {
                return Out8::default();
            }
            let det = _mm256_add_ps(_mm256_add_ps(u, v), w);
            // Ordered not-equal: false for NaN, as `det != 0.0 && !det.is_nan()`.
            let det_ok = _mm256_cmp_ps::<_CMP_NEQ_OQ>(det, zero);
            let (az, bz, cz) = (
                _mm256_mul_ps(sz, az),
                _mm256_mul_ps(sz, bz),
                _mm256_mul_ps(sz, cz),
            );
            let inv = _mm256_div_ps(_mm256_set1_ps(1.0), det);
            let sum = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(u, az), _mm256_mul_ps(v, bz)),
                _mm256_mul_ps(w, cz),
            );
            let t = _mm256_mul_ps(sum, inv);
            let in_range = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(t, load(input.t_min)),
                _mm256_cmp_ps::<_CMP_LE_OQ>(t, load(input.t_max)),
            );
            let inside = _mm256_andnot_ps(outside, _mm256_and_ps(det_ok, in_range));
            let mut out = Out8 {
                inside: _mm256_movemask_ps(inside) as u8,
                zero: zero_bits,
                ..Out8::default()
            };
            _mm256_storeu_ps(out.t.as_mut_ptr(), t);
            _mm256_storeu_ps(out.u.as_mut_ptr(), _mm256_mul_ps(v, inv));
            _mm256_storeu_ps(out.v.as_mut_ptr(), _mm256_mul_ps(w, inv));
            out
        }
    }

    /// [`watertight8_portable`](crate::lanes::watertight8_portable) in AVX-512 over sixteen
    /// lanes: the same operations, in the same order, as the AVX2 kernel.
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub(super) fn watertight16(verts: &[f32; 9], input: &Step16) -> Out16 {
        // SAFETY: every load reads sixteen `f32` of an array of sixteen, and every store writes
        // sixteen into one; unaligned loads and stores need no alignment.
        unsafe {
            let load = |a: &[f32; 16]| _mm512_loadu_ps(a.as_ptr());
            let [ox, oy, oz] = input.origin.map(load);
            let [sx, sy, sz] = input.shear.map(load);
            let rel = |k: usize| {
                (
                    _mm512_sub_ps(_mm512_set1_ps(verts[k]), ox),
                    _mm512_sub_ps(_mm512_set1_ps(verts[k + 1]), oy),
                    _mm512_sub_ps(_mm512_set1_ps(verts[k + 2]), oz),
                )
            };
            let (ax, ay, az) = rel(0);
            let (bx, by, bz) = rel(3);
            let (cx, cy, cz) = rel(6);
            let shear = |x: __m512, s: __m512, z: __m512| _mm512_sub_ps(x, _mm512_mul_ps(s, z));
            let (ax, ay) = (shear(ax, sx, az), shear(ay, sy, az));
            let (bx, by) = (shear(bx, sx, bz), shear(by, sy, bz));
            let (cx, cy) = (shear(cx, sx, cz), shear(cy, sy, cz));
            let cross = |p: __m512, q: __m512, r: __m512, s: __m512| {
                _mm512_sub_ps(_mm512_mul_ps(p, q), _mm512_mul_ps(r, s))
            };
            let u = cross(cx, by, cy, bx);
            let v = cross(ax, cy, ay, cx);
            let w = cross(bx, ay, by, ax);
            let zero = _mm512_setzero_ps();
            let eq0 = |x| _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(x, zero);
            let lt0 = |x| _mm512_cmp_ps_mask::<_CMP_LT_OQ>(x, zero);
            let gt0 = |x| _mm512_cmp_ps_mask::<_CMP_GT_OQ>(x, zero);
            let zero_bits = eq0(u) | eq0(v) | eq0(w);
            // Some edge function below zero and some above, from their least and greatest: the
            // scalar test's `outside` on every lane where none is NaN; where one is, `det`
            // below is NaN and the lane is not inside either way.
            // PERF: six comparisons and their mask operations were the longest chain of the
            // kernel's profile. The wide BVH's bundles, close views, private harness, one
            // thread, medians of five alternating runs, Mrays/s: the sphereflake 38.8 -> 38.9,
            // the bunny 42.5 -> 43.0, the teapot 62.1 -> 63.3, the teapot in a stadium 70.4 ->
            // 70.9.
            let (lo, hi) = (
                _mm512_min_ps(_mm512_min_ps(u, v), w),
                _mm512_max_ps(_mm512_max_ps(u, v), w),
            );
            let outside = lt0(lo) & gt0(hi);
            // As in the AVX2 kernel: when every active lane passes outside an edge, no lane
            // the caller reads is inside, and the division is skipped.
            if (!outside | zero_bits) & input.active == 0 {
                return Out16::default();
            }
            let det = _mm512_add_ps(_mm512_add_ps(u, v), w);
            // Ordered not-equal: false for NaN, as `det != 0.0 && !det.is_nan()`.
            let det_ok = _mm512_cmp_ps_mask::<_CMP_NEQ_OQ>(det, zero);
            let (az, bz, cz) = (
                _mm512_mul_ps(sz, az),
                _mm512_mul_ps(sz, bz),
                _mm512_mul_ps(sz, cz),
            );
            let inv = _mm512_div_ps(_mm512_set1_ps(1.0), det);
            let sum = _mm512_add_ps(
                _mm512_add_ps(_mm512_mul_ps(u, az), _mm512_mul_ps(v, bz)),
                _mm512_mul_ps(w, cz),
            );
            let t = _mm512_mul_ps(sum, inv);
            let in_range = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(t, load(input.t_min))
                & _mm512_cmp_ps_mask::<_CMP_LE_OQ>(t, load(input.t_max));
            let mut out = Out16 {
                inside: !outside & det_ok & in_range,
                zero: zero_bits,
                ..Out16::default()
            };
            _mm512_storeu_ps(out.t.as_mut_ptr(), t);
            _mm512_storeu_ps(out.u.as_mut_ptr(), _mm512_mul_ps(v, inv));
            _mm512_storeu_ps(out.v.as_mut_ptr(), _mm512_mul_ps(w, inv));
            out
        }
    }

    /// [`keep16`](super::keep16): `Hit::beats` as two comparisons and a masked store of each
    /// of the four outputs.
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub(super) fn keep16(out: &Out16, id: u32, lanes: u16, best: Best16<'_>) -> u16 {
        // SAFETY: every load reads sixteen 32-bit values of an array of sixteen, and every
        // masked store writes at most sixteen into one; unaligned accesses need no alignment.
        unsafe {
            let t = _mm512_loadu_ps(out.t.as_ptr());
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
            _mm512_mask_storeu_ps(best.u.as_mut_ptr(), keep, _mm512_loadu_ps(out.u.as_ptr()));
            _mm512_mask_storeu_ps(best.v.as_mut_ptr(), keep, _mm512_loadu_ps(out.v.as_ptr()));
            keep
        }
    }
}

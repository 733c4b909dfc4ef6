//! The one run-time choice of instruction set: [`Isa`].

use crate::Simd;
use crate::vector::Portable;
#[cfg(target_arch = "x86_64")]
use crate::x86::{self, Avx2, Avx512, Sse2};

/// The instruction set the kernels run with, chosen once per CPU at run time
/// ([`Isa::detect`]): every kernel of every structure (a BVH's single-ray walk, a bundle's
/// leaf tests, the filling of bundles) takes it from here, so one value says what runs, and
/// `RT_ACCEL_PORTABLE=1` in the environment forces the portable kernels everywhere.
///
/// A value is a proof that this CPU runs the instruction set: the x86-64 variants carry the
/// proof made by detection ([`Avx2::detect`], [`Avx512::detect`]; every x86-64 CPU runs SSE2),
/// so the kernels choose by a `match`, with no detection per call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Plain arrays ([`Portable`]), whatever the compiler makes of them for the build's
    /// target: what every target without intrinsics here runs (aarch64, wasm32).
    Portable,
    /// SSE2 intrinsics, four lanes to a register: every x86-64 CPU.
    #[cfg(target_arch = "x86_64")]
    Sse2(Sse2),
    /// AVX2 and FMA (x86-64): eight lanes to a register.
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
    /// AVX-512F with AVX2 and FMA (x86-64): sixteen lanes to a register where a kernel has a
    /// sixteen-lane form (a bundle's leaf test), AVX2 elsewhere.
    #[cfg(target_arch = "x86_64")]
    Avx512(Avx512),
}

/// Work to run over the four- and eight-lane vectors of an instruction set, given as a value of
/// a type implementing both widths (a BVH's walk over eight child boxes and four-triangle
/// packs). [`Isa::wide`] calls [`run`](WithLanes::run) inside a frame compiled for the
/// instruction set, so an implementation marked `#[inline(always)]` compiles to its
/// instructions there.
pub trait WithLanes {
    /// What the work returns.
    type Out;
    /// Does the work with the lane operations of `s`.
    fn run<S: Simd<4> + Simd<8>>(self, s: S) -> Self::Out;
}

impl Isa {
    /// The best this CPU runs: AVX-512, else AVX2, else SSE2 on x86-64, else the portable
    /// kernels. `RT_ACCEL_PORTABLE=1` in the environment (read once) forces the portable ones:
    /// the one switch for every kernel of every structure.
    pub fn detect() -> Self {
        if portable_forced() {
            return Isa::Portable;
        }
        Self::detect_ignoring_env()
    }

    /// The best this CPU runs, whatever the environment says.
    pub fn detect_ignoring_env() -> Self {
        Self::avx512()
            .or_else(Self::avx2)
            .or_else(Self::sse2)
            .unwrap_or(Isa::Portable)
    }

    /// SSE2, on x86-64 (every CPU there runs it); `None` elsewhere.
    pub fn sse2() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        return Some(Isa::Sse2(Sse2));
        #[cfg(not(target_arch = "x86_64"))]
        None
    }

    /// AVX2 with FMA, when this CPU runs them.
    pub fn avx2() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        return Avx2::detect().map(Isa::Avx2);
        #[cfg(not(target_arch = "x86_64"))]
        None
    }

    /// AVX-512F with AVX2 and FMA, when this CPU runs them.
    pub fn avx512() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        return Avx512::detect().map(Isa::Avx512);
        #[cfg(not(target_arch = "x86_64"))]
        None
    }

    /// Every instruction set this CPU runs, the portable one first (for tests that compare
    /// them).
    pub fn all_available() -> Vec<Isa> {
        [
            Some(Isa::Portable),
            Self::sse2(),
            Self::avx2(),
            Self::avx512(),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// The instruction set's name in lower case: `portable`, `sse2`, `avx2` or `avx512`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Portable => "portable",
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2(_) => "sse2",
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(_) => "avx2",
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(_) => "avx512",
        }
    }

    /// The AVX2 proof of [`Isa::Avx2`] and [`Isa::Avx512`].
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn avx2_proof(self) -> Option<Avx2> {
        match self {
            Isa::Avx2(s) => Some(s),
            Isa::Avx512(s) => Some(s.avx2()),
            _ => None,
        }
    }

    /// Runs `w` with this instruction set's four- and eight-lane operations: AVX2 (for
    /// [`Isa::Avx2`] and [`Isa::Avx512`]) inside a function compiled with AVX2 and FMA, SSE2,
    /// or [`Portable`].
    #[inline(always)]
    pub fn wide<W: WithLanes>(self, w: W) -> W::Out {
        match self {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(s) => x86::run_wide_avx2(s, w),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(s) => x86::run_wide_avx512(s, w),
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2(s) => run_apart(s, w),
            Isa::Portable => run_apart(Portable, w),
        }
    }

    /// [`Isa::wide`], but with [`Isa::Avx512`] in the AVX2 frame (AVX2 and FMA only): for
    /// walks that measured slower in the AVX-512 frame (the bundle walks; see [`Isa::run`]).
    #[inline(always)]
    pub fn wide_avx2_frame<W: WithLanes>(self, w: W) -> W::Out {
        match self {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(s) => x86::run_wide_avx2(s.avx2(), w),
            _ => self.wide(w),
        }
    }

    /// Runs `f` compiled for this instruction set where the CPU has it (else as the build's
    /// target has it): with [`Isa::Avx2`] or [`Isa::Avx512`], inside a function compiled with
    /// AVX2 and FMA enabled, so that the code `f` inlines (a bundle walk's loops over eight
    /// lanes, the eight-lane kernels) is vectorised with them, eight lanes to a register and
    /// with mask moves, instead of the baseline's four-lane SSE2. The sixteen-lane AVX-512
    /// kernels are entered from there in a frame of their own.
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
        #[cfg(target_arch = "x86_64")]
        if let Some(s) = self.avx2_proof() {
            return x86::run_avx2(s, f);
        }
        f()
    }
}

/// Runs `w` with `s` in a function of its own, as the AVX2 and AVX-512 frames are: inlined
/// into [`Isa::wide`]'s caller, a walk's fixed stack would make that caller's frame large
/// enough to need a stack probe on every call, whichever instruction set runs.
// PERF: rt-bvh's single rays with AVX-512, Intel Emerald Rapids, private harness, three
// alternating runs, Mrays/s: woody's shadow rays (all miss) 83.07 79.27 82.87 -> 98.47 98.70
// 101.20, the bunny's 6.86 6.83 6.84 -> 6.91 6.91 6.89, random soup's 5.10 5.14 5.15 -> 5.19
// 5.23 5.22; primary and incoherent rays within ±1% (five alternating runs).
#[inline(never)]
fn run_apart<S: Simd<4> + Simd<8>, W: WithLanes>(s: S, w: W) -> W::Out {
    w.run(s)
}

/// Whether the environment asks for the portable kernels (`RT_ACCEL_PORTABLE=1`), read once.
fn portable_forced() -> bool {
    static FORCED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FORCED.get_or_init(|| std::env::var_os("RT_ACCEL_PORTABLE").is_some_and(|v| v == "1"))
}

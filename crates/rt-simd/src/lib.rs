//! The SIMD layer of rt-accel: one run-time choice of instruction set ([`Isa`]), lane vectors of
//! any width ([`Simd<N>`]), the kernels every structure's hot loops share, written once over the
//! lane width, and ray bundles for the structures' packet walks ([`bundle`]).
//!
//! - **One instruction set per CPU.** [`Isa::detect`] picks AVX-512, AVX2, SSE2 or the
//!   portable kernels at run time (no `RUSTFLAGS` needed); `RT_ACCEL_PORTABLE=1` forces the
//!   portable ones for every kernel of every structure. A value of [`Isa`] proves its CPU
//!   support, so kernels choose by a `match`.
//! - **Lane vectors.** [`Simd<N>`] is every operation a kernel uses on `N` lanes of `f32`;
//!   [`Portable`] implements it on arrays for any width and target, and on x86-64 [`Sse2`],
//!   [`Avx2`] and [`Avx512`] with intrinsics (the crate's only `unsafe`, in `x86.rs`).
//! - **Kernels written once.** [`watertight`](watertight()) is the watertight ray–triangle
//!   test over `N` lanes: a BVH tests four triangles against one ray with it, a bundle's leaf
//!   tests one triangle against eight or sixteen rays. [`moller_trumbore`](moller_trumbore())
//!   and [`slab`](slab()) are the Möller–Trumbore test and the slab test of `N` boxes. Each lane
//!   performs the scalar function's operations in its order (no fused multiply-add, the same
//!   comparisons), so every instruction set answers with the scalar function's bits.
//! - **Bundles.** [`Bundle`], [`Lanes`] and [`walk_groups`](bundle::walk_groups): up to 64
//!   rays of one direction octant in structure-of-arrays form, the leaf tests of many lanes at
//!   once, and the frame every structure's bundle queries share. [`BundledBruteForce`] is the
//!   reference that answers bundles fast.
//!
//! ```
//! use rt_simd::{Isa, Portable, Simd, watertight};
//! // One ray along +z from the origin against four triangles at z = 1, lane by lane.
//! let s = Portable;
//! let row = |v: [f32; 4]| Simd::<4>::load(s, &v);
//! let verts = [
//!     [row([-1.0, 5.0, -1.0, f32::NAN]), row([-1.0; 4]), row([1.0; 4])],
//!     [row([1.0, 6.0, 1.0, f32::NAN]), row([-1.0; 4]), row([1.0; 4])],
//!     [row([0.0, 5.5, 0.0, f32::NAN]), row([1.0; 4]), row([1.0; 4])],
//! ];
//! let zero = Simd::<4>::splat(s, 0.0);
//! let shear = [zero, zero, Simd::<4>::splat(s, 1.0)]; // `Shear::new(Vec3::Z)`'s factors
//! let hits = watertight(s, verts, [zero; 3], shear, zero, Simd::<4>::splat(s, 10.0), 0b1111);
//! assert_eq!(hits.mask, 0b0101); // the first and third; the second lies aside, the fourth is unused
//! assert_eq!(Simd::<4>::store(s, hits.t)[0], 1.0);
//! assert!(Isa::all_available().contains(&Isa::detect_ignoring_env()));
//! ```
#![warn(missing_docs)]

pub mod bundle;
mod columns;
mod isa;
mod moller;
mod slab;
mod vector;
mod watertight;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use bundle::{BUNDLE_LANES, Bundle, BundledBruteForce, LaneBounds, Lanes};
pub use isa::{Isa, WithLanes};
pub use moller::moller_trumbore;
pub use slab::{SlabRay, slab, slab_lanes};
pub use vector::{Portable, Simd};
pub use watertight::{Hits, watertight};
#[cfg(target_arch = "x86_64")]
pub use x86::{Avx2, Avx512, Sse2};

/// Asks the CPU to bring cache lines `first .. first + lines` of `v` (the 64 bytes at byte
/// `64 * line` of its memory, for each `line`) into its caches, those inside `v`: a hint,
/// which changes no value. It lets a walk start the memory reads of the nodes it will visit
/// next while it works on the current one. On CPUs other than x86-64 it does nothing.
///
/// ```
/// let nodes = vec![0u8; 100];
/// // Lines 0 and 1 hold bytes of `nodes`; lines 2 and 3 would lie past its end and are skipped.
/// rt_simd::prefetch(&nodes, 0, 4);
/// rt_simd::prefetch::<u8>(&[], 0, 1);
/// rt_simd::prefetch(&nodes, usize::MAX, usize::MAX); // nothing there, and no overflow
/// ```
#[inline(always)]
pub fn prefetch<T>(v: &[T], first: usize, lines: usize) {
    #[cfg(target_arch = "x86_64")]
    x86::prefetch_lines(v, first, lines);
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (v, first, lines);
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

// With `share-dyn`, debug and test builds of the crates that use a `BundledBruteForce` as a trait
// object (the shootout, the renderer's tests) link this crate's copy of its methods instead of
// compiling their own.
#[cfg(feature = "share-dyn")]
rt_core::share_dyn_accel!(BundledBruteForce);

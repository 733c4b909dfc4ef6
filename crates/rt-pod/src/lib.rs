//! Plain-old-data structs without a derive macro: [`pod_struct!`](crate::pod_struct), the
//! field trait it checks with, and the one cast of flat `f32` buffers to `Vec3`s. rt-core
//! re-exports the macro (`rt_core::pod_struct!`) and bytemuck.
//!
//! This is one of the few places with `unsafe` code (each block says why it is sound): bytemuck's
//! own route to these impls is a procedural macro, which every user of a structure would compile,
//! and glam's `bytemuck` feature enables that macro too.
#![allow(unsafe_code)]
#![warn(missing_docs)]

/// Re-exported so that [`pod_struct!`]'s expansion names the bytemuck this crate implements.
pub use bytemuck;

use glam::Vec3;

/// A type whose every bit pattern is a valid value and which has no padding: what a
/// [`pod_struct!`](crate::pod_struct)'s fields must be. Implemented for the plain numbers, arrays
/// of such types, glam's `Vec3`, and every `pod_struct!`.
///
/// # Safety
/// Implement it only for `Copy + 'static` types with no padding bytes, no pointers, and no
/// invalid bit patterns (the conditions of [`bytemuck::Pod`]). Only this module and the macro
/// do.
pub unsafe trait PodField: Copy + 'static {}

macro_rules! pod_fields {
    ($($t:ty),*) => {
        // SAFETY: the plain integer and float types have no padding and no invalid values.
        $(unsafe impl PodField for $t {})*
    };
}
pod_fields!(u8, u16, u32, u64, i8, i16, i32, i64, f32, f64);

// SAFETY: an array of `N` fields without padding or invalid values has neither: arrays add no
// padding between elements whose size is a multiple of their alignment, which holds for every type.
unsafe impl<T: PodField, const N: usize> PodField for [T; N] {}

// glam declares `Vec3` as `#[repr(C)] struct Vec3 { x: f32, y: f32, z: f32 }`; these assertions
// check that the build agrees (no SIMD layout, no padding), which `PodField` and `vec3s` rely on.
const _: () = assert!(size_of::<Vec3>() == 12 && align_of::<Vec3>() == align_of::<f32>());

// SAFETY: `Vec3` is three `f32`s in `repr(C)` with no padding (asserted just above): every bit
// pattern is a valid value.
unsafe impl PodField for Vec3 {}

/// The flat buffer `x0 y0 z0 x1 y1 z1 …` as `Vec3`s; a trailing partial vertex is left out.
pub fn vec3s(flat: &[f32]) -> &[Vec3] {
    // SAFETY: `Vec3` is three `f32`s with the alignment of `f32` and no padding (asserted above),
    // so the pointer of an `f32` slice is aligned for `Vec3`, each run of three `f32`s is a valid
    // `Vec3`, and `len / 3` of them lie within the slice, for the slice's lifetime.
    unsafe { std::slice::from_raw_parts(flat.as_ptr().cast::<Vec3>(), flat.len() / 3) }
}

/// Declares a `#[repr(C)]` struct (named fields, or a tuple struct) and implements
/// [`bytemuck::Zeroable`] and [`bytemuck::Pod`] for it after checking at compile time that every
/// field is `Pod` and that the struct has no padding. Further `repr` hints (`#[repr(align(64))]`)
/// may be given among the struct's attributes.
///
/// Nodes, triangle packs and primitives are [`bytemuck::Pod`], so that a structure's arrays can
/// be viewed as bytes (to save them, hash them, or hand them to a GPU) without copying. The usual
/// way is bytemuck's `derive` feature, but that is a procedural macro: `bytemuck_derive` brings
/// `syn`, `quote`, `proc-macro2` and `unicode-ident` into every program that depends on a
/// structure: five of the nine crates a user of `rt-bvh` would otherwise compile. This macro
/// makes the same checks the derive makes, at compile time, for the plain structs this workspace
/// needs (glam's `bytemuck` feature would bring the derive back, so `Vec3` fields are checked
/// through this crate's own field trait):
///
/// - the struct is `#[repr(C)]` (the macro adds the attribute itself, so it cannot be missing);
/// - every field's type is plain old data: a number, an array of such, a `Vec3`, or another
///   `pod_struct!`;
/// - the fields fill the struct exactly: no padding between them or after them;
/// - the struct is not generic (the macro's grammar has no place for parameters).
///
/// A struct that breaks a rule does not compile:
///
/// ```compile_fail
/// rt_pod::pod_struct! {
///     #[derive(Clone, Copy)]
///     pub struct Padded { pub flag: u8, pub count: u32 } // three bytes of padding after `flag`
/// }
/// ```
///
/// ```compile_fail
/// rt_pod::pod_struct! {
///     #[derive(Clone, Copy)]
///     pub struct Flagged { pub flag: bool, pub more: [bool; 3] } // a `bool` is not `Pod`
/// }
/// ```
///
/// ```
/// rt_pod::pod_struct! {
///     /// Two counts, eight bytes.
///     #[derive(Clone, Copy, Debug, PartialEq)]
///     pub struct Counts { pub first: u32, pub count: u32 }
/// }
/// let counts = [Counts { first: 1, count: 2 }];
/// let bytes: &[u8] = rt_pod::bytemuck::cast_slice(&counts);
/// assert_eq!(bytes.len(), 8);
/// ```
#[macro_export]
macro_rules! pod_struct {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $($(#[$field_meta:meta])* $field_vis:vis $field:ident : $field_ty:ty),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        $vis struct $name {
            $($(#[$field_meta])* $field_vis $field: $field_ty),*
        }
        $crate::pod_struct!(@impl $name; $($field_ty),*);
    };
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident ( $($(#[$field_meta:meta])* $field_vis:vis $field_ty:ty),* $(,)? );
    ) => {
        $(#[$meta])*
        #[repr(C)]
        $vis struct $name ( $($(#[$field_meta])* $field_vis $field_ty),* );
        $crate::pod_struct!(@impl $name; $($field_ty),*);
    };
    (@impl $name:ident; $($field_ty:ty),*) => {
        const _: () = {
            const fn field_is_pod<T: $crate::PodField>() {}
            $(field_is_pod::<$field_ty>();)*
            assert!(
                ::core::mem::size_of::<$name>() == 0 $(+ ::core::mem::size_of::<$field_ty>())*,
                "a pod_struct! has padding between or after its fields"
            );
        };
        // SAFETY: the struct is `repr(C)` (the macro adds the attribute), not generic (the
        // macro's grammar takes no parameters), every field is plain old data (`PodField`)
        // and the fields' sizes add
        // up to the struct's size, so there is no padding: both are checked at compile time just
        // above. Those are the conditions bytemuck's documentation sets for `Pod` (and its
        // derive checks); `Copy + 'static` are required by the trait itself.
        #[allow(unsafe_code)]
        unsafe impl $crate::bytemuck::Zeroable for $name {}
        // SAFETY: as for `Zeroable` just above.
        #[allow(unsafe_code)]
        unsafe impl $crate::bytemuck::Pod for $name {}
        // SAFETY: as for `Zeroable` just above: `Pod` is exactly what the field trait asks for.
        #[allow(unsafe_code)]
        unsafe impl $crate::PodField for $name {}
    };
}

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

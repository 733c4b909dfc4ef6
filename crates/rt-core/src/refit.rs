//! Structures that follow moving primitives by updating their boxes instead of rebuilding.

use crate::{Accel, Geometry};
use std::fmt;

/// Why a structure could not be refitted to moved primitives; the structure is left as it was,
/// and a rebuild ([`Accel::build_from`]) is the way on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RefitError {
    /// The geometry has another number of primitives than the structure was built over.
    CountChanged {
        /// Primitives at the build.
        built: usize,
        /// Primitives now.
        now: usize,
    },
    /// A primitive became invalid ([`Primitive::is_valid`](crate::Primitive::is_valid)), or
    /// an invalid one, which the structure left out, became valid.
    ValidityChanged {
        /// Its index.
        prim: u32,
    },
    /// A primitive the structure stores in a layout for its kind (a triangle in rt-bvh's SIMD
    /// packs) is no longer of that kind.
    KindChanged {
        /// Its index.
        prim: u32,
    },
    /// A bit-identical copy of a triangle, which the structure left out because only the copy
    /// with the smaller index can ever be hit, no longer equals it.
    CopiesDiverged {
        /// The copy left out.
        prim: u32,
        /// The copy kept.
        copy_of: u32,
    },
}

impl fmt::Display for RefitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RefitError::CountChanged { built, now } => write!(
                f,
                "built over {built} primitives but given {now}: rebuild instead of refitting"
            ),
            RefitError::ValidityChanged { prim } => write!(
                f,
                "primitive {prim} changed between valid and invalid: rebuild instead of refitting"
            ),
            RefitError::KindChanged { prim } => write!(
                f,
                "primitive {prim} is no longer of the kind its leaf stores: rebuild instead of \
                 refitting"
            ),
            RefitError::CopiesDiverged { prim, copy_of } => write!(
                f,
                "primitive {prim} was a copy of {copy_of} and is no longer: rebuild instead of \
                 refitting"
            ),
        }
    }
}

impl std::error::Error for RefitError {}

/// A structure that can follow its primitives when they move: the same tree, its boxes updated
/// bottom-up in `O(N)`, in place of an `O(N log N)` rebuild.
///
/// A refitted structure answers exactly like brute force over the moved primitives (the
/// conformance kit's `check_refit` proves it), but its tree was chosen for where the
/// primitives were: as they move apart its boxes grow and overlap and rays pay more. Comparing
/// a cost model of the refitted tree with a fresh build's tells when to rebuild (rt-bvh:
/// `Bvh::sah_cost`).
pub trait Refit: Accel {
    /// Moves the structure's primitives to `geometry`'s, which must number the same primitives
    /// in the same order, and updates every box.
    ///
    /// # Errors
    /// A [`RefitError`] when the primitives cannot be followed (another count, a primitive
    /// that changed validity or kind); the structure is then unchanged.
    fn refit<G: Geometry<Prim = Self::Prim> + ?Sized>(
        &mut self,
        geometry: &G,
    ) -> Result<(), RefitError>;
}

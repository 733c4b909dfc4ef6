//! The octree's node: a range of primitive references, or the index of a block of eight children.

rt_core::pod_struct! {
    /// One node, 8 bytes. A leaf lists `refs[first..first + count]`; an interior node's eight children
    /// are the [`Block`] `blocks[first]`.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct Node {
        /// First reference of a leaf; the children's block for an interior node.
        first: u32,
        /// Number of references, or [`Node::INTERIOR`].
        count: u32,
    }
}

const _: () = assert!(size_of::<Node>() == 8);

impl Node {
    /// The `count` field of an interior node.
    const INTERIOR: u32 = u32::MAX;

    /// A leaf listing `refs[first..first + count]`.
    pub(crate) fn leaf(first: usize, count: usize) -> Self {
        Self {
            first: u32::try_from(first).expect("at most 2^32 - 1 references"),
            count: u32::try_from(count)
                .ok()
                .filter(|&c| c != Self::INTERIOR)
                .expect("at most 2^32 - 2 references in a leaf"),
        }
    }

    /// An interior node whose children are `blocks[block]`.
    pub(crate) fn interior(block: usize) -> Self {
        Self {
            first: u32::try_from(block).expect("at most 2^32 - 1 blocks"),
            count: Self::INTERIOR,
        }
    }

    /// The node as it reads once its tree's blocks are moved `blocks` places on and its
    /// references `refs` places on (when a separately built subtree is appended).
    pub(crate) fn relocated(self, blocks: usize, refs: usize) -> Self {
        match self.children() {
            Some(block) => Self::interior(block + blocks),
            None => Self::leaf(self.first as usize + refs, self.count as usize),
        }
    }

    /// The index of the children's block, for an interior node.
    #[inline(always)]
    pub fn children(&self) -> Option<usize> {
        (self.count == Self::INTERIOR).then_some(self.first as usize)
    }

    /// The reference range of a leaf (empty for an interior node).
    #[inline(always)]
    pub fn references(&self) -> std::ops::Range<usize> {
        if self.count == Self::INTERIOR {
            0..0
        } else {
            self.first as usize..self.first as usize + self.count as usize
        }
    }

    /// Whether the node is a leaf holding no primitive.
    #[inline(always)]
    pub fn is_empty_leaf(&self) -> bool {
        self.count == 0
    }
}

rt_core::pod_struct! {
    /// The eight children of an interior node, in one 64-byte cache line. Child `i` covers the upper
    /// half of its parent on axis `a` exactly when bit `a` of `i` is set (x is bit 0, y bit 1, z bit
    /// 2).
    ///
    /// A block always holds all eight children, empty ones included: an empty leaf costs 8 bytes, and
    /// in exchange child `i` is simply `block.0[i]`, with no mask or popcount to decode, and the walk
    /// reads all eight in one cache line.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    #[repr(align(64))]
    pub struct Block(pub [Node; 8]);
}

const _: () = assert!(size_of::<Block>() == 64 && align_of::<Block>() == 64);

use rt_core::{Aabb, glam::Vec3};

/// Where a node's box is cut into eight: `lo / 2 + hi / 2` per axis, which cannot overflow and
/// lies in `[lo, hi]`. The builder and the traversal both cut with this function, so they agree
/// on every plane to the bit.
#[inline(always)]
pub(crate) fn midpoint(b: &Aabb) -> Vec3 {
    b.min * 0.5 + b.max * 0.5
}

/// The box of child `i` of a node with box `b` cut at `mid`.
#[inline(always)]
pub(crate) fn child_box(b: &Aabb, mid: Vec3, i: usize) -> Aabb {
    let upper = rt_core::glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0);
    Aabb::new(
        Vec3::select(upper, mid, b.min),
        Vec3::select(upper, b.max, mid),
    )
}

/// The octree's root box: the cube centred on the scene box `b` whose side is `b`'s longest
/// extent, widened where rounding requires so that it contains `b`, and kept finite.
pub(crate) fn root_box(b: &Aabb) -> Aabb {
    let centre = b.min * 0.5 + b.max * 0.5;
    let half = Vec3::splat((b.max * 0.5 - b.min * 0.5).max_element());
    let limit = Vec3::splat(f32::MAX);
    Aabb::new(
        (centre - half).min(b.min).max(-limit),
        (centre + half).max(b.max).min(limit),
    )
}

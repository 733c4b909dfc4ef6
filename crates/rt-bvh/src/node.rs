//! The flattened node layout.

use rt_core::Aabb;

/// One node of the flattened tree: 32 bytes, two per 64-byte cache line.
///
/// Nodes are stored depth first: an interior node's first (left) child is the next node in the
/// array, so only the second (right) child's index is stored. A leaf holds a contiguous range of
/// the reordered primitive array.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node {
    /// The box around everything below this node.
    pub bounds: Aabb,
    /// Leaf: index of the first primitive. Interior: index of the second child.
    pub index: u32,
    /// Leaf: number of primitives (at least 1). Interior: 0.
    pub count: u16,
    /// Interior: the axis (0, 1, 2) the children were split along. Leaf: 0.
    pub axis: u8,
    /// Always 0; keeps the layout free of implicit padding.
    pub pad: u8,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    /// Whether this node is a leaf.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// The primitive range of a leaf (empty for an interior node).
    #[inline(always)]
    pub fn prim_range(&self) -> std::ops::Range<usize> {
        self.index as usize..self.index as usize + self.count as usize
    }
}

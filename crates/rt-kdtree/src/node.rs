//! The 8-byte node.

rt_core::pod_struct! {
    /// One kd-tree node: 8 bytes, no bounding box.
    ///
    /// - `word`: an interior node's split position (`f32` bits), or a leaf's reference count.
    /// - `packed`: the low two bits are the split axis (0, 1, 2) or 3 for a leaf; the upper 30 bits
    ///   are an interior node's first child index (the second child is the next node: children are
    ///   stored side by side) or a leaf's first index into the reference list.
    ///
    /// So a tree holds at most 2³⁰ nodes and 2³⁰ references.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct Node {
        word: u32,
        packed: u32,
    }
}

const _: () = assert!(size_of::<Node>() == 8);

const LEAF: u32 = 3;

/// The largest child or reference index a node can store.
pub(crate) const MAX_INDEX: usize = (1 << 30) - 1;

impl Node {
    /// An interior node splitting `axis` at `split`, whose children are nodes `first_child` and
    /// `first_child + 1`.
    #[inline]
    pub(crate) fn interior(axis: usize, split: f32, first_child: usize) -> Self {
        debug_assert!(axis < 3 && first_child <= MAX_INDEX);
        Self {
            word: split.to_bits(),
            packed: ((first_child as u32) << 2) | axis as u32,
        }
    }

    /// A leaf holding references `first..first + count` of the reference list.
    #[inline]
    pub(crate) fn leaf(first: usize, count: usize) -> Self {
        debug_assert!(first <= MAX_INDEX && count <= u32::MAX as usize);
        Self {
            word: count as u32,
            packed: ((first as u32) << 2) | LEAF,
        }
    }

    /// Whether this node is a leaf.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.packed & 3 == LEAF
    }

    /// An interior node's split axis (0 = x, 1 = y, 2 = z); 3 for a leaf.
    #[inline(always)]
    pub fn axis(&self) -> usize {
        (self.packed & 3) as usize
    }

    /// An interior node's split position. Meaningless for a leaf.
    #[inline(always)]
    pub fn split(&self) -> f32 {
        f32::from_bits(self.word)
    }

    /// An interior node's first child (the second is the next node), or a leaf's first reference.
    #[inline(always)]
    pub fn index(&self) -> usize {
        (self.packed >> 2) as usize
    }

    /// A leaf's reference count. Meaningless for an interior node.
    #[inline(always)]
    pub fn count(&self) -> usize {
        self.word as usize
    }

    /// Shifts the child or reference index, when a subtree built separately is appended.
    #[inline]
    pub(crate) fn relocated(self, node_shift: usize, ref_shift: usize) -> Self {
        let shift = if self.is_leaf() {
            ref_shift
        } else {
            node_shift
        };
        let index = self.index() + shift;
        debug_assert!(index <= MAX_INDEX);
        Self {
            word: self.word,
            packed: ((index as u32) << 2) | (self.packed & 3),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_round_trip() {
        let n = Node::interior(2, -1.5, 12345);
        assert!(!n.is_leaf());
        assert_eq!((n.axis(), n.split(), n.index()), (2, -1.5, 12345));
        let l = Node::leaf(MAX_INDEX, 7);
        assert!(l.is_leaf());
        assert_eq!((l.index(), l.count()), (MAX_INDEX, 7));
        assert_eq!(l.relocated(100, 0).index(), MAX_INDEX);
        assert_eq!(n.relocated(10, 1000).index(), 12355);
        assert_eq!(Node::leaf(5, 1).relocated(10, 1000).index(), 1005);
    }
}

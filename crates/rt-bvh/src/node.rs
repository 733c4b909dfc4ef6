//! The flattened node layouts: the binary [`Node`], the 8-wide [`WideNode`] and the triangle
//! [`TriPack`] its leaves point to.

use rt_core::glam::Vec3;
use rt_core::{Aabb, Triangle, TriangleTest};

rt_core::pod_struct! {
    /// One node of the flattened binary tree: 32 bytes, two per 64-byte cache line.
    ///
    /// Nodes are stored depth first: an interior node's first (left) child is the next node in the
    /// array, so only the second (right) child's index is stored. A leaf holds a contiguous range of
    /// the reordered primitive array.
    #[derive(Clone, Copy, Debug, PartialEq)]
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

/// Children of one [`WideNode`].
pub const WIDTH: usize = 8;

rt_core::pod_struct! {
    /// One node of the 8-wide tree: the boxes of up to eight children as structure of arrays, so
    /// one SIMD slab test covers all of them, and a reference to each child. 256 bytes, four cache
    /// lines, aligned to a line (224 of them used).
    ///
    /// Unused lanes hold the empty box (`min = +inf`, `max = -inf`), which no valid ray enters, and
    /// [`ChildRef::EMPTY`]; used lanes come first.
    #[derive(Clone, Copy, Debug, PartialEq)]
    #[repr(align(64))]
    pub struct WideNode {
        /// Six rows of eight lanes: the children's minimum x, y, z, then maximum x, y, z.
        pub bounds: [[f32; WIDTH]; 6],
        /// Each child's [`ChildRef`], as its raw `u32`.
        pub children: [u32; WIDTH],
        /// Always 0. PERF: it makes a node four whole cache lines; packed to 224 bytes (aligned to
        /// 32) the bunny's primary and shadow rays traced 2-3% slower, incoherent rays 1% faster
        /// (three interleaved runs each, single-threaded).
        pub pad: [u32; WIDTH],
    }
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 256);

impl WideNode {
    /// A node with no children.
    pub const EMPTY: Self = Self {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        children: [ChildRef::EMPTY.0; WIDTH],
        pad: [0; WIDTH],
    };

    /// Child `i`'s box.
    pub fn child_bounds(&self, i: usize) -> Aabb {
        let b = &self.bounds;
        Aabb::new(
            [b[0][i], b[1][i], b[2][i]].into(),
            [b[3][i], b[4][i], b[5][i]].into(),
        )
    }

    /// Child `i`'s reference.
    #[inline(always)]
    pub fn child(&self, i: usize) -> ChildRef {
        ChildRef(self.children[i])
    }
}

/// A reference to a child of a [`WideNode`]: another node, a leaf (a range of at most eight
/// items: triangle packs or primitives), or nothing.
///
/// Encoding: bit 31 clear, a node index; bit 31 set, a leaf, with the item count minus one in
/// bits 28..31 and the first item in bits 0..28. `u32::MAX` is no child.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChildRef(pub u32);

impl ChildRef {
    /// No child.
    pub const EMPTY: Self = Self(u32::MAX);
    const LEAF: u32 = 1 << 31;
    /// The most items one leaf may hold.
    pub const MAX_LEAF_ITEMS: usize = 8;
    /// Leaf items are indexed with 28 bits.
    pub const MAX_ITEMS: usize = 1 << 28;

    /// A reference to node `index` (below 2³¹).
    #[inline(always)]
    pub fn node(index: u32) -> Self {
        debug_assert!(index < Self::LEAF);
        Self(index)
    }

    /// A leaf of `count` items (1 to 8) from `first` (below 2²⁸).
    #[inline(always)]
    pub fn leaf(first: u32, count: u32) -> Self {
        debug_assert!((1..=8).contains(&count) && (first as usize) < Self::MAX_ITEMS);
        Self(Self::LEAF | (count - 1) << 28 | first)
    }

    /// Whether this is a leaf (or [`ChildRef::EMPTY`]).
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.0 & Self::LEAF != 0
    }

    /// The node index of an interior reference.
    #[inline(always)]
    pub fn index(self) -> usize {
        self.0 as usize
    }

    /// The item range of a leaf.
    #[inline(always)]
    pub fn items(self) -> std::ops::Range<usize> {
        let first = (self.0 & (Self::MAX_ITEMS as u32 - 1)) as usize;
        let count = ((self.0 >> 28) & 7) as usize + 1;
        first..first + count
    }
}

/// Triangles per [`TriPack`].
pub const PACK: usize = 4;

rt_core::pod_struct! {
    /// Four triangles pre-processed for a SIMD ray–triangle test, as structure of arrays: 160
    /// bytes, 40 per triangle.
    ///
    /// For the watertight test the nine rows are the vertices `v0`, `v1`, `v2` (x, y, z each); for
    /// Möller–Trumbore they are `v0`, `e1 = v1 - v0` and `e2 = v2 - v0`, computed once at build
    /// time exactly as the scalar test computes them per ray. Unused lanes hold NaN coordinates,
    /// which every test rejects, and the id `u32::MAX`.
    #[derive(Clone, Copy, Debug, PartialEq)]
    #[repr(align(16))]
    pub struct TriPack {
        /// Nine rows of four lanes (see the type's documentation).
        pub rows: [[f32; PACK]; 9],
        /// Each lane's triangle index in the build input; `u32::MAX` in unused lanes.
        pub ids: [u32; PACK],
    }
}

const _: () = assert!(std::mem::size_of::<TriPack>() == 160);

impl TriPack {
    /// Row triple `k` (0, 1 or 2) of `lane` as a vector: vertex `k` of a watertight pack; the
    /// first vertex, then the two edges, of a Möller–Trumbore pack.
    #[inline(always)]
    pub fn row(&self, k: usize, lane: usize) -> Vec3 {
        Vec3::new(
            self.rows[3 * k][lane],
            self.rows[3 * k + 1][lane],
            self.rows[3 * k + 2][lane],
        )
    }

    /// A pack of up to four `(triangle, input index)` pairs for `test`.
    pub fn new(tris: &[(Triangle, u32)], test: TriangleTest) -> Self {
        debug_assert!(tris.len() <= PACK);
        let mut p = Self {
            rows: [[f32::NAN; PACK]; 9],
            ids: [u32::MAX; PACK],
        };
        for (lane, &(t, id)) in tris.iter().enumerate() {
            let rows = match test {
                TriangleTest::Watertight => [t.v0, t.v1, t.v2],
                TriangleTest::MollerTrumbore => [t.v0, t.v1 - t.v0, t.v2 - t.v0],
            };
            for (v, row) in rows.iter().enumerate() {
                for axis in 0..3 {
                    p.rows[3 * v + axis][lane] = row[axis];
                }
            }
            p.ids[lane] = id;
        }
        p
    }

    /// Lanes holding a triangle.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.ids.iter().filter(|&&id| id != u32::MAX).count()
    }

    /// Whether no lane holds a triangle (never true of a built tree's packs).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The triangle in `lane`, as given to [`TriPack::new`] (for Möller–Trumbore, `v1` and `v2`
    /// are rebuilt as `v0 + e1`, `v0 + e2`, which may differ from the input by rounding).
    pub fn triangle(&self, lane: usize, test: TriangleTest) -> Triangle {
        let v = |k: usize| {
            rt_core::glam::Vec3::new(
                self.rows[3 * k][lane],
                self.rows[3 * k + 1][lane],
                self.rows[3 * k + 2][lane],
            )
        };
        match test {
            TriangleTest::Watertight => Triangle::new(v(0), v(1), v(2)),
            TriangleTest::MollerTrumbore => Triangle::new(v(0), v(0) + v(1), v(0) + v(2)),
        }
    }
}

//! Box queries (box overlap): every subtree whose box meets the query box, in any order.

use crate::node::{ChildRef, WIDTH, WideNode};
use crate::traverse::WIDE_STACK;
use crate::{Bvh, Layout, MAX_DEPTH};
use rt_core::glam::Vec3;
use rt_core::{Aabb, BoxQuery, PrimHit, Primitive, RayQuery, Stack, Stats, TriangleTest};
use std::ops::ControlFlow;

impl<P: Primitive> Bvh<P> {
    /// The box query of either layout.
    pub(crate) fn box_walk<Q: BoxQuery<P>, S: Stats>(
        &self,
        q: &mut Q,
        stats: &mut S,
    ) -> ControlFlow<()> {
        match self.layout() {
            Layout::Binary => self.box_binary(q, stats),
            Layout::Wide => self.box_wide(q, stats),
        }
    }

    /// The binary tree's box query: depth first, both children of a node kept when their boxes
    /// meet the query box. No order helps a query that wants every primitive in the box, so the
    /// left child is visited first. One stack entry per level.
    pub(crate) fn box_binary<Q: BoxQuery<P>, S: Stats>(
        &self,
        q: &mut Q,
        stats: &mut S,
    ) -> ControlFlow<()> {
        let (nodes, b) = (self.nodes(), q.bounds());
        if self.primitive_ids().is_empty() || b.is_empty() || !nodes[0].bounds.overlaps(&b) {
            return ControlFlow::Continue(());
        }
        let mut stack = Stack::<u32, MAX_DEPTH>::new();
        let mut current = 0usize;
        loop {
            stats.node_visit();
            let node = &nodes[current];
            if node.is_leaf() {
                let range = node.prim_range();
                for (prim, id) in self.leaf_prims(range) {
                    stats.prim_test();
                    q.test(prim, id)?;
                }
            } else {
                let (a, c) = (current + 1, node.index as usize);
                match (nodes[a].bounds.overlaps(&b), nodes[c].bounds.overlaps(&b)) {
                    (true, meets) => {
                        if meets {
                            stack.push(c as u32);
                        }
                        current = a;
                        continue;
                    }
                    (false, true) => {
                        current = c;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            let Some(next) = stack.pop() else {
                return ControlFlow::Continue(());
            };
            current = next as usize;
        }
    }

    /// The wide tree's box query: the children of a node whose boxes meet the query box are
    /// pushed in lane order (the first visited next). Triangle packs are offered lane by lane
    /// as the triangles they store.
    pub(crate) fn box_wide<Q: BoxQuery<P>, S: Stats>(
        &self,
        q: &mut Q,
        stats: &mut S,
    ) -> ControlFlow<()> {
        let (nodes, b) = (self.wide_nodes(), q.bounds());
        if nodes.is_empty() || b.is_empty() {
            return ControlFlow::Continue(());
        }
        let mut stack = Stack::<u32, WIDE_STACK>::new();
        let mut current = ChildRef::node(0);
        loop {
            stats.node_visit();
            if current.is_leaf() {
                self.offer_leaf_box(current.items(), q, stats)?;
            } else {
                let node = &nodes[current.index()];
                let meets = meeting(node, &b);
                if meets != 0 {
                    // The lowest lane next, the others pushed highest first (at most seven a
                    // level, as the ray walks push, which the stack is sized for).
                    let first = meets.trailing_zeros() as usize;
                    for i in (first + 1..WIDTH).rev() {
                        if meets & 1 << i != 0 {
                            stack.push(node.children[i]);
                        }
                    }
                    current = ChildRef(node.children[first]);
                    continue;
                }
            }
            let Some(next) = stack.pop() else {
                return ControlFlow::Continue(());
            };
            current = ChildRef(next);
        }
    }

    /// Offers a wide leaf's items: triangle packs by their vertices when the tree has them
    /// (Möller–Trumbore packs keep the first vertex and two edges, whose sums are the
    /// vertices `MtTriangle::edge_form` gives), else primitives.
    fn offer_leaf_box<Q: BoxQuery<P>, S: Stats>(
        &self,
        items: std::ops::Range<usize>,
        q: &mut Q,
        stats: &mut S,
    ) -> ControlFlow<()> {
        let Some(test) = self.pack_test().filter(|_| !self.packs().is_empty()) else {
            for (prim, id) in self.leaf_prims(items) {
                stats.prim_test();
                q.test(prim, id)?;
            }
            return ControlFlow::Continue(());
        };
        for pack in &self.packs()[items] {
            for lane in 0..pack.len() {
                stats.prim_test();
                let row = |k: usize| pack.row(k, lane);
                let v = match test {
                    TriangleTest::Watertight => [row(0), row(1), row(2)],
                    TriangleTest::MollerTrumbore => [row(0), row(0) + row(1), row(0) + row(2)],
                };
                q.test_triangle(v, pack.ids[lane])?;
            }
        }
        ControlFlow::Continue(())
    }
}

/// The lanes of `node` whose children's boxes meet `b`, as bits. Row by row over the lanes, so
/// the compiler can vectorize it.
#[inline(always)]
fn meeting(node: &WideNode, b: &Aabb) -> u32 {
    let rows = &node.bounds;
    let mut mask = 0;
    for (i, &child) in node.children.iter().enumerate() {
        let mut meets = child != ChildRef::EMPTY.0;
        for axis in 0..3 {
            meets &= rows[axis][i] <= b.max[axis] && b.min[axis] <= rows[axis + 3][i];
        }
        mask |= u32::from(meets) << i;
    }
    mask
}

/// A box or ray query that is offered, after each stored triangle, its bit-identical copies,
/// which the tree leaves out (the lowest index of a set of copies is stored, which is all a
/// closest or any hit ever reports; filters and all hits want the copies too). Counts the
/// copies it offers, for the caller's statistics.
pub(crate) struct WithCopies<'a, Q> {
    query: &'a mut Q,
    /// `(stored, copy)` pairs, ascending.
    twins: &'a [(u32, u32)],
    offered: u64,
}

impl<'a, Q> WithCopies<'a, Q> {
    pub(crate) fn new(query: &'a mut Q, twins: &'a [(u32, u32)]) -> Self {
        Self {
            query,
            twins,
            offered: 0,
        }
    }

    /// How many copies were offered.
    pub(crate) fn offered(&self) -> u64 {
        self.offered
    }

    /// Offers each copy of `id` through `offer`.
    fn copies(
        &mut self,
        id: u32,
        mut offer: impl FnMut(&mut Q, u32) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        if self.twins.is_empty() {
            return ControlFlow::Continue(());
        }
        let start = self.twins.partition_point(|&(stored, _)| stored < id);
        for &(_, copy) in self.twins[start..].iter().take_while(|&&(s, _)| s == id) {
            self.offered += 1;
            offer(self.query, copy)?;
        }
        ControlFlow::Continue(())
    }
}

impl<P, Q: BoxQuery<P>> BoxQuery<P> for WithCopies<'_, Q> {
    fn bounds(&self) -> Aabb {
        self.query.bounds()
    }
    fn test(&mut self, prim: &P, id: u32) -> ControlFlow<()> {
        self.query.test(prim, id)?;
        self.copies(id, |q, copy| q.test(prim, copy))
    }
    fn test_triangle(&mut self, v: [Vec3; 3], id: u32) -> ControlFlow<()> {
        self.query.test_triangle(v, id)?;
        self.copies(id, |q, copy| q.test_triangle(v, copy))
    }
}

/// A copy's hit is its stored triangle's, bit for bit: the same vertices, the same test.
impl<Q: RayQuery> RayQuery for WithCopies<'_, Q> {
    const OCCLUSION: bool = Q::OCCLUSION;
    const REPEATABLE: bool = Q::REPEATABLE;
    #[inline]
    fn t_far(&self) -> f32 {
        self.query.t_far()
    }
    #[inline]
    fn offer(&mut self, prim: u32, hit: PrimHit) -> ControlFlow<()> {
        self.query.offer(prim, hit)?;
        self.copies(prim, |q, copy| q.offer(copy, hit))
    }
}

//! Step 2: the mid-planes, a child's faces, and the order of the children.
//!
//! A node is cut at its centre ([`crate::mid`]) by three mid-planes. Their parameters `tm`,
//! with the node's near and far face parameters from step 1, are all a node needs: on axis `a`
//! a child is the near half, from the near face to the mid-plane, or the far half, from the
//! mid-plane to the far face. So a child's faces come from its parent's without a division
//! (Revelles et al.'s observation), and the child with ray-order index `c` (bit `a` set: the far
//! half on axis `a`) is the interval from the largest of its near faces to the smallest of its
//! far ones. In the block, mirrored axes count the other way: it is child `c ^ r.neg`.
//!
//! On a flat axis the ray never crosses the mid-plane: it stays in the half its origin is in,
//! the upper one when the origin lies on the plane (boxes are closed, and the builder lists a
//! triangle touching the plane on both sides). Give such a mid-plane the parameter `-∞` when
//! the origin is in the upper half (crossed before the ray starts) and `+∞` when it is in the
//! lower half (never crossed): the children on the wrong side then get empty intervals.
//!
//! Revelles et al. find the children in order with a small state table: the first child from
//! the entry parameter, each next one from the plane through which the ray leaves the current
//! one. That order is the children sorted by entry, which is how this step finds it. The table
//! has a flaw that sorting exposes: two mid-planes crossed at nearly the same parameter may be
//! ordered wrongly by rounding, and the child between them, a sliver the ray really passes
//! through, comes out with an empty interval. So a child whose interval is empty by less than
//! a relative [`NEAR_TIE`] (`1 + 2⁻²⁰`) is kept: [`widen`] its exit before comparing. The kit's
//! `lattice` scene (tiny triangles hugging cell edges, seen from afar) fails without it.

use crate::Block;
use crate::step1::Axes;
use rt_core::NEAR_TIE;
use rt_core::glam::Vec3;

/// `t` moved up by the near-tie tolerance: `t + |t| · 2⁻²⁰`.
pub fn widen(t: f32) -> f32 {
    t + t.abs() * (NEAR_TIE - 1.0)
}

/// The parameters of the mid-planes of box `[lo, hi]` (cut at [`crate::mid`]), per axis; on a
/// flat axis `-∞` when the origin lies in the upper half (on the plane counts as upper), `+∞`
/// when it lies in the lower half.
pub fn mid_params(r: &Axes, lo: Vec3, hi: Vec3) -> Vec3 {
    // BEGIN SOLUTION step 2: the mid-planes' parameters
    let m = crate::mid(lo, hi);
    Vec3::from_array(std::array::from_fn(|a| {
        if r.flat & 1 << a == 0 {
            (m[a] - r.origin[a]) * r.inv[a]
        } else if r.origin[a] >= m[a] {
            f32::NEG_INFINITY
        } else {
            f32::INFINITY
        }
    }))
    // END SOLUTION
}

/// The near and far face parameters of the child with ray-order index `c` of a node with face
/// parameters `near`, `far` and mid-plane parameters `tm`: on axis `a`, `(near, tm)` when bit
/// `a` of `c` is clear, `(tm, far)` when it is set.
pub fn child_faces(near: Vec3, far: Vec3, tm: Vec3, c: u32) -> (Vec3, Vec3) {
    // BEGIN SOLUTION step 2: a child's faces
    let upper = rt_core::glam::BVec3::new(c & 1 != 0, c & 2 != 0, c & 4 != 0);
    (Vec3::select(upper, tm, near), Vec3::select(upper, far, tm))
    // END SOLUTION
}

/// The children of one node the ray passes through, in the order it reaches them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Order {
    /// `(i, entry, exit)`: the child's index in the block, and the parameters where the ray
    /// enters and leaves it. The first `len` are used.
    pub children: [(u32, f32, f32); 8],
    /// How many children the ray passes through.
    pub len: usize,
}

impl Order {
    /// The children, in order.
    pub fn as_slice(&self) -> &[(u32, f32, f32)] {
        &self.children[..self.len]
    }
}

/// The children of a node with face parameters `(near, far)`, mid-plane parameters `tm` and
/// children `block` that the ray passes through, sorted by their entry parameter: every child
/// whose interval is not empty (its entry at most its exit [`widen`]ed; an entry of `+∞` is
/// empty), that ends at or after `t_from`, and that is not an empty leaf.
pub fn order(r: &Axes, (near, far): (Vec3, Vec3), tm: Vec3, block: &Block, t_from: f32) -> Order {
    // BEGIN SOLUTION step 2: the children in order
    let mut out = Order::default();
    for c in 0..8 {
        let (n, f) = child_faces(near, far, tm, c);
        let (entry, exit) = (n.max_element(), f.min_element());
        let i = c ^ r.neg;
        if entry > widen(exit)
            || entry == f32::INFINITY
            || exit < t_from
            || block.0[i as usize].is_empty_leaf()
        {
            continue;
        }
        // Insertion by entry; children entered together stay in ray order.
        let mut k = out.len;
        while k > 0 && out.children[k - 1].1 > entry {
            out.children[k] = out.children[k - 1];
            k -= 1;
        }
        out.children[k] = (i, entry, exit);
        out.len += 1;
    }
    out
    // END SOLUTION
}

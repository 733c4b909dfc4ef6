//! The watertight ray–triangle test (Woop, Benthin & Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013), written once over the lane width: a BVH tests four triangles
//! against one ray with it ([`Simd<4>`]), a bundle's leaves test one triangle against eight or
//! sixteen rays ([`Simd<8>`], [`Simd<16>`]). Each lane performs the operations of
//! [`Triangle::intersect_sheared`](rt_core::Triangle::intersect_sheared), the scalar test, in
//! the same order, and an edge function of exactly zero is recomputed in `f64` as there, so
//! every lane gets the scalar test's bits of `t`, `u` and `v`.

use crate::Simd;

/// What the watertight test finds in each lane: the lanes hit within their interval (a bit
/// per lane) and each lane's `t`, `u` and `v` (meaningful in those lanes only).
#[derive(Clone, Copy, Debug)]
pub struct Hits<V> {
    /// Bit `i` set when lane `i` hits within `[t_min, t_max]` (and is active).
    pub mask: u32,
    /// The ray parameter of each lane's hit.
    pub t: V,
    /// The barycentric weight of `v1`.
    pub u: V,
    /// The barycentric weight of `v2`.
    pub v: V,
}

/// The watertight test of `N` lanes, each a triangle and a ray (either may be the same in every
/// lane): `verts` the three vertices along the ray's axes `kx`, `ky`, `kz` (the ray's
/// [`Shear`](rt_core::Shear) order), `origin` the ray's origin along the same axes, `shear`
/// its factors `sx`, `sy`, `sz`, and its interval `[t_min, t_max]`. Only the lanes of
/// `active` can hit; a lane holding NaN (an unused slot) never does.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn watertight<const N: usize, S: Simd<N>>(
    s: S,
    verts: [[S::V; 3]; 3],
    origin: [S::V; 3],
    shear: [S::V; 3],
    t_min: S::V,
    t_max: S::V,
    active: u32,
) -> Hits<S::V> {
    let [ox, oy, oz] = origin;
    let [sx, sy, sz] = shear;
    // Each vertex relative to the origin, sheared: (x − sx·z, y − sy·z) and z.
    let rel = |[x, y, z]: [S::V; 3]| {
        let (x, y, z) = (s.sub(x, ox), s.sub(y, oy), s.sub(z, oz));
        (s.sub(x, s.mul(sx, z)), s.sub(y, s.mul(sy, z)), z)
    };
    let (ax, ay, az) = rel(verts[0]);
    let (bx, by, bz) = rel(verts[1]);
    let (cx, cy, cz) = rel(verts[2]);
    let u = s.sub(s.mul(cx, by), s.mul(cy, bx));
    let v = s.sub(s.mul(ax, cy), s.mul(ay, cx));
    let w = s.sub(s.mul(bx, ay), s.mul(by, ax));
    let zero = s.splat(0.0);
    let exact = s.or(s.or(s.eq(u, zero), s.eq(v, zero)), s.eq(w, zero));
    // Where an edge function is exactly zero (a ray through an edge or a vertex, rare except on
    // lattices), the scalar test recomputes all three in `f64`: so do these lanes, in vectors.
    // PERF: calling the scalar test for those lanes made the compiler keep the ray's vectors in
    // memory around the call in the hot loop (teapot primary rays 29.2 -> 33.2 Mrays/s).
    let (u, v, w) = if s.bits(exact) & active != 0 {
        let [u2, v2, w2] = s.edges_f64(ax, ay, bx, by, cx, cy);
        (
            s.select(exact, u2, u),
            s.select(exact, v2, v),
            s.select(exact, w2, w),
        )
    } else {
        (u, v, w)
    };
    // Outside when some edge function is below zero and some above: from their least and
    // greatest. Where one is NaN the comparisons may say anything, but `det` is NaN there and
    // the lane is no candidate either way.
    // PERF: two comparisons of the extremes instead of six and their masks: the longest chain
    // of the sixteen-lane kernel's profile (the wide BVH's bundles, close views, one thread,
    // medians of five alternating runs, Mrays/s: the sphereflake 38.8 -> 38.9, the bunny 42.5
    // -> 43.0, the teapot 62.1 -> 63.3, the teapot in a stadium 70.4 -> 70.9).
    let lo = s.min(s.min(u, v), w);
    let hi = s.max(s.max(u, v), w);
    let outside = s.and(s.lt(lo, zero), s.gt(hi, zero));
    let det = s.add(s.add(u, v), w);
    // `det != 0` and not NaN: NaN edge functions (non-finite input) are no candidate.
    let candidates = s.andnot(outside, s.ne_ordered(det, zero));
    if s.bits(candidates) & active == 0 {
        // PERF: no lane can hit (each is outside an edge, or degenerate), so the division for
        // `t` is skipped. Bunny, single-threaded, interleaved runs: primary rays 20.3 -> 21.0
        // Mrays/s, incoherent 6.15 -> 6.3, shadow 8.7 -> 8.5.
        return Hits {
            mask: 0,
            t: zero,
            u: zero,
            v: zero,
        };
    }
    let inv = s.div(s.splat(1.0), det);
    let t_num = s.add(
        s.add(s.mul(u, s.mul(sz, az)), s.mul(v, s.mul(sz, bz))),
        s.mul(w, s.mul(sz, cz)),
    );
    let t = s.mul(t_num, inv);
    let in_range = s.and(s.ge(t, t_min), s.le(t, t_max));
    Hits {
        mask: s.bits(s.and(candidates, in_range)) & active,
        t,
        u: s.mul(v, inv),
        v: s.mul(w, inv),
    }
}

/// The axis order `[kx, ky, kz]` ([`Shear::new`](rt_core::Shear::new)'s) of a lane of octant
/// `octant` whose dominant axis is `kz`, for each `kz`: the next two axes, swapped when the
/// direction along `kz` is negative, which the octant says for every lane.
#[inline(always)]
pub(crate) fn shear_orders(octant: usize) -> [[usize; 3]; 3] {
    let mut orders = [[0; 3]; 3];
    for (kz, order) in orders.iter_mut().enumerate() {
        let kx = if kz == 2 { 0 } else { kz + 1 };
        let ky = if kx == 2 { 0 } else { kx + 1 };
        *order = if octant >> kz & 1 != 0 {
            [ky, kx, kz]
        } else {
            [kx, ky, kz]
        };
    }
    orders
}

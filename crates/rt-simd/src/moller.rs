//! The Möller–Trumbore ray–triangle test over the lane width, from each triangle's stored first
//! vertex and edges: lane by lane the operations of
//! [`rt_core::moller_trumbore_edges`], in the same order, so the same bits.

use crate::{Hits, Simd};

/// Möller–Trumbore on `N` lanes: `v0`, `e1`, `e2` the first vertex and the two edges along x,
/// y, z; `origin` and `dir` the ray's; its interval `[t_min, t_max]`. A lane holding NaN (an
/// unused slot) never hits.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn moller_trumbore<const N: usize, S: Simd<N>>(
    s: S,
    v0: [S::V; 3],
    e1: [S::V; 3],
    e2: [S::V; 3],
    origin: [S::V; 3],
    dir: [S::V; 3],
    t_min: S::V,
    t_max: S::V,
) -> Hits<S::V> {
    let [dx, dy, dz] = dir;
    let [ox, oy, oz] = origin;
    let [v0x, v0y, v0z] = v0;
    let [e1x, e1y, e1z] = e1;
    let [e2x, e2y, e2z] = e2;
    let cross = |ay, az, by, bz| s.sub(s.mul(ay, bz), s.mul(by, az));
    let dot = |ax, ay, az, bx, by, bz| s.add(s.add(s.mul(ax, bx), s.mul(ay, by)), s.mul(az, bz));
    // p = d × e2 and q = s × e1, as glam's `Vec3::cross` evaluates them.
    let (px, py, pz) = (
        cross(dy, dz, e2y, e2z),
        cross(dz, dx, e2z, e2x),
        cross(dx, dy, e2x, e2y),
    );
    let det = dot(e1x, e1y, e1z, px, py, pz);
    let inv = s.div(s.splat(1.0), det);
    let (sx, sy, sz) = (s.sub(ox, v0x), s.sub(oy, v0y), s.sub(oz, v0z));
    let u = s.mul(dot(sx, sy, sz, px, py, pz), inv);
    let (qx, qy, qz) = (
        cross(sy, sz, e1y, e1z),
        cross(sz, sx, e1z, e1x),
        cross(sx, sy, e1x, e1y),
    );
    let v = s.mul(dot(dx, dy, dz, qx, qy, qz), inv);
    let t = s.mul(dot(e2x, e2y, e2z, qx, qy, qz), inv);
    let (zero, one) = (s.splat(0.0), s.splat(1.0));
    let ok = s.and(
        s.and(s.ne_ordered(det, zero), s.and(s.ge(u, zero), s.le(u, one))),
        s.and(
            s.and(s.ge(v, zero), s.le(s.add(u, v), one)),
            s.and(s.ge(t, t_min), s.le(t, t_max)),
        ),
    );
    Hits {
        mask: s.bits(ok),
        t,
        u,
        v,
    }
}

//! The wide layout's inner kernels: one slab test for all eight children of a [`WideNode`] and
//! one ray–triangle test for the four lanes of a [`TriPack`].
//!
//! They are written once, over the small [`Simd`] trait: [`Portable`] implements it with plain
//! arrays (which LLVM turns into SSE2 or NEON code for the baseline target), and `simd::Avx2`
//! with AVX2 intrinsics. Both compute every lane with the same operations, in the same order, as
//! the scalar functions they mirror ([`rt_core::Aabb::intersect`],
//! [`rt_core::Triangle::intersect_sheared`], [`rt_core::moller_trumbore_edges`]): no fused
//! multiply-adds, IEEE division, comparisons with the same NaN behaviour. So the results are the
//! same bits, and the tests compare them exactly.

use crate::node::{PACK, TriPack, WIDTH, WideNode};
use rt_core::{Ray, SLAB_FAR_SCALE, Shear};

/// The lane operations the kernels need: eight-lane vectors for node boxes, four-lane vectors
/// and masks for triangle packs. Comparisons follow Rust's operators (false when a lane is NaN).
pub(crate) trait Simd: Copy {
    /// Eight `f32` lanes.
    type F8: Copy;
    /// Four `f32` lanes.
    type F4: Copy;
    /// A four-lane comparison result.
    type M4: Copy;

    fn load8(self, v: &[f32; 8]) -> Self::F8;
    fn splat8(self, x: f32) -> Self::F8;
    fn sub8(self, a: Self::F8, b: Self::F8) -> Self::F8;
    fn mul8(self, a: Self::F8, b: Self::F8) -> Self::F8;
    /// Per lane `if a > b { a } else { b }` (so `b` where `a` is NaN).
    fn max8(self, a: Self::F8, b: Self::F8) -> Self::F8;
    /// Per lane `if a < b { a } else { b }` (so `b` where `a` is NaN).
    fn min8(self, a: Self::F8, b: Self::F8) -> Self::F8;
    /// Bit `i` set when `a[i] <= b[i]`.
    fn le_bits8(self, a: Self::F8, b: Self::F8) -> u32;
    /// Per lane `neg` where `sign`'s sign bit is set (`-0` included), else `pos`.
    fn select_sign8(self, sign: Self::F8, neg: Self::F8, pos: Self::F8) -> Self::F8;
    fn store8(self, a: Self::F8) -> [f32; 8];

    fn load4(self, v: &[f32; 4]) -> Self::F4;
    fn splat4(self, x: f32) -> Self::F4;
    fn add4(self, a: Self::F4, b: Self::F4) -> Self::F4;
    fn sub4(self, a: Self::F4, b: Self::F4) -> Self::F4;
    fn mul4(self, a: Self::F4, b: Self::F4) -> Self::F4;
    fn div4(self, a: Self::F4, b: Self::F4) -> Self::F4;
    fn eq4(self, a: Self::F4, b: Self::F4) -> Self::M4;
    /// `a != b` and neither is NaN.
    fn ne_ordered4(self, a: Self::F4, b: Self::F4) -> Self::M4;
    fn lt4(self, a: Self::F4, b: Self::F4) -> Self::M4;
    fn gt4(self, a: Self::F4, b: Self::F4) -> Self::M4;
    fn le4(self, a: Self::F4, b: Self::F4) -> Self::M4;
    fn ge4(self, a: Self::F4, b: Self::F4) -> Self::M4;
    fn and4(self, a: Self::M4, b: Self::M4) -> Self::M4;
    fn or4(self, a: Self::M4, b: Self::M4) -> Self::M4;
    /// `!a & b`.
    fn andnot4(self, a: Self::M4, b: Self::M4) -> Self::M4;
    /// Bit `i` set when lane `i` of the mask is.
    fn bits4(self, m: Self::M4) -> u32;
    fn store4(self, a: Self::F4) -> [f32; 4];
    /// Per lane `if m { a } else { b }`.
    fn select4(self, m: Self::M4, a: Self::F4, b: Self::F4) -> Self::F4;
    /// The watertight test's edge functions recomputed in `f64` and rounded to `f32`, per lane:
    /// `(cx·by - cy·bx, ax·cy - ay·cx, bx·ay - by·ax)`.
    #[allow(clippy::too_many_arguments)]
    fn edges_f64(
        self,
        ax: Self::F4,
        ay: Self::F4,
        bx: Self::F4,
        by: Self::F4,
        cx: Self::F4,
        cy: Self::F4,
    ) -> [Self::F4; 3];
}

/// The kernels on plain arrays, for any target.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

#[inline(always)]
fn map<const N: usize, T: Copy, U>(a: [T; N], b: [T; N], f: impl Fn(T, T) -> U) -> [U; N] {
    std::array::from_fn(|i| f(a[i], b[i]))
}

/// Bit `i` set when `f(a[i], b[i])`.
#[inline(always)]
fn cmp<const N: usize>(a: [f32; N], b: [f32; N], f: impl Fn(f32, f32) -> bool) -> u32 {
    let mut m = 0;
    for i in 0..N {
        m |= (f(a[i], b[i]) as u32) << i;
    }
    m
}

impl Simd for Portable {
    type F8 = [f32; 8];
    type F4 = [f32; 4];
    /// Masks are bit masks: the bit operations are one instruction each, and no lane-by-lane
    /// gathering is left for the tests of a mask. PERF: as `[bool; 4]`, the portable kernels
    /// traced the teapot's primary rays slower than the binary tree (15.0 against 18.7 Mrays/s).
    type M4 = u32;

    #[inline(always)]
    fn load8(self, v: &[f32; 8]) -> [f32; 8] {
        *v
    }
    #[inline(always)]
    fn splat8(self, x: f32) -> [f32; 8] {
        [x; 8]
    }
    #[inline(always)]
    fn sub8(self, a: [f32; 8], b: [f32; 8]) -> [f32; 8] {
        map(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn mul8(self, a: [f32; 8], b: [f32; 8]) -> [f32; 8] {
        map(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn max8(self, a: [f32; 8], b: [f32; 8]) -> [f32; 8] {
        map(a, b, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn min8(self, a: [f32; 8], b: [f32; 8]) -> [f32; 8] {
        map(a, b, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn le_bits8(self, a: [f32; 8], b: [f32; 8]) -> u32 {
        cmp(a, b, |a, b| a <= b)
    }
    #[inline(always)]
    fn select_sign8(self, sign: [f32; 8], neg: [f32; 8], pos: [f32; 8]) -> [f32; 8] {
        std::array::from_fn(|i| {
            if sign[i].is_sign_negative() {
                neg[i]
            } else {
                pos[i]
            }
        })
    }
    #[inline(always)]
    fn store8(self, a: [f32; 8]) -> [f32; 8] {
        a
    }
    #[inline(always)]
    fn load4(self, v: &[f32; 4]) -> [f32; 4] {
        *v
    }
    #[inline(always)]
    fn splat4(self, x: f32) -> [f32; 4] {
        [x; 4]
    }
    #[inline(always)]
    fn add4(self, a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
        map(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn sub4(self, a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
        map(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn mul4(self, a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
        map(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn div4(self, a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
        map(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn eq4(self, a: [f32; 4], b: [f32; 4]) -> u32 {
        cmp(a, b, |a, b| a == b)
    }
    #[inline(always)]
    fn ne_ordered4(self, a: [f32; 4], b: [f32; 4]) -> u32 {
        cmp(a, b, |a, b| a != b && !a.is_nan() && !b.is_nan())
    }
    #[inline(always)]
    fn lt4(self, a: [f32; 4], b: [f32; 4]) -> u32 {
        cmp(a, b, |a, b| a < b)
    }
    #[inline(always)]
    fn gt4(self, a: [f32; 4], b: [f32; 4]) -> u32 {
        cmp(a, b, |a, b| a > b)
    }
    #[inline(always)]
    fn le4(self, a: [f32; 4], b: [f32; 4]) -> u32 {
        cmp(a, b, |a, b| a <= b)
    }
    #[inline(always)]
    fn ge4(self, a: [f32; 4], b: [f32; 4]) -> u32 {
        cmp(a, b, |a, b| a >= b)
    }
    #[inline(always)]
    fn and4(self, a: u32, b: u32) -> u32 {
        a & b
    }
    #[inline(always)]
    fn or4(self, a: u32, b: u32) -> u32 {
        a | b
    }
    #[inline(always)]
    fn andnot4(self, a: u32, b: u32) -> u32 {
        !a & b
    }
    #[inline(always)]
    fn bits4(self, m: u32) -> u32 {
        m & 0xf
    }
    #[inline(always)]
    fn store4(self, a: [f32; 4]) -> [f32; 4] {
        a
    }
    #[inline(always)]
    fn select4(self, m: u32, a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
        std::array::from_fn(|i| if m >> i & 1 != 0 { a[i] } else { b[i] })
    }
    #[inline(always)]
    fn edges_f64(
        self,
        ax: [f32; 4],
        ay: [f32; 4],
        bx: [f32; 4],
        by: [f32; 4],
        cx: [f32; 4],
        cy: [f32; 4],
    ) -> [[f32; 4]; 3] {
        let d = |v: [f32; 4]| v.map(f64::from);
        let (ax, ay, bx, by, cx, cy) = (d(ax), d(ay), d(bx), d(by), d(cx), d(cy));
        [
            std::array::from_fn(|i| (cx[i] * by[i] - cy[i] * bx[i]) as f32),
            std::array::from_fn(|i| (ax[i] * cy[i] - ay[i] * cx[i]) as f32),
            std::array::from_fn(|i| (bx[i] * ay[i] - by[i] * ax[i]) as f32),
        ]
    }
}

/// What the kernels need of a ray, computed once per ray: broadcast into vectors where the
/// kernels use it lane-wise.
#[derive(Clone, Copy)]
pub(crate) struct RayData<S: Simd> {
    pub boxes: BoxRay<S>,
    pub shear: Shear,
    /// The origin along the shear's axes kx, ky, kz, the shear factors, and `t_min`, as
    /// four-lane vectors for the watertight test.
    pub o4: [S::F4; 3],
    pub s4: [S::F4; 3],
    /// The origin and direction along x, y, z, for Möller–Trumbore.
    pub origin4: [S::F4; 3],
    pub dir4: [S::F4; 3],
    pub t_min4: S::F4,
}

/// What the slab test needs of a ray, as eight-lane vectors.
#[derive(Clone, Copy)]
pub(crate) struct BoxRay<S: Simd> {
    pub origin: [S::F8; 3],
    pub inv_dir: [S::F8; 3],
    pub t_min8: S::F8,
}

impl<S: Simd> BoxRay<S> {
    #[inline(always)]
    pub fn new(simd: S, ray: &Ray) -> Self {
        let (o, inv) = (ray.origin, ray.inv_dir());
        // Written out lane by lane: closures passed to `array::map` are not inlined into the
        // AVX2 entry point, and the broadcasts then run as calls (measured: a third of the cost
        // of a ray that misses the root).
        let s8 = |x| simd.splat8(x);
        Self {
            origin: [s8(o.x), s8(o.y), s8(o.z)],
            inv_dir: [s8(inv.x), s8(inv.y), s8(inv.z)],
            t_min8: s8(ray.t_min),
        }
    }
}

impl<S: Simd> RayData<S> {
    /// The ray's data for the whole traversal, from its slab-test part.
    #[inline(always)]
    pub fn new(simd: S, ray: &Ray, boxes: BoxRay<S>) -> Self {
        Self::with_shear(simd, ray, boxes, Shear::new(ray.dir()))
    }

    /// [`RayData::new`] with the ray's shear computed already (a bundle keeps each lane's).
    #[inline(always)]
    pub fn with_shear(simd: S, ray: &Ray, boxes: BoxRay<S>, shear: Shear) -> Self {
        let (o, d) = (ray.origin, ray.dir());
        let s4 = |x| simd.splat4(x);
        Self {
            boxes,
            shear,
            o4: [s4(o[shear.kx]), s4(o[shear.ky]), s4(o[shear.kz])],
            s4: [s4(shear.sx), s4(shear.sy), s4(shear.sz)],
            origin4: [s4(o.x), s4(o.y), s4(o.z)],
            dir4: [s4(d.x), s4(d.y), s4(d.z)],
            t_min4: s4(ray.t_min),
        }
    }
}

/// The slab test of all eight children against `[t_min, t_max]`: a bit mask of the children
/// entered and each child's entry distance.
///
/// Lane by lane this is [`rt_core::Aabb::intersect`]: the near and far planes chosen by the sign
/// of the reciprocal direction, `(plane - origin) · inv_dir`, the interval narrowed by
/// comparisons that ignore NaN (an origin in a face plane with a zero direction component), the
/// far end widened by [`SLAB_FAR_SCALE`]. Empty lanes (`+inf` minimum, `-inf` maximum) never pass.
#[inline(always)]
pub(crate) fn slab8<S: Simd>(s: S, node: &WideNode, r: &BoxRay<S>, t_max: f32) -> (u32, S::F8) {
    let mut t0 = r.t_min8;
    let mut t1 = s.splat8(t_max);
    for a in 0..3 {
        // The near plane is the minimum row for a positive reciprocal direction and the maximum
        // row for a negative one (`-0` included), chosen lane by lane from the reciprocal's sign
        // (one blend) rather than by row indices kept per ray. PERF: the indices were reloaded
        // from the stack at every node; with the blend the AVX2 walk of 60,000 incoherent
        // bunny rays ran 603 instead of 669 instructions per ray (cachegrind), 1.00-1.04 of the
        // speed before (in one process, on the four peer scenes and three ray kinds).
        let (lo, hi) = (s.load8(&node.bounds[a]), s.load8(&node.bounds[a + 3]));
        let inv = r.inv_dir[a];
        let (near, far) = (s.select_sign8(inv, hi, lo), s.select_sign8(inv, lo, hi));
        let tn = s.mul8(s.sub8(near, r.origin[a]), inv);
        let tf = s.mul8(s.sub8(far, r.origin[a]), inv);
        t0 = s.max8(tn, t0);
        t1 = s.min8(tf, t1);
    }
    let mask = s.le_bits8(t0, s.mul8(t1, s.splat8(SLAB_FAR_SCALE)));
    (mask, t0)
}

/// The hits of one pack: a mask of the lanes hit within `[t_min, t_max]`, and per lane `t` and
/// the surface coordinates `u`, `v` (meaningful in the masked lanes only).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PackHits<S: Simd> {
    pub mask: u32,
    pub t: S::F4,
    pub u: S::F4,
    pub v: S::F4,
}

/// The watertight test (Woop, Benthin & Wald 2013) on four triangles at once, lane by lane the
/// operations of [`rt_core::Triangle::intersect_sheared`].
///
/// Like the scalar test, a lane whose edge functions include an exact zero has all three
/// recomputed in `f64` (a ray through an edge or a vertex, rare except on lattices). Unused lanes
/// hold NaN, which gives NaN edge functions: never zero, always rejected.
#[inline(always)]
pub(crate) fn watertight4<S: Simd>(s: S, p: &TriPack, r: &RayData<S>, t_max: f32) -> PackHits<S> {
    let Shear { kx, ky, kz, .. } = r.shear;
    let [sx, sy, sz] = r.s4;
    let [ox, oy, oz] = r.o4;
    // Vertex k relative to the origin, sheared: (x - sx·z, y - sy·z) and z.
    let vertex = |k: usize| {
        let x = s.sub4(s.load4(&p.rows[3 * k + kx]), ox);
        let y = s.sub4(s.load4(&p.rows[3 * k + ky]), oy);
        let z = s.sub4(s.load4(&p.rows[3 * k + kz]), oz);
        (s.sub4(x, s.mul4(sx, z)), s.sub4(y, s.mul4(sy, z)), z)
    };
    let (ax, ay, az) = vertex(0);
    let (bx, by, bz) = vertex(1);
    let (cx, cy, cz) = vertex(2);
    let u = s.sub4(s.mul4(cx, by), s.mul4(cy, bx));
    let v = s.sub4(s.mul4(ax, cy), s.mul4(ay, cx));
    let w = s.sub4(s.mul4(bx, ay), s.mul4(by, ax));
    let zero4 = s.splat4(0.0);
    let zero = s.or4(s.or4(s.eq4(u, zero4), s.eq4(v, zero4)), s.eq4(w, zero4));
    // Where an edge function is exactly zero, the scalar test recomputes all three in f64 (a
    // ray through an edge or a vertex): so do the lanes here, in vectors, without a call.
    // PERF: calling the scalar test for those lanes made the compiler keep the ray's vectors in
    // memory around the call in the hot loop (teapot primary rays 29.2 -> 33.2 Mrays/s).
    let (u, v, w) = if s.bits4(zero) != 0 {
        let [u2, v2, w2] = s.edges_f64(ax, ay, bx, by, cx, cy);
        (
            s.select4(zero, u2, u),
            s.select4(zero, v2, v),
            s.select4(zero, w2, w),
        )
    } else {
        (u, v, w)
    };
    let neg = s.or4(s.or4(s.lt4(u, zero4), s.lt4(v, zero4)), s.lt4(w, zero4));
    let pos = s.or4(s.or4(s.gt4(u, zero4), s.gt4(v, zero4)), s.gt4(w, zero4));
    let det = s.add4(s.add4(u, v), w);
    let candidates = s.andnot4(s.and4(neg, pos), s.ne_ordered4(det, zero4));
    if s.bits4(candidates) == 0 {
        // PERF: no lane can hit (each is outside an edge, or degenerate), so the division for
        // `t` is skipped. Bunny, single-threaded, interleaved runs: primary rays 20.3 -> 21.0
        // Mrays/s, incoherent 6.15 -> 6.3, shadow 8.7 -> 8.5.
        return PackHits {
            mask: 0,
            t: zero4,
            u: zero4,
            v: zero4,
        };
    }
    let inv = s.div4(s.splat4(1.0), det);
    let t_num = s.add4(
        s.add4(s.mul4(u, s.mul4(sz, az)), s.mul4(v, s.mul4(sz, bz))),
        s.mul4(w, s.mul4(sz, cz)),
    );
    let t = s.mul4(t_num, inv);
    let in_range = s.and4(s.ge4(t, r.t_min4), s.le4(t, s.splat4(t_max)));
    let ok = s.and4(candidates, in_range);
    PackHits {
        mask: s.bits4(ok),
        t,
        u: s.mul4(v, inv),
        v: s.mul4(w, inv),
    }
}

/// Möller–Trumbore on four triangles at once from their stored first vertex and edges, lane by
/// lane the operations of [`rt_core::moller_trumbore_edges`]. Unused lanes hold NaN and are
/// rejected.
#[inline(always)]
pub(crate) fn moller_trumbore4<S: Simd>(
    s: S,
    p: &TriPack,
    r: &RayData<S>,
    t_max: f32,
) -> PackHits<S> {
    let row = |k: usize| s.load4(&p.rows[k]);
    let [dx, dy, dz] = r.dir4;
    let [ox, oy, oz] = r.origin4;
    let (v0x, v0y, v0z) = (row(0), row(1), row(2));
    let (e1x, e1y, e1z) = (row(3), row(4), row(5));
    let (e2x, e2y, e2z) = (row(6), row(7), row(8));
    let cross = |ay, az, by, bz| s.sub4(s.mul4(ay, bz), s.mul4(by, az));
    let dot =
        |ax, ay, az, bx, by, bz| s.add4(s.add4(s.mul4(ax, bx), s.mul4(ay, by)), s.mul4(az, bz));
    // p = d × e2 and q = s × e1, as glam's `Vec3::cross` evaluates them.
    let (px, py, pz) = (
        cross(dy, dz, e2y, e2z),
        cross(dz, dx, e2z, e2x),
        cross(dx, dy, e2x, e2y),
    );
    let det = dot(e1x, e1y, e1z, px, py, pz);
    let inv = s.div4(s.splat4(1.0), det);
    let (sx, sy, sz) = (s.sub4(ox, v0x), s.sub4(oy, v0y), s.sub4(oz, v0z));
    let u = s.mul4(dot(sx, sy, sz, px, py, pz), inv);
    let (qx, qy, qz) = (
        cross(sy, sz, e1y, e1z),
        cross(sz, sx, e1z, e1x),
        cross(sx, sy, e1x, e1y),
    );
    let v = s.mul4(dot(dx, dy, dz, qx, qy, qz), inv);
    let t = s.mul4(dot(e2x, e2y, e2z, qx, qy, qz), inv);
    let (zero, one) = (s.splat4(0.0), s.splat4(1.0));
    let ok = s.and4(
        s.and4(
            s.ne_ordered4(det, zero),
            s.and4(s.ge4(u, zero), s.le4(u, one)),
        ),
        s.and4(
            s.and4(s.ge4(v, zero), s.le4(s.add4(u, v), one)),
            s.and4(s.ge4(t, r.t_min4), s.le4(t, s.splat4(t_max))),
        ),
    );
    PackHits {
        mask: s.bits4(ok),
        t,
        u,
        v,
    }
}

const _: () = assert!(WIDTH == 8 && PACK == 4);

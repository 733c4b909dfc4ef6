//! A bundle's lanes at the leaves: one primitive tested against many lanes at once, each lane
//! with exactly the arithmetic of its single-ray test.
//!
//! Structures whose cells or leaves list primitives by index (the kd-tree, the grids, the
//! octree) test each listed primitive against every lane of a [`Bundle`] that is still tracing.
//! For the watertight triangle ([`Triangle::intersect_watertight`]), [`Lanes`] runs the one
//! watertight kernel ([`watertight`](crate::watertight())) over eight lanes per step (sixteen
//! with AVX-512): every lane takes the same operations in the same order as the scalar test
//! (Rust never fuses a multiply and an add unasked), so it gets the same bits of `t`, `u` and
//! `v`. Other primitives are tested lane by lane with [`Primitive::intersect`].
//!
//! Which lanes a primitive is tested against is the structure's choice: any lane may be tested
//! against any primitive, since a hit found is a true hit of that lane, and the closest of the
//! hits (ties to the smaller index) does not depend on which extra primitives were tried. A
//! structure must only make sure that every primitive its single-ray walk would test for a lane
//! is tested for that lane too.
//!
//! The instruction set is the [`Isa`] chosen at run time (AVX-512 or AVX2 on x86-64 CPUs that
//! have them); `RT_ACCEL_PORTABLE=1` forces the portable kernels, and the tests run every
//! instruction set this CPU has.

use super::Bundle;
use crate::watertight::shear_orders;
use crate::{BUNDLE_LANES, Isa, Portable, Simd, watertight};
use rt_core::{Aabb, Hit, Primitive, Ray, Shear, Stats, Triangle, TriangleTest};

/// Lanes per vector step (sixteen-lane steps are two of them).
const W: usize = 8;

/// The lanes of one [`Bundle`] with each lane's best hit so far. The lanes' rays (and their
/// watertight shears) stay in the bundle, which this borrows.
#[derive(Clone, Debug)]
pub struct Lanes<'b> {
    /// The bundle whose lanes these are.
    bundle: &'b Bundle,
    /// The axis order `[kx, ky, kz]` of the lanes whose dominant axis is `a`, for each axis `a`
    /// (the bundle's one octant fixes `kx` and `ky` given `kz`).
    order: [[usize; 3]; 3],
    /// The best hit of each lane: its `t` (the lane's `t_max` while it has none)...
    t: [f32; BUNDLE_LANES],
    /// ... its primitive (`u32::MAX` while none) ...
    prim: [u32; BUNDLE_LANES],
    /// ... and its `u`, `v`.
    uv: [[f32; BUNDLE_LANES]; 2],
    /// The instruction set the kernels use.
    isa: Isa,
}

/// Lanes `N * step ..` of a bundle's array.
#[inline(always)]
fn chunk<T, const N: usize>(v: &[T; BUNDLE_LANES], step: usize) -> &[T; N] {
    &v.as_chunks::<N>().0[step]
}

/// Lanes `N * step ..` of an array, to write.
#[inline(always)]
fn chunk_mut<T, const N: usize>(v: &mut [T; BUNDLE_LANES], step: usize) -> &mut [T; N] {
    &mut v.as_chunks_mut::<N>().0[step]
}

impl<'b> Lanes<'b> {
    /// The lanes of `bundle`, none hit yet: each lane's best `t` is its `t_max`. The kernels
    /// use the best instructions this CPU has ([`Isa::detect`]).
    pub fn new(bundle: &'b Bundle) -> Self {
        Self::with_isa(bundle, Isa::detect())
    }

    /// [`Lanes::new`] with the kernels' instruction set chosen by the caller (the tests run
    /// each one). Lanes past the bundle's length keep NaN as their best `t` and no primitive.
    // PERF: the lanes once kept copies of the bundle's rays and shears, copied in for each
    // bundle (4 KB a bundle); borrowing the bundle leaves 1 KB of best hits to set. The frame
    // around a bundle walk (a walk that does nothing, the teapot's close view) went from
    // 5.2-6.0 to 4.9 ns a ray. The wide BVH's bundles, the peers benchmark's close views, one
    // thread, medians of five alternating runs of a private harness, Mrays/s: the bunny 40.3
    // -> 41.6, the teapot 53.8 -> 61.5, the teapot in a stadium 62.1 -> 68.0, the sphereflake
    // 35.6 -> 36.7.
    #[inline(always)]
    pub fn with_isa(bundle: &'b Bundle, isa: Isa) -> Self {
        let mut t = bundle.t_max;
        t[bundle.len()..].fill(f32::NAN);
        Self {
            bundle,
            order: shear_orders(bundle.octant()),
            t,
            prim: [u32::MAX; BUNDLE_LANES],
            uv: [[0.0; BUNDLE_LANES]; 2],
            isa,
        }
    }

    /// Lane `i` as a ray: the same bits as the ray it came from.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        self.bundle.ray(i)
    }

    /// Lane `i`'s best `t` so far (its `t_max` while it has no hit).
    #[inline(always)]
    pub fn t(&self, i: usize) -> f32 {
        self.t[i]
    }

    /// Every lane's best `t` so far (lanes past the bundle's length hold NaN).
    #[inline(always)]
    pub fn best_t(&self) -> &[f32; BUNDLE_LANES] {
        &self.t
    }

    /// The instruction set the kernels run with: a walk that calls them from a frame of its own
    /// compiles that frame for it, so that they inline.
    #[inline(always)]
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// How many vector steps the watertight test of one triangle against the lanes of `mask`
    /// takes (with lanes of one dominant axis): the occupied groups of sixteen lanes with
    /// AVX-512, else of eight. A walk weighs testing a leaf's triangles ray-parallel, with
    /// these lanes, against testing each lane alone.
    #[inline(always)]
    pub fn steps(&self, mask: u64) -> usize {
        let width = if self.sixteen() { 16 } else { W };
        (0..BUNDLE_LANES / width)
            .filter(|g| mask >> (width * g) & ((1 << width) - 1) != 0)
            .count()
    }

    /// Whether the kernels step sixteen lanes at a time (AVX-512).
    #[inline(always)]
    fn sixteen(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return matches!(self.isa, Isa::Avx512(_));
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// The largest best `t` over the lanes, which bounds every lane's best hit from here on (a
    /// lane's best only shrinks; lanes past the bundle's length are ignored).
    // PERF: written over whole vectors of lanes, so that it compiles to vector maxima: a loop
    // over the live lanes' bits with `f32::max` was a tenth of the BVH's bundle traversal's
    // samples (`perf record`, bunny primary rays, 8×8 tiles).
    #[inline(always)]
    pub fn far_end(&self) -> f32 {
        let mut hi = [f32::NEG_INFINITY; W];
        for step in self.t.as_chunks::<W>().0 {
            for (h, &t) in hi.iter_mut().zip(step) {
                *h = if t > *h { t } else { *h };
            }
        }
        hi.into_iter()
            .fold(f32::NEG_INFINITY, |a, b| if b > a { b } else { a })
    }

    /// Lane `i`'s best hit so far: primitive `u32::MAX` (and `t` its `t_max`) while it has
    /// none, as a single-ray walk starts its own.
    #[inline(always)]
    pub fn best(&self, i: usize) -> Hit {
        Hit {
            prim: self.prim[i],
            t: self.t[i],
            u: self.uv[0][i],
            v: self.uv[1][i],
        }
    }

    /// Lane `i`'s watertight [`Shear`], the one [`Shear::new`] makes of its direction.
    #[inline(always)]
    pub fn shear(&self, i: usize) -> Shear {
        let by_axis = self.bundle.by_axis;
        let kz = if by_axis[0] >> i & 1 != 0 {
            0
        } else if by_axis[1] >> i & 1 != 0 {
            1
        } else {
            2
        };
        let [kx, ky, kz] = self.order[kz];
        Shear {
            kx,
            ky,
            kz,
            sx: self.bundle.shear[0][i],
            sy: self.bundle.shear[1][i],
            sz: self.bundle.shear[2][i],
        }
    }

    /// Keeps `hit` as lane `i`'s best if it beats it ([`Hit::beats`]): for a walk that tests a
    /// lane on its own, with its single-ray test, and hands back what it found.
    #[inline(always)]
    pub fn offer_hit(&mut self, i: usize, hit: Hit) {
        self.offer(i, hit.prim, hit.t, hit.u, hit.v);
    }

    /// Records that primitive `id` blocks lane `i` (an any-hit query), as
    /// [`Lanes::occluded`] records the lanes it blocks: the lane's answer becomes `Some`.
    #[inline(always)]
    pub fn block(&mut self, i: usize, id: u32) {
        self.prim[i] = id;
    }

    /// Lane `i`'s answer: its closest hit, if any.
    #[inline(always)]
    pub fn hit(&self, i: usize) -> Option<Hit> {
        let prim = self.prim[i];
        (prim != u32::MAX).then_some(Hit {
            prim,
            t: self.t[i],
            u: self.uv[0][i],
            v: self.uv[1][i],
        })
    }

    /// Tests primitive `id` against the lanes of `mask` for their closest hits, as
    /// [`rt_core::leaf::test_primitives`] does for one ray: a hit within `[t_min, best t]` that
    /// beats the lane's best ([`Hit::beats`]) replaces it. Counts one primitive test per lane.
    #[inline(always)]
    pub fn intersect<P: Primitive, S: Stats>(
        &mut self,
        prim: &P,
        id: u32,
        mask: u64,
        stats: &mut S,
    ) {
        self.test::<P, S, false>(prim, id, mask, stats);
    }

    /// Tests primitive `id` against the lanes of `mask` for any hit within `[t_min, t_max]`;
    /// returns the lanes it blocks (their primitive becomes `id`). Counts one primitive test per
    /// lane.
    #[inline(always)]
    pub fn occluded<P: Primitive, S: Stats>(
        &mut self,
        prim: &P,
        id: u32,
        mask: u64,
        stats: &mut S,
    ) -> u64 {
        self.test::<P, S, true>(prim, id, mask, stats)
    }

    #[inline(always)]
    fn test<P: Primitive, S: Stats, const ANY: bool>(
        &mut self,
        prim: &P,
        id: u32,
        mask: u64,
        stats: &mut S,
    ) -> u64 {
        for _ in 0..mask.count_ones() {
            stats.prim_test();
        }
        match prim.as_triangle() {
            Some((tri, TriangleTest::Watertight)) => self.watertight::<ANY>(&tri, id, mask),
            _ => self.one_by_one::<P, ANY>(prim, id, mask),
        }
    }

    /// Any primitive, one lane at a time.
    #[inline(always)]
    fn one_by_one<P: Primitive, const ANY: bool>(&mut self, prim: &P, id: u32, mask: u64) -> u64 {
        let mut hit = 0;
        let mut m = mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            if let Some(h) = prim.intersect(&self.ray(i), self.t(i)) {
                if ANY {
                    self.prim[i] = id;
                    hit |= 1 << i;
                } else {
                    self.offer(i, id, h.t, h.u, h.v);
                }
            }
        }
        hit
    }

    /// Lane `i`'s hit of primitive `id`, kept if it beats the lane's best.
    #[inline(always)]
    fn offer(&mut self, i: usize, id: u32, t: f32, u: f32, v: f32) {
        if Hit::beats(t, id, self.t[i], self.prim[i]) {
            self.t[i] = t;
            self.prim[i] = id;
            self.uv[0][i] = u;
            self.uv[1][i] = v;
        }
    }

    /// The watertight test over the lanes of `mask`, grouped by dominant axis: sixteen lanes
    /// per step with AVX-512, else eight (AVX2, or the portable kernel).
    // PERF: sixteen lanes per AVX-512 step, called from the walks' AVX2 frame (see `Isa::run`),
    // against eight per inlined AVX2 step: the teapot's close view, primary rays in 8×8 tiles,
    // one thread, three alternating runs, Mrays/s: uniform grid 12.7 13.6 14.1 -> 15.0 14.4
    // 14.8, octree 21.8 23.8 24.1 -> 24.7 24.4 24.9, kd-tree 28.2 27.5 29.0 -> 27.7 28.6 29.7,
    // wide BVH 28.2 29.4 28.1 -> 27.3 31.9 31.4; the bunny's close view, primary and shadow
    // rays, 0-8% faster for every structure.
    #[inline(always)]
    fn watertight<const ANY: bool>(&mut self, tri: &Triangle, id: u32, mask: u64) -> u64 {
        match self.isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(s) => crate::x86::run_avx512(
                s,
                #[inline(always)]
                || self.steps_of::<16, _, ANY>(s, tri, id, mask),
            ),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(s) => crate::x86::run_avx2(
                s,
                #[inline(always)]
                || self.steps_of::<8, _, ANY>(s, tri, id, mask),
            ),
            _ => self.steps_of::<8, _, ANY>(Portable, tri, id, mask),
        }
    }

    /// [`Lanes::watertight`] `N` lanes per step with the operations of `s`.
    #[inline(always)]
    fn steps_of<const N: usize, S: Simd<N> + Keep<N>, const ANY: bool>(
        &mut self,
        s: S,
        tri: &Triangle,
        id: u32,
        mask: u64,
    ) -> u64 {
        let mut hit = 0;
        let all = if N == 64 { u64::MAX } else { (1u64 << N) - 1 };
        for step in 0..BUNDLE_LANES / N {
            let base = step * N;
            let in_step = mask >> base & all;
            if in_step == 0 {
                continue;
            }
            for axis in 0..3 {
                let m = in_step & self.bundle.by_axis[axis] >> base;
                if m != 0 {
                    let h = self.step::<N, S, ANY>(s, tri, id, step, self.order[axis], m as u32);
                    hit |= u64::from(h) << base;
                }
            }
        }
        hit
    }

    /// The watertight test of the lanes `m` of step `step` (lanes `N * step ..`), whose axis
    /// order is `k`, with [`watertight`](crate::watertight()); returns the lanes hit (for `ANY`)
    /// or whose best hit it became.
    #[inline(always)]
    fn step<const N: usize, S: Simd<N> + Keep<N>, const ANY: bool>(
        &mut self,
        s: S,
        tri: &Triangle,
        id: u32,
        step: usize,
        k: [usize; 3],
        m: u32,
    ) -> u32 {
        let [kx, ky, kz] = k;
        let b = self.bundle;
        let lanes = |v: &[f32; BUNDLE_LANES]| s.load(chunk::<f32, N>(v, step));
        let vertex = |p: rt_core::glam::Vec3| [s.splat(p[kx]), s.splat(p[ky]), s.splat(p[kz])];
        let hits = watertight(
            s,
            [vertex(tri.v0), vertex(tri.v1), vertex(tri.v2)],
            [
                lanes(&b.origin[kx]),
                lanes(&b.origin[ky]),
                lanes(&b.origin[kz]),
            ],
            [lanes(&b.shear[0]), lanes(&b.shear[1]), lanes(&b.shear[2])],
            lanes(&b.t_min),
            lanes(&self.t),
            m,
        );
        if hits.mask == 0 {
            return 0;
        }
        if ANY {
            let prim = chunk_mut::<u32, N>(&mut self.prim, step);
            for (j, p) in prim.iter_mut().enumerate() {
                *p = if hits.mask >> j & 1 != 0 { id } else { *p };
            }
            return hits.mask;
        }
        let [t, u, v] = [hits.t, hits.u, hits.v].map(|x| s.store(x));
        let [bu, bv] = &mut self.uv;
        let best = Best {
            t: chunk_mut::<f32, N>(&mut self.t, step),
            prim: chunk_mut::<u32, N>(&mut self.prim, step),
            u: chunk_mut::<f32, N>(bu, step),
            v: chunk_mut::<f32, N>(bv, step),
        };
        s.keep([&t, &u, &v], id, hits.mask, best)
    }
}

/// `N` lanes' best hits so far, as [`Lanes`] keeps them.
pub(crate) struct Best<'a, const N: usize> {
    pub t: &'a mut [f32; N],
    pub prim: &'a mut [u32; N],
    pub u: &'a mut [f32; N],
    pub v: &'a mut [f32; N],
}

/// The tie rule ([`Hit::beats`]) applied to `N` lanes' hits: each hit of `hits` (a bit per lane)
/// on primitive `id` replaces the lane's best where it beats it; returns the lanes whose best
/// it became. Lane by lane, unless an instruction set has a faster way.
pub(crate) trait Keep<const N: usize> {
    #[inline(always)]
    fn keep(self, out: [&[f32; N]; 3], id: u32, hits: u32, best: Best<'_, N>) -> u32
    where
        Self: Sized,
    {
        // Few of the lanes a primitive is tested against hit it, so the update goes lane by
        // lane.
        let mut kept = 0;
        let mut rest = hits;
        while rest != 0 {
            let j = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            if Hit::beats(out[0][j], id, best.t[j], best.prim[j]) {
                best.t[j] = out[0][j];
                best.prim[j] = id;
                best.u[j] = out[1][j];
                best.v[j] = out[2][j];
                kept |= 1 << j;
            }
        }
        kept
    }
}

impl Keep<8> for Portable {}
#[cfg(target_arch = "x86_64")]
impl Keep<8> for crate::Avx2 {}

/// With AVX-512, all sixteen lanes at once: the tie rule as vector comparisons and masked
/// stores.
// PERF: lane by lane, as the eight-lane kernels' hits are kept, the update was a loop over the
// inside lanes with a branch each, and a close view's big triangles have many (a private
// harness, the teapot's close view, 8×8 tiles, one thread, Mrays/s, two alternating runs of
// five passes, before -> after): wide BVH primary 36.9 33.9 -> 38.5 38.8, shadow 37.7 30.8 ->
// 41.3 40.7; kd-tree primary 21.8 20.8 -> 23.5 23.8; octree primary 16.9 16.7 -> 18.3 18.3;
// uniform grid primary 9.4 9.5 -> 10.0 10.0.
#[cfg(target_arch = "x86_64")]
impl Keep<16> for crate::Avx512 {
    #[inline(always)]
    fn keep(self, out: [&[f32; 16]; 3], id: u32, hits: u32, best: Best<'_, 16>) -> u32 {
        let best = crate::x86::Best16 {
            t: best.t,
            prim: best.prim,
            u: best.u,
            v: best.v,
        };
        u32::from(crate::x86::keep16_avx512(self, out, id, hits as u16, best))
    }
}

/// The lanes of `active` (lanes of bundle `b` that entered a cell's parent) that may enter
/// `cell`, whose best hits so far are in `lanes` and at most `t_hi`; 0 when none can.
///
/// - When `exact` is false and the first lane of `active` enters `cell` by its own slab test
///   ([`Bundle::lane_enters`]), all of `active`: coherent lanes mostly enter together, and one
///   lane's test is cheap (the first-active-lane rule of Wald, Boulos & Shirley 2007).
/// - Otherwise none when the bundle's interval bound rules the cell out for every lane
///   ([`Bundle::may_enter`]), else exactly the lanes whose own slab test passes
///   ([`Bundle::lanes_entering`]), eight per vector step; a walk asks for that at leaves, so
///   their tests run on as few vectors of lanes as can be.
///
/// Each answer holds every lane of `active` that enters `cell`, which is all a walk needs to
/// stay exact (a lane tested against more primitives keeps the same closest hit).
#[inline(always)]
pub fn narrow(b: &Bundle, lanes: &Lanes, cell: &Aabb, active: u64, t_hi: f32, exact: bool) -> u64 {
    if active == 0 {
        return 0;
    }
    let first = active.trailing_zeros() as usize;
    if !exact && b.lane_enters(first, cell, lanes.t(first)) {
        return active;
    }
    if !b.may_enter(cell, t_hi) {
        return 0;
    }
    b.lanes_entering(cell, lanes.best_t(), active)
}

/// Mailbox slots per bundle (see [`LaneMailbox`]).
pub const LANE_MAILBOX: usize = 128;

/// Tests the primitives `ids` (indices into `prims`) against the lanes of `lanes_in` that the
/// mailbox does not show tested already, skipping those whose box no lane of `b` can enter
/// before `t_hi`; returns the lanes blocked (for `ANY`; none otherwise).
///
/// The skip is the frustum culling of triangles of Wald et al.'s coherent grid traversal, with
/// [`Bundle::may_enter`]'s interval bound as the frustum: a lane that hits a primitive enters
/// its box at or before the hit, which its slab test finds (the test a BVH culls with), and the
/// bound is conservative for every lane's slab test.
///
/// The cells and leaves that list primitives by index (the grids, the octree, the kd-tree) test
/// them with this, with one [`LaneMailbox`] per bundle.
#[inline(always)]
pub fn test_primitives<P: Primitive, S: Stats, const ANY: bool>(
    prims: &[P],
    ids: &[u32],
    (b, t_hi): (&Bundle, f32),
    lanes: &mut Lanes,
    mut lanes_in: u64,
    mailbox: &mut LaneMailbox,
    stats: &mut S,
) -> u64 {
    let mut blocked = 0;
    for &id in ids {
        let untested = mailbox.untested(id, lanes_in);
        for _ in 0..(lanes_in & !untested).count_ones() {
            stats.mailbox_skip();
        }
        if untested == 0 {
            continue;
        }
        let prim = &prims[id as usize];
        // PERF: the uniform grid's primary rays in 8x8 tiles, bundles against single rays in
        // one run (`cargo xtask compare --scene S -s grid --bundle 8x8 -j 1`): without this
        // cull 2.67x on the teapot in a stadium, 2.36x on the sphereflake, 2.05x on the bunny;
        // with it 15.3x, 2.76x, 2.52x.
        if !b.may_enter(&prim.bounds(), t_hi) {
            continue;
        }
        if ANY {
            let hit = lanes.occluded(prim, id, untested, stats);
            blocked |= hit;
            lanes_in &= !hit;
            if lanes_in == 0 {
                break;
            }
        } else {
            lanes.intersect(prim, id, untested, stats);
        }
    }
    blocked
}

/// A bundle's mailbox: for the last primitive seen in each slot (its index modulo
/// [`LANE_MAILBOX`]),
/// the lanes it was tested against. A primitive met again in a later cell of the rectangle or a
/// later slice is tested only against lanes it was not tested against; a slot taken over by
/// another primitive only costs a second test, never a wrong answer.
#[derive(Clone, Debug)]
pub struct LaneMailbox {
    ids: [u32; LANE_MAILBOX],
    tested: [u64; LANE_MAILBOX],
}

impl Default for LaneMailbox {
    fn default() -> Self {
        Self::new()
    }
}

impl LaneMailbox {
    /// Every slot empty.
    pub fn new() -> Self {
        Self {
            ids: [u32::MAX; LANE_MAILBOX],
            tested: [0; LANE_MAILBOX],
        }
    }

    /// The lanes of `lanes` that primitive `id` has not been tested against; records them as
    /// tested.
    #[inline(always)]
    pub fn untested(&mut self, id: u32, lanes: u64) -> u64 {
        let k = id as usize % LANE_MAILBOX;
        if self.ids[k] != id {
            self.ids[k] = id;
            self.tested[k] = 0;
        }
        let new = lanes & !self.tested[k];
        self.tested[k] |= lanes;
        new
    }
}

#[cfg(test)]
mod tests {
    use crate::Isa;
    use rt_core::{Ray, Rng, glam::Vec3};

    /// Every instruction set's transpose of eight rays gives each ray's own fields, bit for
    /// bit, in the lane of its position.
    #[test]
    fn rays_transpose_into_their_lanes_on_every_instruction_set() {
        let mut rng = Rng::new(11);
        let rays: Vec<Ray> = (0..400)
            .map(|_| {
                let o = rng.in_box(Vec3::splat(-4.0), Vec3::splat(4.0));
                Ray::with_interval(o, rng.unit_vector(), rng.f32(), 1.0 + rng.f32())
            })
            .collect();
        let bits = |c: crate::columns::RayColumns| c.map(|v| v.map(f32::to_bits));
        for isa in Isa::all_available() {
            for eight in rays.as_chunks::<8>().0 {
                let got = bits(crate::bundle::ray_columns8(isa, eight));
                for (i, r) in eight.iter().enumerate() {
                    let (o, d, inv) = (r.origin, r.dir(), r.inv_dir());
                    let want = [
                        o.x, o.y, o.z, d.x, d.y, d.z, inv.x, inv.y, inv.z, r.t_min, r.t_max,
                    ];
                    for (k, w) in want.iter().enumerate() {
                        assert_eq!(got[k][i], w.to_bits(), "{isa:?}, field {k}, ray {i}");
                    }
                }
            }
        }
    }
}

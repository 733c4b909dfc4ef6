//! A bundle's lanes at the leaves: one primitive tested against many lanes at once, each lane
//! with exactly the arithmetic of its single-ray test.
//!
//! Structures whose cells or leaves list primitives by index (the kd-tree, the grids, the
//! octree) test each listed primitive against every lane of a [`Bundle`] that is still tracing.
//! For the watertight triangle ([`Triangle::intersect_watertight`]), [`Lanes`] runs the test
//! over eight lanes per step (sixteen with AVX-512), in vector instructions: every lane
//! takes the same operations in the same order as the scalar test (Rust never fuses a multiply
//! and an add unasked), so it gets the same bits of `t`, `u` and `v`. A lane whose edge
//! function is exactly zero, where the scalar test recomputes in `f64`, is handed to the scalar
//! test itself. Other primitives are tested lane by lane with [`Primitive::intersect`].
//!
//! Which lanes a primitive is tested against is the structure's choice: any lane may be tested
//! against any primitive, since a hit found is a true hit of that lane, and the closest of the
//! hits (ties to the smaller index) does not depend on which extra primitives were tried. A
//! structure must only make sure that every primitive its single-ray walk would test for a lane
//! is tested for that lane too.
//!
//! The vector kernels are chosen at run time ([`Isa`](crate::bundle::Isa): AVX-512 or AVX2
//! on x86-64 CPUs that have them); `RT_ACCEL_PORTABLE=1` forces the portable ones, which the
//! tests run too, as they run every kernel this CPU has.

use crate::bundle::{BUNDLE_LANES, Bundle};

use crate::{Aabb, Hit, Primitive, Ray, Shear, Stats, Triangle, TriangleTest};

/// Lanes per vector step.
pub(crate) const W: usize = 8;

/// Steps of [`W`] lanes in a bundle.
const STEPS: usize = BUNDLE_LANES / W;

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
    t: [[f32; W]; STEPS],
    /// ... its primitive (`u32::MAX` while none) ...
    prim: [[u32; W]; STEPS],
    /// ... and its `u`, `v`.
    uv: [[[f32; W]; STEPS]; 2],
    /// The vector instructions the kernels use.
    isa: crate::simd::Isa,
}

/// Lanes `8 * step ..` of a bundle's array.
#[inline(always)]
fn step8(v: &[f32; BUNDLE_LANES], step: usize) -> &[f32; W] {
    &v.as_chunks::<W>().0[step]
}

/// Lanes `16 * pair ..` of a bundle's array.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn pair16(v: &[f32; BUNDLE_LANES], pair: usize) -> &[f32; 16] {
    &v.as_chunks::<16>().0[pair]
}

impl<'b> Lanes<'b> {
    /// The lanes of `bundle`, none hit yet: each lane's best `t` is its `t_max`. The kernels
    /// use the best instructions this CPU has ([`Isa::detect`](crate::bundle::Isa::detect)).
    pub fn new(bundle: &'b Bundle) -> Self {
        Self::with_isa(bundle, crate::simd::Isa::detect())
    }

    /// [`Lanes::new`] with the kernels' instruction set chosen by the caller (the tests run
    /// each one); an instruction set this CPU lacks falls back to the portable kernels. Lanes
    /// past the bundle's length keep NaN as their best `t` and no primitive.
    // PERF: the lanes once kept copies of the bundle's rays and shears, copied in for each
    // bundle (4 KB a bundle); borrowing the bundle leaves 1 KB of best hits to set. The frame
    // around a bundle walk (a walk that does nothing, the teapot's close view) went from
    // 5.2-6.0 to 4.9 ns a ray. The wide BVH's bundles, the peers benchmark's close views, one
    // thread, medians of five alternating runs of a private harness, Mrays/s: the bunny 40.3
    // -> 41.6, the teapot 53.8 -> 61.5, the teapot in a stadium 62.1 -> 68.0, the sphereflake
    // 35.6 -> 36.7.
    #[inline(always)]
    pub fn with_isa(bundle: &'b Bundle, isa: crate::simd::Isa) -> Self {
        let isa = if isa.available() {
            isa
        } else {
            crate::simd::Isa::Portable
        };
        let mut t = [[f32::NAN; W]; STEPS];
        let flat: &mut [f32; BUNDLE_LANES] = t
            .as_flattened_mut()
            .try_into()
            .expect("STEPS vectors of W lanes");
        *flat = bundle.t_max;
        flat[bundle.len()..].fill(f32::NAN);
        Self {
            bundle,
            order: crate::bundle::shear_orders(bundle.octant()),
            t,
            prim: [[u32::MAX; W]; STEPS],
            uv: [[[0.0; W]; STEPS]; 2],
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
        self.t[i / W][i % W]
    }

    /// Every lane's best `t` so far (lanes past the bundle's length hold NaN).
    #[inline(always)]
    pub fn best_t(&self) -> &[f32; BUNDLE_LANES] {
        self.t
            .as_flattened()
            .try_into()
            .expect("the steps hold BUNDLE_LANES lanes")
    }

    /// The instruction set the kernels run with: a walk that calls them from a frame of its own
    /// compiles that frame for it, so that they inline.
    #[inline(always)]
    pub fn isa(&self) -> crate::simd::Isa {
        self.isa
    }

    /// How many vector steps the watertight test of one triangle against the lanes of `mask`
    /// takes (with lanes of one dominant axis): the occupied groups of sixteen lanes with
    /// AVX-512, else of eight. A walk weighs testing a leaf's triangles ray-parallel, with
    /// these lanes, against testing each lane alone.
    #[inline(always)]
    pub fn steps(&self, mask: u64) -> usize {
        #[cfg(target_arch = "x86_64")]
        if self.isa == crate::simd::Isa::Avx512 {
            return (0..BUNDLE_LANES / 16)
                .filter(|g| (mask >> (16 * g)) as u16 != 0)
                .count();
        }
        (0..STEPS).filter(|g| (mask >> (W * g)) as u8 != 0).count()
    }

    /// The largest best `t` over the lanes, which bounds every lane's best hit from here on (a
    /// lane's best only shrinks; lanes past the bundle's length are ignored).
    // PERF: written over whole vectors of lanes, so that it compiles to vector maxima: a loop
    // over the live lanes' bits with `f32::max` was a tenth of the BVH's bundle traversal's
    // samples (`perf record`, bunny primary rays, 8×8 tiles).
    #[inline(always)]
    pub fn far_end(&self) -> f32 {
        let mut hi = [f32::NEG_INFINITY; W];
        for step in &self.t {
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
        let (step, j) = (i / W, i % W);
        Hit {
            prim: self.prim[step][j],
            t: self.t[step][j],
            u: self.uv[0][step][j],
            v: self.uv[1][step][j],
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
        self.prim[i / W][i % W] = id;
    }

    /// Lane `i`'s answer: its closest hit, if any.
    #[inline(always)]
    pub fn hit(&self, i: usize) -> Option<Hit> {
        // Indexed in the flattened arrays: one scaled index per field.
        let prim = self.prim.as_flattened()[i];
        (prim != u32::MAX).then_some(Hit {
            prim,
            t: self.t.as_flattened()[i],
            u: self.uv[0].as_flattened()[i],
            v: self.uv[1].as_flattened()[i],
        })
    }

    /// Tests primitive `id` against the lanes of `mask` for their closest hits, as
    /// [`leaf::test_primitives`](crate::leaf::test_primitives) does for one ray: a hit within
    /// `[t_min, best t]` that beats the lane's best ([`Hit::beats`]) replaces it. Counts one
    /// primitive test per lane.
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
                    self.prim[i / W][i % W] = id;
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
        let (step, j) = (i / W, i % W);
        if Hit::beats(t, id, self.t[step][j], self.prim[step][j]) {
            self.t[step][j] = t;
            self.prim[step][j] = id;
            self.uv[0][step][j] = u;
            self.uv[1][step][j] = v;
        }
    }

    /// The watertight test over the lanes of `mask`, grouped by dominant axis: sixteen lanes
    /// per step with AVX-512, else eight.
    // PERF: sixteen lanes per AVX-512 step, called from the walks' AVX2 frame (see `Isa::run`),
    // against eight per inlined AVX2 step: the teapot's close view, primary rays in 8×8 tiles,
    // one thread, three alternating runs, Mrays/s: uniform grid 12.7 13.6 14.1 -> 15.0 14.4
    // 14.8, octree 21.8 23.8 24.1 -> 24.7 24.4 24.9, kd-tree 28.2 27.5 29.0 -> 27.7 28.6 29.7,
    // wide BVH 28.2 29.4 28.1 -> 27.3 31.9 31.4; the bunny's close view, primary and shadow
    // rays, 0-8% faster for every structure.
    #[inline(always)]
    fn watertight<const ANY: bool>(&mut self, tri: &Triangle, id: u32, mask: u64) -> u64 {
        let mut hit = 0;
        #[cfg(target_arch = "x86_64")]
        if self.isa == crate::simd::Isa::Avx512 {
            return crate::simd::in_avx512(
                self.isa,
                #[inline(always)]
                || self.watertight_pairs::<ANY>(tri, id, mask),
            );
        }
        for step in 0..STEPS {
            let in_step = (mask >> (step * W)) as u8;
            if in_step == 0 {
                continue;
            }
            for axis in 0..3 {
                let m = in_step & (self.bundle.by_axis[axis] >> (step * W)) as u8;
                if m != 0 {
                    let h = self.watertight_step::<ANY>(tri, id, step, self.order[axis], m);
                    hit |= u64::from(h) << (step * W);
                }
            }
        }
        hit
    }

    /// [`Lanes::watertight`] sixteen lanes per step, run compiled with AVX-512
    /// ([`crate::simd::in_avx512`]) so that the kernel and the update of each lane's best
    /// inline into one function per triangle.
    // PERF: with the kernel called alone from the AVX2 frame, its outputs went through memory
    // to the update. The wide BVH's bundles, close views, one thread, two alternating runs of
    // a private harness, Mrays/s, before -> after: the teapot's primary rays 41.6 44.5 ->
    // 43.0 46.4, shadow rays 49.2 46.6 -> 51.6 51.6; the bunny's primary 34.0 34.9 -> 36.2
    // 34.5, shadow 33.0 31.6 -> 34.2 33.9; the kd-tree, octree and grid within noise.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn watertight_pairs<const ANY: bool>(&mut self, tri: &Triangle, id: u32, mask: u64) -> u64 {
        let mut hit = 0;
        for pair in 0..STEPS / 2 {
            let base = pair * 2 * W;
            let in_pair = (mask >> base) as u16;
            if in_pair == 0 {
                continue;
            }
            for axis in 0..3 {
                let m = in_pair & (self.bundle.by_axis[axis] >> base) as u16;
                if m != 0 {
                    let h = self.watertight16::<ANY>(tri, id, pair, self.order[axis], m);
                    hit |= u64::from(h) << base;
                }
            }
        }
        hit
    }

    /// The triangle's vertices in the axis order `k`, as the kernels take them.
    #[inline(always)]
    fn vertices(tri: &Triangle, k: [usize; 3]) -> [f32; 9] {
        let [kx, ky, kz] = k;
        [
            tri.v0[kx], tri.v0[ky], tri.v0[kz], tri.v1[kx], tri.v1[ky], tri.v1[kz], tri.v2[kx],
            tri.v2[ky], tri.v2[kz],
        ]
    }

    /// [`Triangle::intersect_sheared`] for the lanes `m` of step `step`, whose axis order is `k`;
    /// returns the lanes hit (for `ANY`) or whose best hit it became.
    #[inline(always)]
    fn watertight_step<const ANY: bool>(
        &mut self,
        tri: &Triangle,
        id: u32,
        step: usize,
        k: [usize; 3],
        m: u8,
    ) -> u8 {
        let [kx, ky, kz] = k;
        let input = Step8 {
            origin: [
                step8(&self.bundle.origin[kx], step),
                step8(&self.bundle.origin[ky], step),
                step8(&self.bundle.origin[kz], step),
            ],
            shear: [
                step8(&self.bundle.shear[0], step),
                step8(&self.bundle.shear[1], step),
                step8(&self.bundle.shear[2], step),
            ],
            t_min: step8(&self.bundle.t_min, step),
            t_max: &self.t[step],
            active: m,
        };
        let out = crate::simd::watertight8(self.isa, &Self::vertices(tri, k), &input);
        let (inside, zero) = (u32::from(out.inside), u32::from(out.zero));
        let o = (&out.t[..], &out.u[..], &out.v[..]);
        self.settle::<ANY>(tri, id, step * W, u32::from(m), inside, zero, o) as u8
    }

    /// [`Lanes::watertight_step`] for the sixteen lanes of steps `2 * pair` and `2 * pair + 1`.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn watertight16<const ANY: bool>(
        &mut self,
        tri: &Triangle,
        id: u32,
        pair: usize,
        k: [usize; 3],
        m: u16,
    ) -> u16 {
        let [kx, ky, kz] = k;
        fn at(v: &[[f32; W]; STEPS], pair: usize) -> &[f32; 16] {
            &v.as_flattened().as_chunks::<16>().0[pair]
        }
        fn at_mut<T>(v: &mut [[T; W]; STEPS], pair: usize) -> &mut [T; 16] {
            &mut v.as_flattened_mut().as_chunks_mut::<16>().0[pair]
        }
        let input = Step16 {
            origin: [
                pair16(&self.bundle.origin[kx], pair),
                pair16(&self.bundle.origin[ky], pair),
                pair16(&self.bundle.origin[kz], pair),
            ],
            shear: [
                pair16(&self.bundle.shear[0], pair),
                pair16(&self.bundle.shear[1], pair),
                pair16(&self.bundle.shear[2], pair),
            ],
            t_min: pair16(&self.bundle.t_min, pair),
            t_max: at(&self.t, pair),
            active: m,
        };
        // Only `watertight` calls this, and only when `self.isa` is `Isa::Avx512`.
        let Some(out) = crate::simd::watertight16(self.isa, &Self::vertices(tri, k), &input) else {
            return 0;
        };
        // The lanes inside are kept all at once, by the tie rule as vector comparisons and
        // masked stores; those with an edge function of zero go to the scalar test in `settle`.
        // PERF: lane by lane, as `settle` keeps the AVX2 kernel's hits, the update was a loop
        // over the inside lanes with a branch each, and a close view's big triangles have many
        // (a private harness, the teapot's close view, 8×8 tiles, one thread, Mrays/s, two
        // alternating runs of five passes, before -> after): wide BVH primary 36.9 33.9 ->
        // 38.5 38.8, shadow 37.7 30.8 -> 41.3 40.7; kd-tree primary 21.8 20.8 -> 23.5 23.8;
        // octree primary 16.9 16.7 -> 18.3 18.3; uniform grid primary 9.4 9.5 -> 10.0 10.0.
        let inside = out.inside & m & !out.zero;
        let mut hit = 0;
        if inside != 0 {
            hit = if ANY {
                let prim = at_mut(&mut self.prim, pair);
                for (j, p) in prim.iter_mut().enumerate() {
                    *p = if inside >> j & 1 != 0 { id } else { *p };
                }
                inside
            } else {
                let [u, v] = &mut self.uv;
                let best = crate::simd::Best16 {
                    t: at_mut(&mut self.t, pair),
                    prim: at_mut(&mut self.prim, pair),
                    u: at_mut(u, pair),
                    v: at_mut(v, pair),
                };
                match crate::simd::keep16(self.isa, &out, id, inside, best) {
                    Some(kept) => kept,
                    // Only with AVX-512, which `watertight16` answering shows; lane by lane
                    // otherwise, never dropped.
                    None => {
                        let o = (&out.t[..], &out.u[..], &out.v[..]);
                        let base = pair * 2 * W;
                        self.settle::<ANY>(
                            tri,
                            id,
                            base,
                            u32::from(inside),
                            u32::from(inside),
                            0,
                            o,
                        ) as u16
                    }
                }
            };
        }
        if out.zero & m != 0 {
            let o = (&out.t[..], &out.u[..], &out.v[..]);
            let zero = u32::from(out.zero);
            hit |= self.settle::<ANY>(tri, id, pair * 2 * W, u32::from(m), 0, zero, o) as u16;
        }
        hit
    }

    /// What a kernel found for the lanes `m` from lane `base` on (bit `j` is lane `base + j`,
    /// whose `t`, `u`, `v` are at `j` of `out`), kept where it beats each lane's best; returns
    /// the lanes hit (for `ANY`) or whose best hit it became.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn settle<const ANY: bool>(
        &mut self,
        tri: &Triangle,
        id: u32,
        base: usize,
        m: u32,
        inside: u32,
        zero: u32,
        out: (&[f32], &[f32], &[f32]),
    ) -> u32 {
        let mut hit = 0u32;
        // Lanes whose hit lies in their interval: few of the lanes a primitive is tested
        // against, so the tie rule and the update go lane by lane.
        let mut rest = inside & m & !zero;
        while rest != 0 {
            let j = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let i = base + j;
            let (step, l) = (i / W, i % W);
            if ANY {
                self.prim[step][l] = id;
                hit |= 1 << j;
            } else if Hit::beats(out.0[j], id, self.t[step][l], self.prim[step][l]) {
                self.offer(i, id, out.0[j], out.1[j], out.2[j]);
                hit |= 1 << j;
            }
        }
        // Lanes with an edge function of exactly zero: the scalar test, which decides them in
        // `f64`, so they too answer exactly as their single ray.
        let mut rest = zero & m;
        while rest != 0 {
            let j = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let i = base + j;
            let (step, l) = (i / W, i % W);
            let ray = self.ray(i);
            if let Some(h) = tri.intersect_sheared(&Shear::new(ray.dir()), &ray, self.t(i)) {
                if ANY {
                    self.prim[step][l] = id;
                    hit |= 1 << j;
                } else if Hit::beats(h.t, id, self.t(i), self.prim[step][l]) {
                    self.offer(i, id, h.t, h.u, h.v);
                    hit |= 1 << j;
                }
            }
        }
        hit
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

/// Eight lanes' input to the watertight test ([`crate::simd::watertight8`]): origins in the
/// lanes' axis order `kx`, `ky`, `kz`, their shears `sx`, `sy`, `sz`, and their intervals.
pub(crate) struct Step8<'a> {
    pub origin: [&'a [f32; W]; 3],
    pub shear: [&'a [f32; W]; 3],
    pub t_min: &'a [f32; W],
    pub t_max: &'a [f32; W],
    /// The lanes whose outputs the caller reads; a kernel may leave the others' unset. Only
    /// the AVX2 kernel uses it (to skip work no active lane needs); the portable one computes
    /// every lane in one loop, so on targets without AVX2 nothing reads it.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub active: u8,
}

/// Sixteen lanes' input to the watertight test ([`crate::simd::watertight16`]): two
/// [`Step8`]s that lie one after the other in memory.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Step16<'a> {
    pub origin: [&'a [f32; 16]; 3],
    pub shear: [&'a [f32; 16]; 3],
    pub t_min: &'a [f32; 16],
    pub t_max: &'a [f32; 16],
    /// The lanes whose outputs the caller reads.
    pub active: u16,
}

/// Sixteen lanes' watertight test, as [`Out8`].
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Out16 {
    pub t: [f32; 16],
    pub u: [f32; 16],
    pub v: [f32; 16],
    pub inside: u16,
    pub zero: u16,
}

/// Eight lanes' watertight test: `t`, `u`, `v` of each, the lanes whose hit lies in their
/// interval, and the lanes with an edge function of exactly zero (whose other outputs are to
/// be ignored: the scalar test decides them).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Out8 {
    pub t: [f32; W],
    pub u: [f32; W],
    pub v: [f32; W],
    pub inside: u8,
    pub zero: u8,
}

/// [`Triangle::intersect_sheared`] for eight lanes, in plain arrays: the portable kernel, and
/// the reference the vector kernels match bit for bit. `verts` holds the three vertices in the
/// lanes' axis order.
#[inline(always)]
pub(crate) fn watertight8_portable(verts: &[f32; 9], input: &Step8) -> Out8 {
    let [ox, oy, oz] = input.origin;
    let [sx, sy, sz] = input.shear;
    let mut out = Out8::default();
    for j in 0..W {
        // The vertices relative to the origin, in the lane's axis order, then sheared; the
        // same operations in the same order as the scalar test.
        let (ax, ay, az) = (verts[0] - ox[j], verts[1] - oy[j], verts[2] - oz[j]);
        let (bx, by, bz) = (verts[3] - ox[j], verts[4] - oy[j], verts[5] - oz[j]);
        let (cx, cy, cz) = (verts[6] - ox[j], verts[7] - oy[j], verts[8] - oz[j]);
        let (ax, ay) = (ax - sx[j] * az, ay - sy[j] * az);
        let (bx, by) = (bx - sx[j] * bz, by - sy[j] * bz);
        let (cx, cy) = (cx - sx[j] * cz, cy - sy[j] * cz);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = u == 0.0 || v == 0.0 || w == 0.0;
        let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
        let det = u + v + w;
        let (az, bz, cz) = (sz[j] * az, sz[j] * bz, sz[j] * cz);
        let inv = 1.0 / det;
        let t = (u * az + v * bz + w * cz) * inv;
        let inside =
            !outside && det != 0.0 && !det.is_nan() && t >= input.t_min[j] && t <= input.t_max[j];
        out.t[j] = t;
        out.u[j] = v * inv;
        out.v[j] = w * inv;
        out.inside |= u8::from(inside) << j;
        out.zero |= u8::from(zero) << j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bundle::{Group, Isa, for_each_bundle};
    use crate::{Rng, glam::Vec3};

    /// Triangles and rays where the watertight test is hard: shared edges and vertices hit
    /// exactly (edge functions of exactly zero), axis-aligned triangles, grazing and
    /// parallel rays, ties between copies, and random ones.
    fn cases() -> (Vec<Triangle>, Vec<Ray>) {
        let mut rng = Rng::new(11);
        let mut tris = vec![
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y),
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(Vec3::ZERO, Vec3::Z, Vec3::Y),
            Triangle::new(
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(2.0, 0.0, 1.0),
                Vec3::new(0.0, 2.0, 1.0),
            ),
            // Edge functions that overflow to infinities and NaN, and ones all zero.
            Triangle::new(
                Vec3::splat(3e38),
                Vec3::new(-3e38, 3e38, 0.0),
                Vec3::new(0.0, -3e38, 3e38),
            ),
            Triangle::new(
                Vec3::new(1e20, 0.0, 0.0),
                Vec3::new(0.0, 1e20, 0.0),
                Vec3::new(0.0, 0.0, 1e20),
            ),
            Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE),
        ];
        for _ in 0..40 {
            let c = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
            tris.push(Triangle::new(
                c + rng.unit_vector(),
                c + rng.unit_vector(),
                c + rng.unit_vector(),
            ));
        }
        let mut rays = Vec::new();
        let origin = Vec3::new(0.25, 0.5, -3.0);
        for k in 0..=8 {
            for l in 0..=8 {
                // Through the lattice of quarter points: vertices and edges of the first two
                // triangles exactly.
                let to = Vec3::new(k as f32 * 0.125, l as f32 * 0.125, 0.0);
                rays.push(Ray::new(origin, to - origin));
                rays.push(Ray::new(to - Vec3::Z, Vec3::Z));
            }
        }
        for _ in 0..600 {
            let o = rng.in_box(Vec3::splat(-4.0), Vec3::splat(4.0));
            let t = tris[rng.below(tris.len() as u32) as usize];
            let aim = t.v0 + (t.v1 - t.v0) * rng.f32() * 0.5 + (t.v2 - t.v0) * rng.f32() * 0.5;
            rays.push(Ray::with_interval(
                o,
                aim - o,
                rng.f32() * 0.5,
                0.5 + rng.f32() * 2.0,
            ));
        }
        (tris, rays)
    }

    /// Every instruction set's transpose of eight rays gives each ray's own fields, bit for
    /// bit, in the lane of its position.
    #[test]
    fn rays_transpose_into_their_lanes_on_every_instruction_set() {
        let (_, rays) = cases();
        let bits = |c: crate::simd::RayColumns| c.map(|v| v.map(f32::to_bits));
        for isa in Isa::all_available() {
            for eight in rays.as_chunks::<8>().0 {
                let got = bits(crate::simd::ray_columns8(isa, eight));
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

    /// Every lane of every bundle, on every instruction set, gets the scalar test's answer bit
    /// for bit: closest hits over all triangles (ties to the smaller index), and any hits.
    #[test]
    fn lanes_answer_as_the_scalar_test_on_every_instruction_set() {
        let (tris, rays) = cases();
        let isas = Isa::all_available();
        assert!(isas.len() > 1 || !cfg!(target_arch = "x86_64"), "{isas:?}");
        for isa in isas {
            for_each_bundle(&rays, |group| {
                let Group::Bundle(b) = group else { return };
                let mut lanes = Lanes::with_isa(b, isa);
                let mut any = Lanes::with_isa(b, isa);
                let mut blocked = 0u64;
                for (id, tri) in tris.iter().enumerate() {
                    lanes.intersect(tri, id as u32, b.all_lanes(), &mut crate::NoStats);
                    blocked |= any.occluded(
                        tri,
                        id as u32,
                        b.all_lanes() & !blocked,
                        &mut crate::NoStats,
                    );
                }
                for i in 0..b.len() {
                    let ray = b.ray(i);
                    let mut best = Hit {
                        prim: u32::MAX,
                        t: ray.t_max,
                        u: 0.0,
                        v: 0.0,
                    };
                    for (id, tri) in tris.iter().enumerate() {
                        if let Some(h) = tri.intersect(&ray, best.t)
                            && Hit::beats(h.t, id as u32, best.t, best.prim)
                        {
                            best = Hit {
                                prim: id as u32,
                                t: h.t,
                                u: h.u,
                                v: h.v,
                            };
                        }
                    }
                    let want = (best.prim != u32::MAX).then_some(best);
                    let got = lanes.hit(i);
                    let bits = |h: Option<Hit>| {
                        h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
                    };
                    assert_eq!(bits(got), bits(want), "{isa:?}, lane {i}, ray {ray:?}");
                    let occluded = tris.iter().any(|t| t.intersect(&ray, ray.t_max).is_some());
                    assert_eq!(
                        blocked >> i & 1 != 0,
                        occluded,
                        "{isa:?}, lane {i}, ray {ray:?}"
                    );
                    // The answer a walk reads for the lane, too: `Some` exactly when blocked.
                    assert_eq!(
                        any.hit(i).is_some(),
                        occluded,
                        "{isa:?}, lane {i}, ray {ray:?}"
                    );
                }
            });
        }
    }
}

//! Ray bundles: the rays a structure's packet walk traces together, and what every such walk
//! needs.
//!
//! [`Accel::intersect_bundle`](rt_core::Accel::intersect_bundle) and
//! [`Accel::occluded_bundle`](rt_core::Accel::occluded_bundle) answer a slice of rays (the
//! contract, and how a bundle's steps count, are in `rt_core::bundle`). A structure that
//! traces coherent rays together takes them as [`Bundle`]s, made by [`for_each_bundle`]: up
//! to [`BUNDLE_LANES`] valid rays of one direction octant, in structure-of-arrays form, with
//! bounds over the lanes ([`Bundle::may_enter`]) that cull a box for all of them in one test.
//! Rays a bundle cannot carry (invalid rays, and rays with a zero or tiny direction component,
//! whose reciprocal is infinite) are handed back one by one, to be answered by the single-ray
//! query, which answers invalid rays at once, as it always does. [`walk_groups`] is the frame
//! every structure's bundle queries share: sorting, routing, single-ray fallback, answers;
//! [`walk_groups_ordered`] the same for rays taken in a given order (the ordered bundle
//! queries, which gather each run of rays an order lists).
//!
//! At the leaves, [`Lanes`] tests one primitive against many lanes, eight per vector step
//! with AVX2 and sixteen with AVX-512 when the CPU has them, each lane with exactly its
//! single-ray arithmetic ([`watertight`](crate::watertight())).

mod brute;
mod lanes;
mod walk;

pub use brute::BundledBruteForce;
pub use lanes::{LANE_MAILBOX, LaneMailbox, Lanes, narrow, test_primitives};
pub use walk::{
    BLOCKED, Group, Route, for_each_bundle, single, slots_of, walk_groups, walk_groups_ordered,
};

use crate::Isa;
#[cfg(target_arch = "x86_64")]
use crate::columns::FillTarget;
use crate::columns::{RayColumns, Sealed, ray_columns8_portable};
use crate::vector::{fold_hi, fold_lo};
use crate::watertight::shear_orders;
use glam::Vec3;
use rt_core::{Aabb, Ray, SLAB_FAR_SCALE};

/// The most rays one [`Bundle`] carries: a bit per lane in a `u64` mask.
pub const BUNDLE_LANES: usize = 64;

/// Up to [`BUNDLE_LANES`] valid rays whose direction components have the same signs (one
/// octant) and finite, non-zero reciprocals, in structure-of-arrays form.
///
/// Lane `i` is the ray `rays[slot[i]]` of the slice it was made from; its origin, direction,
/// reciprocal direction and interval are the ray's own values, bit for bit, so a structure's
/// lane-by-lane tests compute exactly what its single-ray tests compute for that ray.
#[derive(Clone, Debug)]
pub struct Bundle {
    len: usize,
    /// For each lane, the index of its ray in the slice the bundle was made from.
    pub slot: [u32; BUNDLE_LANES],
    /// Origins, per axis.
    pub origin: [[f32; BUNDLE_LANES]; 3],
    /// Directions, per axis.
    pub dir: [[f32; BUNDLE_LANES]; 3],
    /// Reciprocal directions, per axis ([`Ray::inv_dir`]).
    pub inv_dir: [[f32; BUNDLE_LANES]; 3],
    /// `t_min` of each lane.
    pub t_min: [f32; BUNDLE_LANES],
    /// `t_max` of each lane.
    pub t_max: [f32; BUNDLE_LANES],
    /// `sx`, `sy`, `sz` of each lane's watertight [`Shear`](rt_core::Shear), made once with the
    /// lanes' other values so that every leaf kernel reads them ([`Lanes`]).
    pub(crate) shear: [[f32; BUNDLE_LANES]; 3],
    /// The lanes whose dominant axis ([`Shear::kz`](rt_core::Shear)) is `a`, for each axis `a`.
    pub(crate) by_axis: [u64; 3],
    octant: usize,
    origin_lo: Vec3,
    origin_hi: Vec3,
    inv_lo: Vec3,
    inv_hi: Vec3,
    t_min_lo: f32,
}

impl Bundle {
    fn empty(octant: usize) -> Self {
        Self {
            len: 0,
            slot: [0; BUNDLE_LANES],
            origin: [[0.0; BUNDLE_LANES]; 3],
            dir: [[0.0; BUNDLE_LANES]; 3],
            inv_dir: [[0.0; BUNDLE_LANES]; 3],
            t_min: [0.0; BUNDLE_LANES],
            t_max: [0.0; BUNDLE_LANES],
            shear: [[0.0; BUNDLE_LANES]; 3],
            by_axis: [0; 3],
            octant,
            origin_lo: Vec3::INFINITY,
            origin_hi: Vec3::NEG_INFINITY,
            inv_lo: Vec3::INFINITY,
            inv_hi: Vec3::NEG_INFINITY,
            t_min_lo: f32::INFINITY,
        }
    }

    /// Empties the bundle for reuse. Only the length is reset: the lanes' arrays past the
    /// length are never read for an answer (every reader stops at [`Bundle::len`] or masks with
    /// [`Bundle::all_lanes`]), and rewriting them cost a tenth of the time of rays that then go
    /// singly; [`Bundle::seal`] makes the bounds anew.
    fn clear(&mut self) {
        self.len = 0;
    }

    /// Writes `ray` into lane `i`.
    #[inline(always)]
    fn set(&mut self, i: usize, slot: u32, ray: &Ray) {
        self.slot[i] = slot;
        let (o, d, inv) = (ray.origin, ray.dir(), ray.inv_dir());
        for a in 0..3 {
            self.origin[a][i] = o[a];
            self.dir[a][i] = d[a];
            self.inv_dir[a][i] = inv[a];
        }
        self.t_min[i] = ray.t_min;
        self.t_max[i] = ray.t_max;
    }

    /// Writes the rays of `run` (at most [`BUNDLE_LANES`], the first at index `base` of the
    /// slice) into lanes `0..run.len()`, eight at a time as a transpose with `isa`.
    // PERF: everything around a bundle walk (`walk_groups` with a walk that does nothing;
    // the teapot's close view, primary rays in 8×8 tiles, one thread, two alternating runs of
    // a private harness) took 10.3 ns a ray with each ray written field by field, 9.3 ns with
    // the transpose.
    #[inline(always)]
    fn fill(&mut self, isa: Isa, run: &[Ray], base: usize) {
        let (eights, rest) = run.as_chunks::<8>();
        for (g, rays) in eights.iter().enumerate() {
            let c = ray_columns8(isa, rays);
            for a in 0..3 {
                self.origin[a].as_chunks_mut::<8>().0[g] = c[a];
                self.dir[a].as_chunks_mut::<8>().0[g] = c[3 + a];
                self.inv_dir[a].as_chunks_mut::<8>().0[g] = c[6 + a];
            }
            self.t_min.as_chunks_mut::<8>().0[g] = c[9];
            self.t_max.as_chunks_mut::<8>().0[g] = c[10];
        }
        let done = eights.len() * 8;
        for (k, ray) in rest.iter().enumerate() {
            self.set(done + k, (done + k + base) as u32, ray);
        }
        for (k, slot) in self.slot[..run.len()].iter_mut().enumerate() {
            *slot = (base + k) as u32;
        }
        self.len = run.len();
    }

    /// Adds `ray` as the next lane; the bounds over the lanes wait for [`Bundle::seal`].
    #[inline(always)]
    fn push(&mut self, slot: u32, ray: &Ray) {
        self.set(self.len, slot, ray);
        self.len += 1;
    }

    /// Makes the bounds over the lanes ([`Bundle::lane_bounds`]) once all lanes are in. The
    /// lanes past the length up to the next multiple of eight become copies of lane 0 first, so
    /// that the bounds (and any reader of whole vectors of eight lanes) see only real rays'
    /// values, and the minima and maxima run over whole vectors.
    #[inline(always)]
    fn seal(&mut self) {
        const W: usize = 8;
        let (len, full) = (self.len, self.len.next_multiple_of(W));
        for i in len..full {
            for a in 0..3 {
                self.origin[a][i] = self.origin[a][0];
                self.dir[a][i] = self.dir[a][0];
                self.inv_dir[a][i] = self.inv_dir[a][0];
            }
            self.t_min[i] = self.t_min[0];
            self.t_max[i] = self.t_max[0];
        }
        let groups = full / W;
        // The smallest and largest of the first `groups` vectors of `v`. Every value is finite
        // (the lanes are valid rays), so `<` picks as `min` does.
        // PERF: starting from infinities with the new value on the left of each comparison,
        // the compiler reversed the vectors at every step; written this way, the frame of the
        // `Bundle::fill` measurement took 7.3 ns a ray instead of 8.3.
        #[inline(always)]
        fn range(v: &[f32; BUNDLE_LANES], groups: usize) -> (f32, f32) {
            let chunks = &v.as_chunks::<W>().0[..groups.max(1)];
            let (mut lo, mut hi) = (chunks[0], chunks[0]);
            for c in &chunks[1..] {
                for j in 0..W {
                    lo[j] = if lo[j] < c[j] { lo[j] } else { c[j] };
                    hi[j] = if hi[j] > c[j] { hi[j] } else { c[j] };
                }
            }
            (fold_lo(lo), fold_hi(hi))
        }
        // Written out axis by axis: closures passed to `array::map` are not inlined into the
        // vector frame the walks run in (`Isa::run`).
        let (ox, oy, oz) = (
            range(&self.origin[0], groups),
            range(&self.origin[1], groups),
            range(&self.origin[2], groups),
        );
        let (ix, iy, iz) = (
            range(&self.inv_dir[0], groups),
            range(&self.inv_dir[1], groups),
            range(&self.inv_dir[2], groups),
        );
        self.origin_lo = Vec3::new(ox.0, oy.0, oz.0);
        self.origin_hi = Vec3::new(ox.1, oy.1, oz.1);
        self.inv_lo = Vec3::new(ix.0, iy.0, iz.0);
        self.inv_hi = Vec3::new(ix.1, iy.1, iz.1);
        self.t_min_lo = range(&self.t_min, groups).0;
        self.shear_lanes(groups);
    }

    /// Each lane's shear ([`Shear::new`](rt_core::Shear::new) of its direction) for the first
    /// `groups` vectors of eight lanes, eight lanes at a time: the same comparisons pick the
    /// dominant axis, the ray's reciprocal is the same division, and the same products make
    /// the factors, so every lane's are the scalar ones, bit for bit.
    // PERF: with a branch per axis around the division, the compiler divided three times per
    // lane on half-width vectors, with masked stores (the frame around a bundle walk took 9.3
    // ns a ray then, 8.4 ns with the loops below, which have no branch).
    #[inline(always)]
    fn shear_lanes(&mut self, groups: usize) {
        const W: usize = 8;
        let order = shear_orders(self.octant);
        self.by_axis = [0; 3];
        let all = self.all_lanes();
        for g in 0..groups {
            let at = |v: &[f32; BUNDLE_LANES]| v.as_chunks::<W>().0[g];
            // Not `array::map`, whose closure is not inlined into the walks' vector frame.
            let d = [at(&self.dir[0]), at(&self.dir[1]), at(&self.dir[2])];
            let inv = [
                at(&self.inv_dir[0]),
                at(&self.inv_dir[1]),
                at(&self.inv_dir[2]),
            ];
            // The rows each dominant axis reads, chosen once per group (the octant fixes
            // them), so that the lanes below pick among whole vectors. The last is the
            // reciprocal of the dominant component: `Shear::new` divides `1` by it, as
            // `Ray::inv_dir` was made, so the ray's own reciprocal is those bits.
            let rows = |kz: usize| [d[order[kz][0]], d[order[kz][1]], inv[order[kz][2]]];
            let (rx, ry, rz) = (rows(0), rows(1), rows(2));
            let (mut x, mut y) = ([false; W], [false; W]);
            let mut p = [[0.0f32; W]; 3];
            for j in 0..W {
                let (ax, ay, az) = (d[0][j].abs(), d[1][j].abs(), d[2][j].abs());
                // `Shear::new`'s choice: x if it is at least both others, else y if it is at
                // least z, else z.
                x[j] = (ax >= ay) & (ax >= az);
                y[j] = !x[j] & (ay >= az);
                for k in 0..3 {
                    let yz = if y[j] { ry[k][j] } else { rz[k][j] };
                    p[k][j] = if x[j] { rx[k][j] } else { yz };
                }
            }
            let (mut on_x, mut on_y) = (0u64, 0u64);
            for j in 0..W {
                let sz = p[2][j];
                self.shear[0][g * W + j] = p[0][j] * sz;
                self.shear[1][g * W + j] = p[1][j] * sz;
                self.shear[2][g * W + j] = sz;
                on_x |= u64::from(x[j]) << j;
                on_y |= u64::from(y[j]) << j;
            }
            let valid = all >> (g * W) & 0xff;
            self.by_axis[0] |= (on_x & valid) << (g * W);
            self.by_axis[1] |= (on_y & valid) << (g * W);
            self.by_axis[2] |= (!(on_x | on_y) & valid) << (g * W);
        }
    }

    /// Fills the bundle with `run` (at most [`BUNDLE_LANES`] rays, the first at index `base` of
    /// the slice) and seals it when every ray bundles in octant `o`; false (the bundle then
    /// holds nothing of use) when one does not.
    ///
    /// With AVX2 and a run of whole groups of eight (a camera's tile), in one pass over the
    /// rays: each group transposed, checked, bounded and sheared in registers
    /// (`x86::fill_sealed`), with the same comparisons and arithmetic as
    /// [`Bundle::fill`], [`Bundle::all_bundle_in`] and [`Bundle::seal`] make in turn
    /// otherwise, so either way gives the same bundle.
    // PERF: in turn, the three passes and each lane's shear (then made when `Lanes` was reset)
    // took 4.3 ns a ray of the 7.0 around a bundle walk (`walk_groups` with a walk that does
    // nothing: the teapot in a stadium, primary rays in 8×8 tiles, one thread, a private
    // harness); 5.65 ns in one pass, most of it now the wait for the rays from memory. The wide
    // BVH's bundles, the views of the peers benchmark's framing, medians of four alternating
    // runs, Mrays/s, before -> after: the bunny 54.4 -> 55.8, the teapot 66.2 -> 68.0, the
    // sphereflake 63.7 -> 66.4, the teapot in a stadium 57.6 -> 58.9; the kd-tree's on the
    // stadium's own view 30.3 -> 32.7 (medians of three).
    #[inline(always)]
    fn fill_sealed(&mut self, isa: Isa, run: &[Ray], base: usize, o: usize) -> bool {
        let (eights, rest) = run.as_chunks::<8>();
        let filled = if rest.is_empty() && !eights.is_empty() && eights.len() <= 8 {
            self.fill_sealed_x86(isa, eights, o)
        } else {
            None
        };
        match filled {
            Some(sealed) => {
                for (k, slot) in self.slot[..run.len()].iter_mut().enumerate() {
                    *slot = (base + k) as u32;
                }
                self.len = run.len();
                self.octant = o;
                self.origin_lo = Vec3::from(sealed.origin_lo);
                self.origin_hi = Vec3::from(sealed.origin_hi);
                self.inv_lo = Vec3::from(sealed.inv_lo);
                self.inv_hi = Vec3::from(sealed.inv_hi);
                self.t_min_lo = sealed.t_min_lo;
                sealed.good
            }
            None => {
                self.fill(isa, run, base);
                if !self.all_bundle_in(o) {
                    return false;
                }
                self.octant = o;
                self.seal();
                true
            }
        }
    }

    /// [`Bundle::fill_sealed`]'s one pass with AVX2 (and AVX-512VL where the CPU has it) for
    /// one to eight groups of eight rays; `None` with other instruction sets, which make the
    /// same bundle in passes of their own.
    #[inline(always)]
    fn fill_sealed_x86(&mut self, isa: Isa, rays: &[[Ray; 8]], o: usize) -> Option<Sealed> {
        #[cfg(target_arch = "x86_64")]
        if let Some(s) = isa.avx2_proof() {
            let target = FillTarget {
                origin: &mut self.origin,
                dir: &mut self.dir,
                inv_dir: &mut self.inv_dir,
                t_min: &mut self.t_min,
                t_max: &mut self.t_max,
                shear: &mut self.shear,
                by_axis: &mut self.by_axis,
            };
            let vl = matches!(isa, Isa::Avx512(_));
            return Some(crate::x86::fill_sealed_avx2(
                s,
                vl,
                target,
                rays,
                o,
                shear_orders(o),
            ));
        }
        let _ = (isa, rays, o);
        None
    }

    /// Whether every lane's ray would bundle ([`bundles_ray`]) and points into octant `o`: the
    /// same conditions, lane by lane over the arrays, in vectors of lanes.
    #[inline(always)]
    fn all_bundle_in(&self, o: usize) -> bool {
        const W: usize = 8;
        let n = self.len;
        let (lo, hi) = (*Ray::DIR_RANGE.start(), *Ray::DIR_RANGE.end());
        // Each condition over vectors of eight lanes, in one pass with no branch per lane: a
        // lane past the length counts as good.
        // PERF: as a pass over each array in turn, the frame of `Bundle::fill`'s measurement
        // took 7.3 ns a ray; 6.9 ns in one pass.
        let mut bad = [false; W];
        for g in 0..n.div_ceil(W) {
            let at = |v: &[f32; BUNDLE_LANES]| v.as_chunks::<W>().0[g];
            let (o3, d3, i3) = (
                [
                    at(&self.origin[0]),
                    at(&self.origin[1]),
                    at(&self.origin[2]),
                ],
                [at(&self.dir[0]), at(&self.dir[1]), at(&self.dir[2])],
                [
                    at(&self.inv_dir[0]),
                    at(&self.inv_dir[1]),
                    at(&self.inv_dir[2]),
                ],
            );
            let (t0, t1) = (at(&self.t_min), at(&self.t_max));
            for j in 0..W {
                let mut b = false;
                for a in 0..3 {
                    let negative = o >> a & 1 != 0;
                    // False for NaN too: one comparison for both conditions.
                    let within = o3[a][j].abs() <= Ray::MAX_ORIGIN;
                    b |= !within;
                    b |= !d3[a][j].is_finite()
                        | (d3[a][j] == 0.0)
                        | (d3[a][j].is_sign_negative() != negative);
                    b |= !i3[a][j].is_finite();
                }
                // The components are finite here (or the lane is bad already), so `max` is
                // exact.
                let largest = d3[0][j].abs().max(d3[1][j].abs()).max(d3[2][j].abs());
                b |= !((largest >= lo) & (largest <= hi));
                b |= !((t0[j] >= 0.0) & t0[j].is_finite() & (t0[j] <= t1[j]));
                bad[j] |= b & (g * W + j < n);
            }
        }
        !bad.iter().any(|&b| b)
    }

    /// How many lanes the bundle carries (1 to [`BUNDLE_LANES`]).
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: [`for_each_bundle`] makes no empty bundle.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The mask of all lanes: bit `i` set for every lane `i < len`.
    #[inline(always)]
    pub fn all_lanes(&self) -> u64 {
        if self.len == BUNDLE_LANES {
            u64::MAX
        } else {
            (1 << self.len) - 1
        }
    }

    /// The direction octant: bit `a` set when the lanes' direction along axis `a` is negative.
    #[inline(always)]
    pub fn octant(&self) -> usize {
        self.octant
    }

    /// The bounds over the lanes that [`Bundle::may_enter`] uses, for a structure that runs the
    /// same test in its own vectors (several boxes at once).
    #[inline(always)]
    pub fn lane_bounds(&self) -> LaneBounds {
        LaneBounds {
            origin_lo: self.origin_lo,
            origin_hi: self.origin_hi,
            inv_dir_lo: self.inv_lo,
            inv_dir_hi: self.inv_hi,
            t_min_lo: self.t_min_lo,
        }
    }

    /// The axis along which the first lane travels fastest (its direction's largest component;
    /// the lowest axis on ties). Structures that walk a bundle in slices or in one child order
    /// take it as the bundle's major axis.
    #[inline]
    pub fn major_axis(&self) -> usize {
        let d = [0, 1, 2].map(|a| self.dir[a][0].abs());
        if d[0] >= d[1] && d[0] >= d[2] {
            0
        } else if d[1] >= d[2] {
            1
        } else {
            2
        }
    }

    /// For the axes `major + 1` and `major + 2` (mod 3), the smallest and largest slope
    /// `d_axis / d_major = inv_major / inv_axis` over the corners of the lanes' reciprocal
    /// bounds: in constant time, an interval that holds every lane's slope up to rounding, and
    /// so how far apart the lanes' directions may be.
    #[inline]
    pub fn slope_bounds(&self, major: usize) -> [(f32, f32); 2] {
        let (lo, hi) = (self.inv_lo.to_array(), self.inv_hi.to_array());
        // Four quotients per axis in one vector division each (the same quotients; the bounds
        // are finite and non-zero, so none is NaN and the extremes are those of a fold).
        // PERF: eight scalar divisions were 2% of a profile of the wide BVH's bundles; with
        // these, its close views (private harness, one thread, medians of five alternating
        // runs, Mrays/s) went: the sphereflake 38.6 -> 39.0, the bunny 42.6 -> 43.0, the teapot
        // 62.9 -> 62.8, the teapot in a stadium 69.5 -> 70.1.
        [(major + 1) % 3, (major + 2) % 3].map(|a| {
            let r = glam::Vec4::new(lo[major], lo[major], hi[major], hi[major])
                / glam::Vec4::new(lo[a], hi[a], lo[a], hi[a]);
            (r.min_element(), r.max_element())
        })
    }

    /// How far apart the lanes' directions may be: the widths of [`Bundle::slope_bounds`] across
    /// the [major axis](Bundle::major_axis), summed over the two other axes (about the angle, in
    /// radians, that the lanes spread over). Constant time, so rays in random directions cost
    /// little before a structure sends them singly.
    #[inline]
    pub fn direction_spread(&self) -> f32 {
        self.slope_bounds(self.major_axis())
            .iter()
            .map(|(lo, hi)| hi - lo)
            .sum()
    }

    /// Whether lane `i`'s own slab test against `bounds` succeeds with `t_max` (its best hit so
    /// far): one lane of [`Bundle::lanes_entering`], the same operations. A packet walk that
    /// tests its first active lane this way, and all of them only when it fails, pays one
    /// lane's test at most nodes of a coherent bundle (the first-active-lane rule of Wald,
    /// Boulos & Shirley 2007).
    #[inline(always)]
    pub fn lane_enters(&self, i: usize, bounds: &Aabb, t_max: f32) -> bool {
        let (mut t0, mut t1) = (self.t_min[i], t_max);
        for a in 0..3 {
            let (near, far) = if self.octant >> a & 1 != 0 {
                (bounds.max[a], bounds.min[a])
            } else {
                (bounds.min[a], bounds.max[a])
            };
            let (o, inv) = (self.origin[a][i], self.inv_dir[a][i]);
            let tn = (near - o) * inv;
            let tf = (far - o) * inv;
            t0 = if tn > t0 { tn } else { t0 };
            t1 = if tf < t1 { tf } else { t1 };
        }
        t0 <= t1 * SLAB_FAR_SCALE
    }

    /// The lanes of `active` whose own slab test against `bounds` succeeds with their own
    /// `t_max[i]` (a lane's best hit so far): lane by lane, the operations of [`Aabb::intersect`]
    /// in the same order (no NaN arises: a lane's reciprocals are finite and non-zero), eight
    /// lanes per step in a form the compiler vectorises.
    ///
    /// A structure whose cells hold every primitive that overlaps them can send a leaf only the
    /// lanes this returns: a lane's closest hit lies in the closed cell of a leaf that lists its
    /// primitive, the lane's slab test enters that cell at or before the hit (widened by
    /// [`SLAB_FAR_SCALE`], as every single-ray walk here allows), so the leaf is tested for it.
    #[inline(always)]
    pub fn lanes_entering(&self, bounds: &Aabb, t_max: &[f32; BUNDLE_LANES], active: u64) -> u64 {
        const W: usize = 8;
        // Written out axis by axis: closures passed to `array::map` are not inlined into the
        // vector frame the walks run in (`Isa::run`).
        let plane = |a: usize| {
            if self.octant >> a & 1 != 0 {
                (bounds.max[a], bounds.min[a])
            } else {
                (bounds.min[a], bounds.max[a])
            }
        };
        let planes = [plane(0), plane(1), plane(2)];
        let mut mask = 0u64;
        for g in 0..BUNDLE_LANES / W {
            if (active >> (W * g)) as u8 == 0 {
                continue;
            }
            let mut t0 = self.t_min.as_chunks::<W>().0[g];
            let mut t1 = t_max.as_chunks::<W>().0[g];
            for (a, &(near, far)) in planes.iter().enumerate() {
                let o = &self.origin[a].as_chunks::<W>().0[g];
                let inv = &self.inv_dir[a].as_chunks::<W>().0[g];
                for i in 0..W {
                    let tn = (near - o[i]) * inv[i];
                    let tf = (far - o[i]) * inv[i];
                    t0[i] = if tn > t0[i] { tn } else { t0[i] };
                    t1[i] = if tf < t1[i] { tf } else { t1[i] };
                }
            }
            let mut bits = 0u64;
            for i in 0..W {
                bits |= u64::from(t0[i] <= t1[i] * SLAB_FAR_SCALE) << i;
            }
            mask |= bits << (W * g);
        }
        mask & active
    }

    /// How [`walk_groups`] should take this bundle through a structure whose primitives all lie
    /// in `bounds`, which its single walk tests first: [`Route::Miss`] when no lane can enter
    /// `bounds` ([`Bundle::may_enter`]; then no lane's single walk gets past that test, or could
    /// hit a primitive inside), else [`Route::Walk`] when `walk` accepts the bundle (coherent
    /// enough for the structure's walk to pay), else [`Route::Singly`].
    #[inline]
    pub fn route(&self, bounds: &Aabb, walk: impl FnOnce(&Bundle) -> bool) -> Route {
        if !self.may_enter(bounds, f32::INFINITY) {
            Route::Miss
        } else if walk(self) {
            Route::Walk
        } else {
            Route::Singly
        }
    }

    /// Lane `i` as a ray: the same bits as the ray it came from.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        let v = |a: &[[f32; BUNDLE_LANES]; 3]| Vec3::new(a[0][i], a[1][i], a[2][i]);
        // The stored reciprocal is the ray's own, so nothing is divided again.
        Ray::from_parts(
            v(&self.origin),
            v(&self.dir),
            v(&self.inv_dir),
            self.t_min[i],
            self.t_max[i],
        )
    }

    /// Whether any lane may enter `bounds` within `[t_min, t_max_hi]`, where `t_max_hi` is at
    /// least every lane's current `t_max` (its best hit so far). False only when no lane's
    /// [`Aabb::intersect`] with its own `t_max` can succeed, so a box this rejects can be
    /// skipped for the whole bundle.
    ///
    /// Why it is conservative: a lane's slab distance along an axis is `fl(fl(p - o)·r)` for the
    /// plane `p`, its origin `o` and reciprocal `r`. `o` lies in `[origin_lo, origin_hi]` and `r`
    /// in `[inv_lo, inv_hi]` (the same sign, finite and non-zero, so no product is NaN). Rounding
    /// is monotone, so `fl(p - o)` lies between `fl(p - origin_hi)` and `fl(p - origin_lo)`, and
    /// the exact product of two values in intervals lies between the smallest and the largest
    /// product of the intervals' ends; rounding those ends bounds the lane's rounded product.
    /// So the largest lower bound of the near distances (and `t_min`) is at most the lane's
    /// entry, the smallest upper bound of the far distances (and `t_max_hi`) at least its exit,
    /// and widening both by [`SLAB_FAR_SCALE`] keeps the order: if the bound's entry exceeds
    /// the bound's widened exit, every lane's does.
    #[inline(always)]
    pub fn may_enter(&self, bounds: &Aabb, t_max_hi: f32) -> bool {
        let mut t0 = self.t_min_lo;
        let mut t1 = t_max_hi;
        for a in 0..3 {
            let negative = self.octant >> a & 1 != 0;
            let (near, far) = if negative {
                (bounds.max[a], bounds.min[a])
            } else {
                (bounds.min[a], bounds.max[a])
            };
            let (lo, hi) = (self.inv_lo[a], self.inv_hi[a]);
            // The near distance's lower bound and the far distance's upper bound.
            let (n0, n1) = (near - self.origin_hi[a], near - self.origin_lo[a]);
            let near_lo = (n0 * lo).min(n0 * hi).min(n1 * lo).min(n1 * hi);
            let (f0, f1) = (far - self.origin_hi[a], far - self.origin_lo[a]);
            let far_hi = (f0 * lo).max(f0 * hi).max(f1 * lo).max(f1 * hi);
            t0 = t0.max(near_lo);
            t1 = t1.min(far_hi);
        }
        t0 <= t1 * SLAB_FAR_SCALE
    }
}

/// The smallest and largest origin and reciprocal direction, per axis, and the smallest `t_min`
/// over the lanes of a [`Bundle`] (see [`Bundle::may_enter`] for what they bound and why).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaneBounds {
    /// The smallest origin coordinate of any lane, per axis.
    pub origin_lo: Vec3,
    /// The largest origin coordinate of any lane, per axis.
    pub origin_hi: Vec3,
    /// The smallest reciprocal direction of any lane, per axis (all of one sign).
    pub inv_dir_lo: Vec3,
    /// The largest reciprocal direction of any lane, per axis.
    pub inv_dir_hi: Vec3,
    /// The smallest `t_min` of any lane.
    pub t_min_lo: f32,
}

/// Eight rays transposed into [`RayColumns`] with instruction set `isa`: the same values
/// either way, only moved.
#[inline(always)]
pub(crate) fn ray_columns8(isa: Isa, rays: &[Ray; 8]) -> RayColumns {
    #[cfg(target_arch = "x86_64")]
    if let Some(s) = isa.avx2_proof() {
        return crate::x86::ray_columns8_avx2(s, rays);
    }
    let _ = isa;
    ray_columns8_portable(rays)
}

/// Whether a ray can travel in a bundle: valid, with every direction component non-zero and a
/// finite reciprocal.
#[inline]
pub fn bundles_ray(ray: &Ray) -> bool {
    // `Ray::is_valid`'s conditions and the bundle's own, combined with `&` rather than `&&`:
    // straight-line code with no branch to mispredict, for every ray of every bundle call.
    let (d, inv) = (ray.dir(), ray.inv_dir());
    let largest = d.abs().max_element();
    ray.origin.abs().cmple(Vec3::splat(Ray::MAX_ORIGIN)).all()
        & d.is_finite()
        & (largest >= *Ray::DIR_RANGE.start())
        & (largest <= *Ray::DIR_RANGE.end())
        & (ray.t_min >= 0.0)
        & ray.t_min.is_finite()
        & (ray.t_min <= ray.t_max)
        & inv.is_finite()
        & d.cmpne(Vec3::ZERO).all()
}

/// The direction octant of a ray: bit `a` set when its direction along axis `a` is negative
/// (`-0.0` counts as negative, as the slab tests read it).
#[inline]
pub fn octant(ray: &Ray) -> usize {
    let d = ray.dir();
    (d.x.is_sign_negative() as usize)
        | (d.y.is_sign_negative() as usize) << 1
        | (d.z.is_sign_negative() as usize) << 2
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::Rng;

    fn random_rays(seed: u64, n: usize) -> Vec<Ray> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|_| {
                Ray::new(
                    rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0)),
                    rng.unit_vector(),
                )
            })
            .collect()
    }

    #[test]
    fn every_ray_goes_to_exactly_one_bundle_lane_or_to_single() {
        let mut rays = random_rays(1, 300);
        rays[5] = Ray::new(Vec3::ZERO, Vec3::X); // zero components: single
        rays[77] = Ray::new(Vec3::NAN, Vec3::X); // invalid: single
        let mut seen = vec![0; rays.len()];
        for_each_bundle(&rays, |g| match g {
            Group::Bundle(b) => {
                assert!(!b.is_empty() && b.len() <= BUNDLE_LANES);
                for i in 0..b.len() {
                    let slot = b.slot[i] as usize;
                    seen[slot] += 1;
                    assert_eq!(octant(&rays[slot]), b.octant());
                    assert_eq!(b.ray(i), rays[slot]);
                    // Lanes keep the rays' order.
                    assert!(i == 0 || b.slot[i - 1] < b.slot[i]);
                }
            }
            Group::Single(slot, ray) => {
                assert!(!bundles_ray(ray));
                seen[slot] += 1;
            }
        });
        assert!(seen.iter().all(|&c| c == 1));
    }

    #[test]
    fn bundles_ray_is_validity_and_non_zero_finite_reciprocals() {
        // Values at and beyond every limit the test names, in every component.
        let specials = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            1e-40,
            1e-30,
            1e30,
            Ray::MAX_ORIGIN,
            Ray::MAX_ORIGIN * 2.0,
            *Ray::DIR_RANGE.start(),
            *Ray::DIR_RANGE.start() * 0.5,
            *Ray::DIR_RANGE.end(),
            *Ray::DIR_RANGE.end() * 2.0,
        ];
        let mut rng = Rng::new(3);
        let pick = |rng: &mut Rng| specials[rng.below(specials.len() as u32) as usize];
        let (mut yes, mut no) = (0, 0);
        for _ in 0..20_000 {
            let v = |rng: &mut Rng| Vec3::new(pick(rng), pick(rng), pick(rng));
            let (o, d) = (v(&mut rng), v(&mut rng));
            let (t0, t1) = (pick(&mut rng).abs(), pick(&mut rng));
            let ray = Ray::with_interval(o, d, t0, t1);
            let expected =
                ray.is_valid() && ray.inv_dir().is_finite() && ray.dir().cmpne(Vec3::ZERO).all();
            assert_eq!(bundles_ray(&ray), expected, "{ray:?}");
            if expected { yes += 1 } else { no += 1 }
        }
        assert!(yes > 100 && no > 100, "{yes} {no}");
    }

    #[test]
    fn a_run_fills_one_bundle_exactly_when_every_ray_bundles_in_its_octant() {
        // Runs of coherent rays, each spoiled (or not) by one ray from the special values; half
        // of them whole groups of eight, which AVX2 fills in one pass.
        let mut rng = Rng::new(5);
        let (mut whole, mut split) = (0, 0);
        let isas = Isa::all_available();
        for round in 0..3000 {
            let d = rng.unit_vector();
            let len = if round % 2 == 0 {
                8 * (1 + round / 2 % 8)
            } else {
                1 + round % BUNDLE_LANES
            };
            let mut run: Vec<Ray> = (0..len)
                .map(|_| Ray::new(rng.in_box(Vec3::ZERO, Vec3::ONE), d))
                .collect();
            let k = rng.below(run.len() as u32) as usize;
            match round % 9 {
                0 => run[k] = Ray::new(run[k].origin, -d),
                1 => run[k] = Ray::new(Vec3::NAN, d),
                2 => run[k] = Ray::new(run[k].origin, Vec3::new(d.x, 0.0, d.z)),
                3 => run[k] = Ray::with_interval(run[k].origin, d, 2.0, 1.0),
                4 => run[k] = Ray::new(run[k].origin, d * 1e-40),
                5 => run[k] = Ray::new(Vec3::new(0.0, f32::INFINITY, 0.0), d),
                6 => run[k] = Ray::with_interval(run[k].origin, d, 0.0, f32::NAN),
                _ => {}
            }
            let o = octant(&run[0]);
            let expected = run.iter().all(|r| bundles_ray(r) && octant(r) == o);
            let mut b = Bundle::empty(o);
            for (i, ray) in run.iter().enumerate() {
                b.set(i, i as u32, ray);
            }
            b.len = run.len();
            assert_eq!(b.all_bundle_in(o), expected, "round {round}");
            if expected {
                whole += 1
            } else {
                split += 1
            }
            // Every instruction set's one pass finds the same, and when the run bundles, fills
            // the same bundle as the passes in turn: the same bits in every lane, the same
            // bounds, and each lane's shear the scalar one.
            let mut want = Bundle::empty(o);
            assert_eq!(want.fill_sealed(Isa::Portable, &run, 3, o), expected);
            for &isa in &isas {
                let mut got = Bundle::empty(7 - o);
                assert_eq!(
                    got.fill_sealed(isa, &run, 3, o),
                    expected,
                    "{isa:?} {round}"
                );
                if !expected {
                    continue;
                }
                let n = run.len();
                let lanes = |b: &Bundle| {
                    let mut v: Vec<u32> = b.slot[..n].to_vec();
                    for a in 0..3 {
                        for arr in [&b.origin[a], &b.dir[a], &b.inv_dir[a], &b.shear[a]] {
                            v.extend(arr[..n].iter().map(|x| x.to_bits()));
                        }
                    }
                    for arr in [&b.t_min, &b.t_max] {
                        v.extend(arr[..n].iter().map(|x| x.to_bits()));
                    }
                    (
                        v,
                        b.by_axis,
                        b.len,
                        b.octant,
                        format!("{:?}", b.lane_bounds()),
                    )
                };
                assert_eq!(lanes(&got), lanes(&want), "{isa:?}, round {round}");
                for (i, ray) in run.iter().enumerate() {
                    let s = rt_core::Shear::new(ray.dir());
                    let axis = (0..3).find(|&a| got.by_axis[a] >> i & 1 != 0);
                    assert_eq!(axis, Some(s.kz), "{isa:?}, round {round}, lane {i}");
                    let bits = [s.sx, s.sy, s.sz].map(f32::to_bits);
                    let lane = [0, 1, 2].map(|k| got.shear[k][i].to_bits());
                    assert_eq!(lane, bits, "{isa:?}, round {round}, lane {i}");
                    let [kx, ky, _] = shear_orders(o)[s.kz];
                    assert_eq!((kx, ky), (s.kx, s.ky), "{isa:?}, round {round}, lane {i}");
                }
            }
        }
        assert!(whole > 500 && split > 500, "{whole} {split}");
    }

    #[test]
    fn may_enter_never_rejects_a_box_a_lane_enters() {
        let mut rng = Rng::new(7);
        let (mut entered_some, mut rejected_some) = (0, 0);
        for round in 0..2000 {
            // Nearly parallel rays from nearby origins, as a camera tile makes, and boxes
            // around, beside and behind them.
            let spread = [1e-6, 1e-3, 0.1, 1.0][round % 4];
            let o = rng.in_box(Vec3::splat(-3.0), Vec3::splat(3.0));
            let d = rng.unit_vector();
            let rays: Vec<Ray> = (0..16)
                .map(|_| {
                    Ray::with_interval(
                        o + rng.unit_vector() * spread,
                        d + rng.unit_vector() * spread,
                        rng.f32() * 0.1,
                        1.0 + rng.f32() * 10.0,
                    )
                })
                .collect();
            // Half the boxes on the bundle's path, half anywhere.
            let c = if round % 2 == 0 {
                o + d * rng.f32() * 8.0 + rng.unit_vector() * rng.f32()
            } else {
                rng.in_box(Vec3::splat(-4.0), Vec3::splat(4.0))
            };
            let h = rng.in_box(Vec3::ZERO, Vec3::splat(1.0));
            let bounds = Aabb::new(c - h, c + h);
            for_each_bundle(&rays, |g| {
                let Group::Bundle(b) = g else { return };
                {
                    let entered = (0..b.len()).any(|i| {
                        let r = b.ray(i);
                        bounds.intersect(&r, r.t_max).is_some()
                    });
                    let t_hi = b.t_max[..b.len()].iter().copied().fold(0.0, f32::max);
                    let may = b.may_enter(&bounds, t_hi);
                    assert!(!entered || may, "{bounds:?} {b:?}");
                    entered_some += entered as u32;
                    rejected_some += !may as u32;
                }
            });
        }
        // The cases include both kinds, so the check above means something.
        assert!(
            entered_some > 500 && rejected_some > 500,
            "{entered_some} {rejected_some}"
        );
    }

    #[test]
    fn lanes_entering_is_each_lanes_own_slab_test() {
        // Bundles of nearby rays and boxes on and off their path, with each lane's own `t_max`;
        // every lane's bit must be its `Aabb::intersect`. (`RT_ACCEL_PORTABLE=1` runs the
        // portable mask instead of the vector one.)
        let mut rng = Rng::new(11);
        let (mut entered, mut missed) = (0, 0);
        for round in 0..2000 {
            let o = rng.in_box(Vec3::splat(-3.0), Vec3::splat(3.0));
            let d = rng.unit_vector();
            let spread = [1e-3, 0.1, 0.5][round % 3];
            let rays: Vec<Ray> = (0..1 + round % BUNDLE_LANES)
                .map(|_| {
                    Ray::with_interval(
                        o + rng.unit_vector() * spread,
                        d + rng.unit_vector() * spread * 0.1,
                        0.0,
                        1.0 + rng.f32() * 8.0,
                    )
                })
                .collect();
            let c = o + d * rng.f32() * 6.0 + rng.unit_vector() * rng.f32();
            let h = rng.in_box(Vec3::splat(0.05), Vec3::splat(1.0));
            let bounds = Aabb::new(c - h, c + h);
            for_each_bundle(&rays, |g| {
                let Group::Bundle(b) = g else { return };
                let mut t_max = [f32::NAN; BUNDLE_LANES];
                for (i, t) in t_max[..b.len()].iter_mut().enumerate() {
                    *t = b.t_max[i] * rng.f32();
                }
                let mask = b.lanes_entering(&bounds, &t_max, b.all_lanes());
                for (i, &t) in t_max[..b.len()].iter().enumerate() {
                    let own = bounds.intersect(&b.ray(i), t).is_some();
                    assert_eq!(mask >> i & 1 != 0, own, "round {round} lane {i}");
                    if own { entered += 1 } else { missed += 1 }
                }
            });
        }
        assert!(entered > 1000 && missed > 1000, "{entered} {missed}");
    }

    #[test]
    fn may_enter_rejects_boxes_the_bundle_passes_by() {
        let rays: Vec<Ray> = (0..8)
            .map(|i| {
                Ray::new(
                    Vec3::new(i as f32 * 0.01, 0.0, 0.0),
                    Vec3::new(0.1, 0.2, 1.0),
                )
            })
            .collect();
        let mut checked = 0;
        for_each_bundle(&rays, |g| {
            let Group::Bundle(b) = g else {
                panic!("every ray bundles")
            };
            {
                assert_eq!(b.len(), 8);
                let ahead = Aabb::new(Vec3::new(-1.0, -1.0, 5.0), Vec3::new(2.0, 2.0, 6.0));
                let aside = Aabb::new(Vec3::new(5.0, 5.0, -1.0), Vec3::new(6.0, 6.0, 1.0));
                assert!(b.may_enter(&ahead, f32::INFINITY));
                assert!(!b.may_enter(&aside, f32::INFINITY));
                // Beyond every lane's best hit so far.
                assert!(!b.may_enter(&ahead, 4.0));
                checked += 1;
            }
        });
        assert_eq!(checked, 1);
    }
}

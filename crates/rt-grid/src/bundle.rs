//! Bundles through the grid: coherent grid traversal (Wald, Ize, Kensler, Knoll & Parker 2006,
//! "Ray tracing animated scenes using coherent grid traversal").
//!
//! A bundle walks the grid one slice at a time along its major axis (the axis its lanes travel
//! along fastest). In each slice it covers the rectangle of cells that any live lane's segment
//! crosses there, and tests each primitive listed in those cells once for the whole bundle,
//! against all live lanes ([`Lanes`], eight lanes per vector step), where single rays walk the
//! same cells one ray at a time and test the same primitives once per ray. A per-bundle mailbox
//! keeps a primitive listed in several cells of the rectangle, or of consecutive slices, from
//! being tested again.
//!
//! # Exact
//! Each lane answers exactly as its single ray. Every hit a lane records is a true hit of its
//! own test ([`Lanes`] runs each lane's own arithmetic), so the closest of them (ties to the
//! smaller index) is the single ray's answer, the closest true hit, which the conformance kit
//! checks the single walk finds, as long as the bundle tests, for each lane, the primitives
//! listed in every cell whose closed box the lane's line meets before its best hit. It does: a
//! slice's rectangle holds every cell whose box a crossing lane's line meets between the
//! slice's planes, its coordinates widened by a bound on their rounding error and its cells
//! found by comparison with the builder's planes; each lane starts one slice before the first
//! cell of its single walk; and a lane stops only at a slice whose near plane lies beyond its
//! best hit, as the single walk stops after the cell it leaves beyond it.
//!
//! The hierarchical grid (rt-hgrid) walks each of its levels with the same [`walk_slices`] and
//! [`test_primitives`].
//!
//! A slice's rectangle of nine cells or more is not tested whole for every
//! crossing lane: each cell is tested for the lanes whose own coordinates in the slice, widened
//! as the rectangle's are, come near the cell (rounded up to whole vector steps of eight lanes),
//! so each lane still tests every cell its single walk enters.
//!
//! # When single rays are cheaper
//! A rectangle much wider than its lanes (rays that spread, or an incoherent set) makes every
//! lane test primitives of cells it never crosses. Before each slice the walk compares the
//! rectangle's cells, times the vector steps a test takes, with the cells the live lanes
//! cross one by one; when the bundle would cost more, the live lanes finish as single rays.

use crate::Grid;
use crate::cell::GridShape;
use crate::dda::{RayAxes, first_cell};
use rt_core::{Hit, Primitive, Ray, SLAB_FAR_SCALE, Stats};
use rt_simd::bundle::{BUNDLE_LANES, Bundle, LaneMailbox, Lanes, test_primitives};

/// The most cells per slice a bundle's rectangle may widen by, summed over its two axes, for the
/// bundle to walk together ([`coherent`]).
// PERF: without this test, incoherent rays (`compare --rays incoherent --bundle 8x8 -j 1`) ran
// at 0.11-0.17x their single rays on four scenes (bundles that fell back only after walking
// slices); with it at 0.93-0.99x, primary and shadow rays unchanged within noise.
pub const MAX_SPREAD: f32 = 1.0;

/// A bundle keeps walking while its cost so far (cells of its rectangles times the vector steps
/// their tests take) is at most this many times what single rays would have cost (the cells each
/// lane's own segment meets), plus [`COST_SLACK`].
const MAX_COST_RATIO: f32 = 2.0;

/// Slack for the first slices, where lanes that have not entered yet make a bundle look
/// wasteful.
const COST_SLACK: f32 = 16.0;

/// The cells of one axis, inclusive.
type Span = (u32, u32);

/// `mask` widened to whole vector steps of eight lanes: every lane of each step that holds one
/// of `mask`'s. A primitive's test costs the same for one lane of a step as for all eight, and
/// splitting a step's lanes between two cells that list the same primitive would test it twice.
#[inline(always)]
fn whole_steps(mask: u64) -> u64 {
    u64::from_le_bytes(mask.to_le_bytes().map(|b| if b != 0 { 0xff } else { 0 }))
}

/// The fewest cells in a slice's rectangle for which the bundle tests each cell for its own
/// lanes ([`Frame::lanes_per_cell`]) rather than for every lane crossing the slice.
const WIDE_RECTANGLE: f32 = 9.0;

/// The widest rectangle, in cells along one axis, whose cells a bundle tests each for its own
/// lanes ([`Frame::lanes_per_cell`]); a wider one tests every cell for every crossing lane.
const MAX_CELL_MASKS: usize = 16;

impl<P: Primitive> Grid<P> {
    /// The bundle queries ([`walk_groups`](rt_simd::bundle::walk_groups)): each coherent
    /// bundle walked slice by slice, every other ray walked alone. Calls `answer(slot, hit)`
    /// for each of the first `slots` rays (for `ANY`, `Some` when the ray is blocked).
    pub(crate) fn bundle_query<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        slots: usize,
        order: Option<&[u32]>,
        stats: &mut S,
        answer: impl FnMut(usize, Option<Hit>),
    ) {
        rt_simd::bundle::walk_groups_ordered::<S, ANY>(
            rays,
            slots,
            order,
            stats,
            |ray, stats| rt_simd::bundle::single::<_, S, ANY>(self, ray, stats),
            |b| {
                b.route(&self.shape.bounds(), |b| {
                    !self.refs.is_empty() && coherent(&self.shape, b)
                })
            },
            // Inlined, so that the walk is compiled with the vector instructions `walk_groups` runs
            // with (`Isa::run`).
            #[inline(always)]
            |b, lanes, stats| self.slices::<S, ANY>(b, lanes, stats),
            answer,
        );
    }

    /// Walks bundle `b` through the grid ([`walk_slices`]), testing each cell's primitives
    /// ([`test_primitives`]). Returns the lanes left to single rays.
    #[inline(always)]
    fn slices<S: Stats, const ANY: bool>(
        &self,
        b: &Bundle,
        lanes: &mut Lanes,
        stats: &mut S,
    ) -> u64 {
        let mut mailbox = LaneMailbox::new();
        let walking = b.all_lanes();
        let walked = walk_slices(
            &self.shape,
            b,
            lanes,
            walking,
            |lanes, c, lanes_in, t_hi| {
                stats.node_visit();
                stats.bundle_lanes(b.len() as u32, lanes_in.count_ones());
                let i = self.shape.index(c);
                let ids = &self.refs[self.cells[i] as usize..self.cells[i + 1] as usize];
                test_primitives::<P, S, ANY>(
                    &self.prims,
                    ids,
                    (b, t_hi),
                    lanes,
                    lanes_in,
                    &mut mailbox,
                    stats,
                )
            },
        );
        walked.alone
    }
}

/// Whether bundle `b`'s lanes travel together through `shape` closely enough for
/// [`walk_slices`]: their rectangle widens by at most [`MAX_SPREAD`] cells per slice. Rays of a
/// camera's pixel tile, or shadow rays towards one light, do; rays in random directions do not,
/// and go singly.
pub fn coherent(shape: &GridShape, b: &Bundle) -> bool {
    Frame::may_cohere(shape, b) && Frame::new(shape, b).coherent()
}

/// What [`walk_slices`] leaves to its caller: the lanes that missed the grid's box, and the
/// lanes to finish as single rays because the bundle would cost more than they.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Walked {
    /// Lanes of the walk whose slab test against the grid's box failed.
    pub missed: u64,
    /// Lanes to finish as single rays.
    pub alone: u64,
}

/// The slice walk of coherent grid traversal: the lanes `walking` of bundle `b` through
/// `shape`, slice by slice along their major axis. For each cell of each slice's rectangle,
/// `visit(lanes, cell, crossing, t_hi)` tests the cell's primitives against the lanes `crossing`
/// the slice (every lane's best hit so far is at most `t_hi`) and returns the lanes that leave
/// the walk (blocked, for any-hit queries; none otherwise).
///
/// Lanes that miss the grid's box are not walked (for the top grid they are done, as their
/// single walks are).
#[inline(always)]
pub fn walk_slices(
    shape: &GridShape,
    b: &Bundle,
    lanes: &mut Lanes,
    walking: u64,
    mut visit: impl FnMut(&mut Lanes, [u32; 3], u64, f32) -> u64,
) -> Walked {
    // Each lane's interval inside the grid's box, as its single walk computes it.
    let mut t0 = [0.0f32; BUNDLE_LANES];
    let mut t1 = [f32::NEG_INFINITY; BUNDLE_LANES];
    let mut live = 0u64;
    let mut m = walking;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let ray = lanes.ray(i);
        if let Some((a, z)) = shape.bounds().intersect(&ray, ray.t_max) {
            (t0[i], t1[i]) = (a, z);
            live |= 1 << i;
        }
    }
    let mut walked = Walked {
        missed: walking & !live,
        alone: 0,
    };
    if live == 0 {
        return walked;
    }
    let frame = Frame::new(shape, b);
    let res = shape.resolution_per_axis();
    let (start, mut s) = start_slices(shape, lanes, frame.major, &t0, live, frame.forward);
    // What the bundle has cost so far and what single rays would have: cells times vector
    // steps, against the cells the lanes cross one by one.
    let (mut cost, mut single_cost) = (0.0f32, 0.0f32);
    loop {
        let (near, far) = if frame.forward {
            (s, s + 1)
        } else {
            (s + 1, s)
        };
        let planes = (
            s,
            shape.plane(frame.major, near),
            shape.plane(frame.major, far),
        );
        let cut = frame.slice(planes, b, lanes.best_t(), &start, &t1, live);
        live &= !cut.done;
        if live == 0 {
            return walked;
        }
        let crossing = cut.crossing & live;
        if crossing != 0 {
            let us = frame.span(shape, frame.u, cut.u);
            let vs = frame.span(shape, frame.v, cut.v);
            let cells = ((us.1 - us.0 + 1) * (vs.1 - vs.0 + 1)) as f32;
            let steps = crossing.to_le_bytes().iter().filter(|&&x| x != 0).count() as f32;
            cost += cells * steps;
            single_cost += crossing.count_ones() as f32 * frame.cells_per_lane;
            if cost > MAX_COST_RATIO * single_cost + COST_SLACK {
                walked.alone = live;
                return walked;
            }
            // Every lane's best hit so far is at most this (lanes only get closer).
            let t_hi = lanes
                .best_t()
                .iter()
                .fold(f32::NEG_INFINITY, |a, &t| a.max(t));
            // PERF: in a rectangle of `WIDE_RECTANGLE` cells or more, each cell is tested for
            // the 8-lane steps of the lanes whose own segment comes near it, not for every lane
            // crossing the slice: shadow rays from scattered points (the sphereflake's) span
            // wide rectangles. Bundles ÷ single rays, old and new binaries alternating
            // (`compare --bundle 8x8 -j 1 --rays shadow`): sphereflake grid 1.88x -> 2.12x,
            // hgrid 1.34x -> 1.41x; rocker-arm and teapot in a stadium unchanged within 3%.
            // From 4 cells, or for every rectangle of two cells or more, the masks cost more
            // than they saved on primary rays: the grid's bunny 4.13x -> 3.44x.
            let per_cell = if cells >= WIDE_RECTANGLE {
                frame.cell_lanes(shape, planes, b, crossing, (us, cut.u), (vs, cut.v))
            } else {
                None
            };
            let mut lanes_in = crossing;
            for cv in vs.0..=vs.1 {
                for cu in us.0..=us.1 {
                    let here = match &per_cell {
                        Some((by_u, by_v)) => {
                            let (ku, kv) = ((cu - us.0) as usize, (cv - vs.0) as usize);
                            lanes_in & whole_steps(by_u[ku] & by_v[kv])
                        }
                        None => lanes_in,
                    };
                    if here == 0 {
                        continue;
                    }
                    let mut c = [0u32; 3];
                    (c[frame.major], c[frame.u], c[frame.v]) = (s, cu, cv);
                    let blocked = visit(lanes, c, here, t_hi);
                    live &= !blocked;
                    lanes_in &= !blocked;
                    if live == 0 {
                        return walked;
                    }
                }
            }
        }
        // The next slice, if the grid has one.
        if frame.forward {
            if s + 1 >= res[frame.major] {
                return walked;
            }
            s += 1;
        } else {
            if s == 0 {
                return walked;
            }
            s -= 1;
        }
    }
}

/// The slice where each live lane starts, and the first of them in the direction of travel:
/// the slice of the first cell of the lane's single walk ([`first_cell`], as `Dda::start`
/// finds it, by comparing the planes' parameters with the lane's entry), stepped one back,
/// since a lane's
/// closest hit may lie just before its entry by rounding (a ray that grazes the box's corner).
fn start_slices(
    shape: &GridShape,
    lanes: &Lanes,
    major: usize,
    t0: &[f32; BUNDLE_LANES],
    live: u64,
    forward: bool,
) -> ([u32; BUNDLE_LANES], u32) {
    let n = shape.resolution_per_axis()[major];
    let mut start = [0u32; BUNDLE_LANES];
    let mut first = if forward { u32::MAX } else { 0 };
    let mut m = live;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let k = first_cell(shape, &RayAxes::new(&lanes.ray(i)), major, t0[i]);
        start[i] = if forward {
            k.saturating_sub(1)
        } else {
            (k + 1).min(n - 1)
        };
        first = if forward {
            first.min(start[i])
        } else {
            first.max(start[i])
        };
    }
    (start, first)
}

/// A bundle's walk through the slices of its major axis: the axes, and each lane's slopes
/// across the slices.
struct Frame {
    /// The axis the slices are cut along, and the other two.
    major: usize,
    u: usize,
    v: usize,
    /// Whether the lanes travel towards larger coordinates along `major`.
    forward: bool,
    /// Each lane's `d_u / d_major` and `d_v / d_major`.
    slope: [[f32; BUNDLE_LANES]; 2],
    /// The largest `|origin|` of a lane along `u` and `v`.
    origin_max: [f32; 2],
    /// About how many cells one lane crosses per slice (from the lanes' mean slopes), for the
    /// cost of single rays.
    cells_per_lane: f32,
    /// How many cells per slice the lanes' rectangle widens by, from the spread of their slopes.
    spread: f32,
}

/// What a slice does to the lanes: the lanes that cross it, those done before it, and the
/// smallest and largest coordinate the crossing lanes reach along `u` and `v` there.
struct Cut {
    crossing: u64,
    done: u64,
    u: (f32, f32),
    v: (f32, f32),
}

impl Frame {
    /// The walk of bundle `b`'s lanes through `shape`: slices along the axis the first lane
    /// travels fastest (all lanes share direction signs, and no component is zero).
    fn new(shape: &GridShape, b: &Bundle) -> Self {
        let major = b.major_axis();
        let (u, v) = ((major + 1) % 3, (major + 2) % 3);
        let mut slope = [[0.0; BUNDLE_LANES]; 2];
        let mut origin_max = [0.0f32; 2];
        let mut mean = [0.0f32; 2];
        let mut range = [(f32::INFINITY, f32::NEG_INFINITY); 2];
        for (k, axis) in [u, v].into_iter().enumerate() {
            for (i, s) in slope[k].iter_mut().enumerate().take(b.len()) {
                *s = b.dir[axis][i] * b.inv_dir[major][i];
                origin_max[k] = origin_max[k].max(b.origin[axis][i].abs());
                mean[k] += s.abs();
                range[k] = (range[k].0.min(*s), range[k].1.max(*s));
            }
        }
        let n = b.len() as f32;
        let size = [0, 1, 2].map(|a| {
            let e = shape.bounds().extent()[a];
            e / shape.resolution_per_axis()[a] as f32
        });
        // Cells per slice along `axis`, for a slope of `s`.
        let per_slice = |s: f32, axis: usize| {
            if size[axis] > 0.0 {
                s * size[major] / size[axis]
            } else {
                0.0
            }
        };
        Self {
            major,
            u,
            v,
            forward: b.dir[major][0] > 0.0,
            slope,
            origin_max,
            cells_per_lane: (1.0 + per_slice(mean[0] / n, u)) * (1.0 + per_slice(mean[1] / n, v)),
            spread: per_slice(range[0].1 - range[0].0, u) + per_slice(range[1].1 - range[1].0, v),
        }
    }

    /// A quick test before [`Frame::new`] that rejects bundles of rays in clearly different
    /// directions from the bundle's bounds alone (the first check of random rays): the spread
    /// of the slopes `d_u / d_major = inv_major / inv_u` is at least that of the bounds'
    /// corners' ratios, so this rejects no bundle that [`Frame::coherent`] accepts, give or
    /// take rounding.
    fn may_cohere(shape: &GridShape, b: &Bundle) -> bool {
        let major = b.major_axis();
        let size =
            [0, 1, 2].map(|a| shape.bounds().extent()[a] / shape.resolution_per_axis()[a] as f32);
        let axes = [(major + 1) % 3, (major + 2) % 3];
        let mut spread = 0.0;
        for (axis, (lo, hi)) in axes.into_iter().zip(b.slope_bounds(major)) {
            if size[axis] > 0.0 {
                // Halved for the rounding a corner's ratio may carry beyond the lanes' own.
                spread += 0.5 * (hi - lo) * size[major] / size[axis];
            }
        }
        spread <= MAX_SPREAD
    }

    /// Whether the lanes' rectangle widens by at most [`MAX_SPREAD`] cells per slice.
    fn coherent(&self) -> bool {
        self.spread <= MAX_SPREAD
    }

    /// The cut of slice `s`, between the planes `near` and `far` (in the order the lanes meet
    /// them), through the `live` lanes, whose best hits so far are `best`, whose walks start at
    /// the slices `start` and whose grid intervals end at `t1`.
    ///
    /// A lane is done when it reaches the slice beyond its best hit or its exit, as its single
    /// walk stops after the cell it leaves beyond either. It crosses the slices from its start
    /// on; its line's coordinates at the two planes bound its segment in the slice (the line
    /// is straight, the bounds are its ends; outside the grid they clamp to its edge cells).
    #[inline(always)]
    fn slice(
        &self,
        (s, near, far): (u32, f32, f32),
        b: &Bundle,
        best: &[f32; BUNDLE_LANES],
        start: &[u32; BUNDLE_LANES],
        t1: &[f32; BUNDLE_LANES],
        live: u64,
    ) -> Cut {
        const W: usize = 8;
        let (m, u, v) = (self.major, self.u, self.v);
        let mut lo = [[f32::INFINITY; W]; 2];
        let mut hi = [[f32::NEG_INFINITY; W]; 2];
        let (mut crossing, mut done) = (0u64, 0u64);
        let (om, inv) = (&b.origin[m], &b.inv_dir[m]);
        let (ou, ov) = (&b.origin[u], &b.origin[v]);
        // PERF: written without branches and with `<`/`>` selects instead of `f32::min`/`max`
        // (whose NaN rules keep the compiler from vector instructions), so that each step of
        // eight lanes compiles to vector code: the hierarchical grid's bundles went from 5.23
        // to 5.73 Mrays/s on the teapot in a stadium and from 3.91 to 4.26 on the sphereflake
        // (`compare --bundle 8x8 -j 1`, primary rays of the filled views).
        // No coordinate is NaN: a bundle's lanes have finite origins and finite, non-zero
        // direction components, so the slopes and distances are finite (at worst a product
        // overflows to an infinity, which `span` widens to the whole axis).
        for step in 0..BUNDLE_LANES / W {
            let lanes8 = (live >> (step * W)) as u8;
            if lanes8 == 0 {
                continue;
            }
            let mut cross = [false; W];
            let mut gone = [false; W];
            for j in 0..W {
                let i = step * W + j;
                let (dn, df) = (near - om[i], far - om[i]);
                let tn = dn * inv[i];
                gone[j] = (tn > best[i] * SLAB_FAR_SCALE) | (tn > t1[i] * SLAB_FAR_SCALE);
                let started = if self.forward {
                    s >= start[i]
                } else {
                    s <= start[i]
                };
                cross[j] = started;
                let keep = started & (lanes8 >> j & 1 != 0);
                for (k, o) in [ou[i], ov[i]].into_iter().enumerate() {
                    let (a, z) = (o + self.slope[k][i] * dn, o + self.slope[k][i] * df);
                    let (mn, mx) = if a < z { (a, z) } else { (z, a) };
                    lo[k][j] = if keep & (mn < lo[k][j]) { mn } else { lo[k][j] };
                    hi[k][j] = if keep & (mx > hi[k][j]) { mx } else { hi[k][j] };
                }
            }
            for j in 0..W {
                crossing |= u64::from(cross[j]) << (step * W + j);
                done |= u64::from(gone[j]) << (step * W + j);
            }
        }
        let reduce = |k: usize| {
            (
                lo[k].iter().fold(f32::INFINITY, |a, &x| a.min(x)),
                hi[k].iter().fold(f32::NEG_INFINITY, |a, &x| a.max(x)),
            )
        };
        Cut {
            crossing,
            done: done & live,
            u: reduce(0),
            v: reduce(1),
        }
    }

    /// The cells along `axis` (`u` or `v`) whose closed boxes meet the coordinates `(lo, hi)`
    /// widened on both sides by a bound on their rounding error.
    ///
    /// The coordinates are `o + s·(x - o_major)` with the rounded slope `s`; the true line
    /// differs by a few units in the last place of `|o|` and of the result: `2⁻²⁰` of twice
    /// their sum is more than sixteen of those units. The cells then come from comparisons with
    /// the planes themselves ([`GridShape::plane`]), which the builder used, not from a rounded
    /// division. A non-finite coordinate widens to the whole axis.
    #[inline(always)]
    fn span(&self, shape: &GridShape, axis: usize, (lo, hi): (f32, f32)) -> Span {
        let n = shape.resolution_per_axis()[axis];
        let err = self.rounding(axis, (lo, hi));
        let (lo, hi) = (lo - err, hi + err);
        if !(lo.is_finite() && hi.is_finite()) {
            return (0, n - 1);
        }
        // The first cell whose far plane is at or past `lo`, the last whose near plane is at or
        // before `hi`.
        let mut k0 = shape.cell_of(axis, lo);
        while k0 > 0 && shape.plane(axis, k0) >= lo {
            k0 -= 1;
        }
        while k0 + 1 < n && shape.plane(axis, k0 + 1) < lo {
            k0 += 1;
        }
        let mut k1 = shape.cell_of(axis, hi).max(k0);
        while k1 + 1 < n && shape.plane(axis, k1 + 1) <= hi {
            k1 += 1;
        }
        while k1 > k0 && shape.plane(axis, k1) > hi {
            k1 -= 1;
        }
        (k0, k1)
    }

    /// Each lane of `lanes`' smallest and largest coordinate along `u` and `v` between the
    /// slice's planes, into `seg` (`u` low, `u` high, `v` low, `v` high): the values
    /// [`Frame::slice`] computes for its rectangle, by the same operations.
    #[inline(always)]
    fn segments(
        &self,
        (_, near, far): (u32, f32, f32),
        b: &Bundle,
        lanes: u64,
        seg: &mut [[f32; BUNDLE_LANES]; 4],
    ) {
        let (om, ou, ov) = (&b.origin[self.major], &b.origin[self.u], &b.origin[self.v]);
        let mut m = lanes;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            let (dn, df) = (near - om[i], far - om[i]);
            for (k, o) in [ou[i], ov[i]].into_iter().enumerate() {
                let (a, z) = (o + self.slope[k][i] * dn, o + self.slope[k][i] * df);
                (seg[2 * k][i], seg[2 * k + 1][i]) = if a < z { (a, z) } else { (z, a) };
            }
        }
    }

    /// For a slice's rectangle of cells `u` by `v` (each the span and the rectangle's
    /// coordinates it came from), the lanes of `lanes` that come near each column and each row
    /// ([`Frame::lanes_per_cell`]), or `None` when the rectangle is too wide for them.
    // PERF: kept out of the slice walk, with its arrays, so that the walk costs nothing more
    // where rectangles stay narrow: inlined, the grid's incoherent rays ran at 0.96-0.98x their
    // single rays against 1.00-1.01x before (`compare --rays incoherent --bundle 8x8 -j 1`,
    // teapot in a stadium, sphereflake).
    #[inline(never)]
    fn cell_lanes(
        &self,
        shape: &GridShape,
        planes: (u32, f32, f32),
        b: &Bundle,
        lanes: u64,
        u: (Span, (f32, f32)),
        v: (Span, (f32, f32)),
    ) -> Option<([u64; MAX_CELL_MASKS], [u64; MAX_CELL_MASKS])> {
        let mut seg = [[0.0f32; BUNDLE_LANES]; 4];
        self.segments(planes, b, lanes, &mut seg);
        let (mut by_u, mut by_v) = ([0u64; MAX_CELL_MASKS], [0u64; MAX_CELL_MASKS]);
        let fits = self.lanes_per_cell(shape, self.u, u, (&seg[0], &seg[1]), lanes, &mut by_u)
            && self.lanes_per_cell(shape, self.v, v, (&seg[2], &seg[3]), lanes, &mut by_v);
        fits.then_some((by_u, by_v))
    }

    /// The bound on the rounding error of coordinates within `(lo, hi)` along `axis` (`u` or
    /// `v`) that [`Frame::span`] widens by: `2⁻²⁰` of twice the largest origin and coordinate.
    #[inline(always)]
    fn rounding(&self, axis: usize, (lo, hi): (f32, f32)) -> f32 {
        let k = if axis == self.u { 0 } else { 1 };
        2.0 * (self.origin_max[k] + lo.abs().max(hi.abs())) * (1.0 / 1_048_576.0)
    }

    /// For each cell `k` of `span` along `axis`, into `out[k - span.0]`, the lanes of `lanes`
    /// whose coordinates in the slice, `lo[i]` to `hi[i]`, come near the cell: with the
    /// widening of [`Frame::span`] for the rectangle's coordinates `rect` (at least each
    /// lane's own), and the cells at the grid's edges open outwards as `span` clamps. So a
    /// cell's lanes are those for which `span` of their own coordinates would hold the cell,
    /// and a lane's single walk enters no cell of the slice that this leaves it out of.
    /// False, writing nothing, when `span` has more cells than `out` or a coordinate of the
    /// rectangle is not finite.
    #[inline(always)]
    fn lanes_per_cell(
        &self,
        shape: &GridShape,
        axis: usize,
        (span, rect): (Span, (f32, f32)),
        (lo, hi): (&[f32; BUNDLE_LANES], &[f32; BUNDLE_LANES]),
        lanes: u64,
        out: &mut [u64; MAX_CELL_MASKS],
    ) -> bool {
        const W: usize = 8;
        let count = (span.1 - span.0 + 1) as usize;
        if count > MAX_CELL_MASKS || !(rect.0.is_finite() && rect.1.is_finite()) {
            return false;
        }
        let err = self.rounding(axis, rect);
        let n = shape.resolution_per_axis()[axis];
        for (k, mask) in (span.0..=span.1).zip(out.iter_mut()) {
            let near = if k == 0 {
                f32::NEG_INFINITY
            } else {
                shape.plane(axis, k)
            };
            let far = if k + 1 >= n {
                f32::INFINITY
            } else {
                shape.plane(axis, k + 1)
            };
            let mut m = 0u64;
            for step in 0..BUNDLE_LANES / W {
                if (lanes >> (step * W)) as u8 == 0 {
                    continue;
                }
                let mut bits = 0u64;
                for j in 0..W {
                    let i = step * W + j;
                    let meets = (lo[i] - err <= far) & (hi[i] + err >= near);
                    bits |= u64::from(meets) << j;
                }
                m |= bits << (step * W);
            }
            *mask = m & lanes;
        }
        true
    }
}

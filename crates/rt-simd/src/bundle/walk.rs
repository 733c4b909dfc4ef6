//! The frame of every structure's bundle queries: rays sorted into [`Bundle`]s, each routed to
//! the structure's walk, answered at once, or traced singly; every answer handed back.

use super::{Bundle, Lanes, bundles_ray, octant};
use crate::{BUNDLE_LANES, Isa};
use rt_core::{Accel, Hit, Ray, Stats};

/// What [`for_each_bundle`] hands over: a bundle, or a ray that travels alone with its index in
/// the slice.
#[derive(Clone, Copy, Debug)]
pub enum Group<'a> {
    /// Rays that travel together.
    Bundle(&'a Bundle),
    /// A ray that cannot travel in a bundle ([`bundles_ray`]), and its index.
    Single(usize, &'a Ray),
}

/// Splits `rays` into bundles: each run of [`BUNDLE_LANES`] consecutive rays gives up to eight
/// bundles, one per direction octant present, each keeping the rays' order. Rays that cannot
/// travel in a bundle ([`bundles_ray`]) come as [`Group::Single`] with their index instead.
/// Every ray comes exactly once.
///
/// Rays given in tile order (a camera's 8×8 pixel tiles, a light's shadow rays) give full
/// bundles; rays in random order give small ones, and a structure's bundle traversal may then
/// trace them singly (it knows what pays).
pub fn for_each_bundle(rays: &[Ray], mut visit: impl FnMut(Group<'_>)) {
    let mut bundler = Bundler::new(Isa::detect());
    for (base, run) in rays.chunks(BUNDLE_LANES).enumerate() {
        bundler.run(run, base * BUNDLE_LANES, &mut visit);
    }
}

/// [`for_each_bundle`] one run of rays at a time, keeping its eight bundles between runs.
struct Bundler {
    groups: [Option<Box<Bundle>>; 8],
    /// A run written in whole, before it is known to fill one bundle.
    whole: Option<Box<Bundle>>,
    /// The instructions that write it.
    isa: Isa,
}

impl Bundler {
    fn new(isa: Isa) -> Self {
        Self {
            groups: Default::default(),
            whole: None,
            isa,
        }
    }

    /// Splits `run` (at most [`BUNDLE_LANES`] rays, the first at index `base` of the slice)
    /// into its bundles and single rays.
    #[inline(always)]
    fn run(&mut self, run: &[Ray], base: usize, mut visit: impl FnMut(Group<'_>)) {
        // PERF: where every ray of the run bundles and all point into one octant (a camera's
        // tile, a light's shadow rays), they fill one bundle in order: all written first, each
        // lane at its own index, then checked in vectors of lanes. A test of each ray before
        // it was written (`bundles_ray`, `octant`) was a quarter of the time around a bundle
        // walk.
        let Some(first) = run.first() else { return };
        let o = octant(first);
        let whole = self.whole.get_or_insert_with(|| Box::new(Bundle::empty(o)));
        if whole.fill_sealed(self.isa, run, base, o) {
            visit(Group::Bundle(whole));
            whole.clear();
            return;
        }
        for (k, ray) in run.iter().enumerate() {
            let slot = base + k;
            if !bundles_ray(ray) {
                visit(Group::Single(slot, ray));
                continue;
            }
            let o = octant(ray);
            let g = self.groups[o].get_or_insert_with(|| Box::new(Bundle::empty(o)));
            g.push(slot as u32, ray);
        }
        for g in self.groups.iter_mut().flatten() {
            if !g.is_empty() {
                g.seal();
                visit(Group::Bundle(g));
                g.clear();
            }
        }
    }
}

/// How [`walk_groups`] takes a bundle ([`Bundle::route`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// The structure's bundle walk.
    Walk,
    /// Every lane by the single-ray query.
    Singly,
    /// No lane reaches the structure's box: every lane answers "no hit" at once, as its single
    /// walk would after its first box test.
    Miss,
}

/// What a single ray of a bundle query answers: [`Accel::intersect_with`], or
/// for `ANY` [`BLOCKED`] when [`Accel::occluded_with`] is true: the `single`
/// walk structures pass to [`walk_groups`].
#[inline(always)]
pub fn single<A: Accel, S: Stats, const ANY: bool>(
    accel: &A,
    ray: &Ray,
    stats: &mut S,
) -> Option<Hit> {
    if ANY {
        accel.occluded_with(ray, stats).then_some(BLOCKED)
    } else {
        accel.intersect_with(ray, stats)
    }
}

/// The answer of a bundle's any-hit lane that is blocked (only `is_some` is read).
pub const BLOCKED: Hit = Hit {
    prim: u32::MAX,
    t: f32::NAN,
    u: 0.0,
    v: 0.0,
};

/// The frame of a structure's own bundle queries: the first `slots` rays split by
/// [`for_each_bundle`]; each bundle of two or more lanes that `route` sends to
/// [`Route::Walk`] walked by `walk` (which records hits in its [`Lanes`] and returns the lanes
/// it leaves to single rays), each one it sends to [`Route::Miss`] answered "no hit" lane by
/// lane, every other ray traced by `single`. Calls `answer(slot, hit)` for every ray, each ray
/// counted as [`Stats::single_ray`] when traced singly. For `ANY`, a lane's answer is `Some`
/// (with a NaN `t`, as the single any-hit walks give) when it is blocked.
///
/// A run of [`BUNDLE_LANES`] rays none of whose bundles walked is followed by a few runs traced
/// singly without sorting them into bundles, so rays in random directions pay for the sorting
/// on a few runs only.
///
/// The whole loop runs compiled for the CPU's best vector instructions ([`Isa::run`]), and with
/// it the walks and the kernels it inlines. Each bundle that walks gets [`Lanes`] of its own,
/// which borrow its rays and hold only the lanes' best hits.
pub fn walk_groups<S: Stats, const ANY: bool>(
    rays: &[Ray],
    slots: usize,
    stats: &mut S,
    single: impl FnMut(&Ray, &mut S) -> Option<Hit>,
    route: impl Fn(&Bundle) -> Route,
    walk: impl FnMut(&Bundle, &mut Lanes, &mut S) -> u64,
    answer: impl FnMut(usize, Option<Hit>),
) {
    walk_groups_ordered::<S, ANY>(rays, slots, None, stats, single, route, walk, answer);
}

/// [`walk_groups`] for the rays `order` lists (entries at or past `slots` and the rays'
/// length ignored), bundled in its order, or for the first `slots` rays with `None`: what the
/// ordered bundle queries ([`Accel::intersect_bundle_ordered_with`]) run on. Each run of
/// [`BUNDLE_LANES`] entries is gathered and bundled as a run of the slice would be, and the
/// next run's rays are asked into the caches as soon as this one is gathered.
#[allow(clippy::too_many_arguments)]
pub fn walk_groups_ordered<S: Stats, const ANY: bool>(
    rays: &[Ray],
    slots: usize,
    order: Option<&[u32]>,
    stats: &mut S,
    mut single: impl FnMut(&Ray, &mut S) -> Option<Hit>,
    route: impl Fn(&Bundle) -> Route,
    walk: impl FnMut(&Bundle, &mut Lanes, &mut S) -> u64,
    mut answer: impl FnMut(usize, Option<Hit>),
) {
    let rays = &rays[..rays.len().min(slots)];
    let kept;
    let order = match order {
        // Entries past the rays are ignored (checked once here, so the runs index freely).
        Some(o) if o.iter().any(|&i| i as usize >= rays.len()) => {
            kept = o
                .iter()
                .copied()
                .filter(|&i| (i as usize) < rays.len())
                .collect::<Vec<u32>>();
            Some(&kept[..])
        }
        o => o,
    };
    if order.map_or(rays.len(), <[u32]>::len) < 2 {
        // One ray (or none) cannot make a bundle: straight to its single walk.
        for slot in slots_of(rays.len(), order) {
            answer(slot, alone(&mut single, &rays[slot], stats));
        }
        return;
    }
    let isa = Isa::detect();
    isa.run(
        #[inline(always)]
        move || walk_runs::<S, ANY>(isa, rays, order, stats, single, route, walk, answer),
    );
}

/// The slots a bundle query answers, in the order it takes them: `0..len`, or `order`'s.
pub fn slots_of(len: usize, order: Option<&[u32]>) -> impl Iterator<Item = usize> + '_ {
    let (all, listed) = match order {
        None => (0..len, None),
        Some(o) => (0..0, Some(o.iter().map(|&i| i as usize))),
    };
    all.chain(listed.into_iter().flatten())
}

/// A ray traced singly, counted as one.
#[inline(always)]
fn alone<S: Stats>(
    single: &mut impl FnMut(&Ray, &mut S) -> Option<Hit>,
    ray: &Ray,
    stats: &mut S,
) -> Option<Hit> {
    stats.single_ray();
    single(ray, stats)
}

/// The body of [`walk_groups`], for two rays or more.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn walk_runs<S: Stats, const ANY: bool>(
    isa: Isa,
    rays: &[Ray],
    order: Option<&[u32]>,
    stats: &mut S,
    mut single: impl FnMut(&Ray, &mut S) -> Option<Hit>,
    route: impl Fn(&Bundle) -> Route,
    mut walk: impl FnMut(&Bundle, &mut Lanes, &mut S) -> u64,
    mut answer: impl FnMut(usize, Option<Hit>),
) {
    // PERF: everything around a bundle walk (this loop with a walk that does nothing, bunny
    // primary rays of the filled view in 8×8 tiles, one thread) took 19.5 ns a ray when each
    // bundle made and moved its own `Lanes`, each ray was tested before it was written into a
    // bundle and the bundle's bounds grew at every push; 10.5 ns now. Bundles ÷ single rays on
    // the bunny, the sphereflake, the teapot in a stadium and the rocker arm, before and after
    // (medians of 3 alternating passes): wide BVH 2.01 1.70 1.63 1.84 -> 2.51 1.99 1.89 1.99,
    // binary BVH 2.56 2.33 3.06 3.31 -> 3.09 2.71 3.88 3.52, kd-tree 2.09 1.90 2.38 2.26 ->
    // 2.23 2.19 2.89 2.71, octree 4.22 3.95 5.54 5.52 -> 4.59 4.42 6.48 6.17, the grids within
    // ±5%. (`Lanes` then held copies of the bundle's rays; now they borrow them, and each
    // bundle's are made in place: see `Lanes::with_isa`.)
    // PERF: after a run of rays none of whose bundles walked, the next runs are traced singly
    // without sorting them into bundles: one after the first such run, doubling with each
    // further one up to `SKIP`, and back to none when a run walks. Rays in random directions
    // then pay the sorting on about one run in `SKIP + 1`; rays of which some runs cohere lose
    // few of those. Incoherent rays, bundles ÷ single rays (`cargo xtask compare --scene S -s
    // kdtree,octree,grid,hgrid --bundle 8x8 -j 1 --rays incoherent`, teapot in a stadium,
    // sphereflake, bunny, teapot): 0.90-0.97 without, 0.96-1.00 with.
    const SKIP: u32 = 8;
    let mut bundler = Bundler::new(isa);
    let (mut backoff, mut skip) = (0, 0);
    // With an order, each run's rays are gathered here, and the next run's are asked into the
    // caches as soon as this one is gathered, a whole walk ahead: the CPU cannot foresee loads
    // from several places as it foresees a slice's. (Gathering the rays into a buffer before
    // the call instead, `intersect_image`'s first form, read them in a pass of its own that
    // waited on memory: teapot primary rays in image order 42.6 -> 38.5 Mrays/s, where this
    // gives 46-49.)
    // PERF: prefetching the next run's rays a line per lane while this run's answers are
    // written, as for a slice, against right after this run's gather: the wide BVH's bundles
    // through `intersect_image`, the teapot's primary rays in image order, one thread, private
    // harness, Mrays/s, 42.4 43.1 -> 44.9 44.4; the bunny 31.2 29.7 -> 31.9 32.0.
    let mut gathered = Vec::with_capacity(if order.is_some() { BUNDLE_LANES } else { 0 });
    let listed = order.map_or(rays.len(), <[u32]>::len);
    for base in (0..listed).step_by(BUNDLE_LANES) {
        let end = (base + BUNDLE_LANES).min(listed);
        // The run, and where the answer of its ray `k` goes.
        let (run, ids) = match order {
            None => (&rays[base..end], None),
            Some(o) => {
                let ids = &o[base..end];
                gathered.clear();
                gathered.extend(ids.iter().map(|&i| rays[i as usize]));
                for &i in &o[end..(end + BUNDLE_LANES).min(o.len())] {
                    // A ray's 44 bytes lie on at most two lines: the line of its start, and
                    // that of the next ray's start (where its last byte is, or on the first).
                    let i = i as usize;
                    crate::prefetch(&rays[i..], 0, 1);
                    crate::prefetch(&rays[i + 1..], 0, 1);
                }
                (&gathered[..], Some(ids))
            }
        };
        let to_slot = |k: usize| ids.map_or(base + k, |ids| ids[k] as usize);
        if skip > 0 {
            skip -= 1;
            for (k, ray) in run.iter().enumerate() {
                answer(to_slot(k), alone(&mut single, ray, stats));
            }
            continue;
        }
        if !may_cohere(run) {
            for (k, ray) in run.iter().enumerate() {
                answer(to_slot(k), alone(&mut single, ray, stats));
            }
            continue;
        }
        let mut walked = false;
        // The next run's rays, asked into the caches a line per lane while this run's answers
        // are written, so that its bundle does not wait for them from memory.
        // PERF: a camera's rays stream from memory (a frame's 786,432 rays are 35 MB), and the
        // fill of each bundle was a fifth of the time of a bundle walk, most of it waiting for
        // the loads (a profile of the teapot in a stadium). The wide BVH's bundles, one
        // thread, medians of five alternating runs of a private harness, Mrays/s, without ->
        // with: the peers benchmark's framing views of the bunny 52.7 -> 55.0, the sphereflake
        // 61.9 -> 63.5, the teapot in a stadium 56.8 -> 65.2; the bunny's filled view 36.0 ->
        // 38.7, the teapot's close view 38.7 -> 41.8 (medians of three). The whole next run
        // asked for at once before this run's walk made them slower (medians of three: bunny
        // 51.9 -> 45.6, stadium 58.4 -> 48.9); two runs ahead, mixed (bunny 52.7 -> 51.0,
        // sphereflake 61.9 -> 59.3, stadium 56.8 -> 61.1); the answers' own lines asked for
        // ahead too, slower (bunny 56.1 -> 54.5, stadium 64.8 -> 61.8).
        let ahead = match order {
            None => &rays[end..(end + BUNDLE_LANES).min(rays.len())],
            Some(_) => &[],
        };
        bundler.run(
            run,
            0,
            #[inline(always)]
            |group| match group {
                Group::Bundle(b) => match if b.len() > 1 { route(b) } else { Route::Singly } {
                    Route::Walk => {
                        walked = true;
                        let mut lanes = Lanes::with_isa(b, isa);
                        let left = walk(b, &mut lanes, stats);
                        for i in 0..b.len() {
                            prefetch_line(ahead, i);
                            let k = b.slot[i] as usize;
                            let slot = to_slot(k);
                            if left >> i & 1 != 0 {
                                answer(slot, alone(&mut single, &run[k], stats));
                            } else {
                                // One call of `answer` per kind of answer, so that each
                                // writes its fields straight into the caller's slot.
                                // PERF: with one call taking an `Option` made above it,
                                // every answer went through a copy on the stack; this loop
                                // was four fifths of the frame's samples (`perf record`, the
                                // teapot's close view). The wide BVH's bundles, the filled
                                // views at half the distance (97.5%, 79.5%, 94.2% and 100%
                                // of the rays hit), one thread, medians of five alternating
                                // runs of a private harness, Mrays/s: the teapot 70.2 ->
                                // 73.0 (three), the bunny 53.0 -> 53.9, the sphereflake 41.4
                                // -> 41.7, the teapot in a stadium 72.7 -> 74.0.
                                match lanes.hit(i) {
                                    Some(h) if ANY => answer(slot, Some(Hit { t: f32::NAN, ..h })),
                                    Some(h) => answer(slot, Some(h)),
                                    None => answer(slot, None),
                                }
                            }
                        }
                    }
                    Route::Miss => {
                        walked = true;
                        for (i, &k) in b.slot[..b.len()].iter().enumerate() {
                            prefetch_line(ahead, i);
                            answer(to_slot(k as usize), None);
                        }
                    }
                    Route::Singly => {
                        for &k in &b.slot[..b.len()] {
                            let k = k as usize;
                            answer(to_slot(k), alone(&mut single, &run[k], stats));
                        }
                    }
                },
                Group::Single(k, ray) => answer(to_slot(k), alone(&mut single, ray, stats)),
            },
        );
        if walked {
            backoff = 0;
        } else {
            backoff = (2 * backoff).clamp(1, SKIP);
            skip = backoff;
        }
    }
}

/// Whether a run of rays may hold a coherent bundle, judged from its first ray and the next
/// three: whether one of them points within about a quarter radian of the first (directions
/// scaled to a largest component of 1, the components' differences summed). Rays of a
/// camera's tile, or shadow rays of neighbouring pixels, pass at once; rays in random
/// directions almost never do, and then skip the sorting into bundles that would only send
/// them singly. Looking three rays on keeps interleaved coherent streams (rays towards two
/// lights in turn, say).
// PERF: `compare` hands rays over in tasks of 256 (four runs), so the backoff alone, which
// starts again with every call, sorted half of the incoherent runs: the BVH's incoherent rays
// ran at 0.91-0.93x its single rays with the backoff alone, and at 1.00-1.01x with this test
// (`compare --rays incoherent --bundle 8x8 -j 1`: teapot in a stadium, sphereflake, bunny,
// teapot.obj, cow).
#[inline]
fn may_cohere(run: &[Ray]) -> bool {
    let unit = |r: &Ray| {
        let d = r.dir();
        let m = d.abs().max_element();
        d / m
    };
    let Some(first) = run.first() else {
        return false;
    };
    let u0 = unit(first);
    run[1..run.len().min(4)].iter().any(|r| {
        let spread = (unit(r) - u0).abs().element_sum();
        // NaN (a zero or non-finite direction) counts as coherent: the sorting sends such rays
        // singly anyway.
        spread.is_nan() || spread <= 0.25
    })
}

/// Asks the CPU to bring cache line `line` of `rays` into its caches (a hint, which changes no
/// value).
#[inline(always)]
fn prefetch_line(rays: &[Ray], line: usize) {
    crate::prefetch(rays, line, 1);
}

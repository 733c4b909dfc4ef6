//! The bundle check: a structure's bundle queries ([`Accel::intersect_bundle_with`],
//! [`Accel::occluded_bundle_with`]) must answer every ray exactly as its single-ray queries do,
//! whatever bundles the rays come in.

use crate::Probe;
use rt_core::{Accel, Counters, Hit, NoStats, Ray, Rng};

/// The slice lengths the kit hands to the bundle queries: one ray, just under, at and over the
/// common bundle widths (8 and 64 lanes), and a long slice.
pub const BUNDLE_SIZES: [usize; 8] = [1, 7, 8, 9, 63, 64, 65, 1000];

/// The slices of `len` rays when their lengths cycle through [`BUNDLE_SIZES`], upwards from one
/// ray or downwards from the long slice: two passes that, between them, hand every length to the
/// queries once the rays are enough (217 for all lengths upwards), and start on different rays.
// PERF: one pass per length traced each ray set 32 times; the fine grid's identical-triangles
// case took 36 s of the CI run's tests (opt-level 1). Two cycling passes per order trace it 8
// times.
pub(crate) fn cycled_slices(len: usize, downwards: bool) -> Vec<std::ops::Range<usize>> {
    let mut sizes = BUNDLE_SIZES;
    if downwards {
        sizes.reverse();
    }
    let mut slices = Vec::new();
    let mut start = 0;
    for size in sizes.iter().cycle() {
        if start >= len {
            break;
        }
        let end = (start + size).min(len);
        slices.push(start..end);
        start = end;
    }
    slices
}

/// The orders the kit re-bundles rays in, each with its name for messages: as given; shuffled;
/// the direction octants interleaved (each run of rays mixes all octants present); and invalid
/// rays (a NaN origin, a zero direction, an empty interval) interleaved with the given ones.
pub fn bundle_orders(rays: &[Ray], seed: u64) -> Vec<(&'static str, Vec<Ray>)> {
    let mut rng = Rng::new(seed);
    let mut shuffled = rays.to_vec();
    for i in (1..shuffled.len()).rev() {
        shuffled.swap(i, rng.below(i as u32 + 1) as usize);
    }
    // Round robin over the octants: ray k of octant 0, of octant 1, ..., then ray k + 1.
    let mut by_octant: [Vec<Ray>; 8] = Default::default();
    for r in rays {
        by_octant[rt_simd::bundle::octant(r)].push(*r);
    }
    let longest = by_octant.iter().map(Vec::len).max().unwrap_or(0);
    let mixed = (0..longest)
        .flat_map(|k| by_octant.iter().filter_map(move |o| o.get(k).copied()))
        .collect();
    let invalid = [
        Ray::new(rt_core::glam::Vec3::NAN, rt_core::glam::Vec3::X),
        Ray::new(rt_core::glam::Vec3::ZERO, rt_core::glam::Vec3::ZERO),
        Ray::with_interval(rt_core::glam::Vec3::ZERO, rt_core::glam::Vec3::Z, 2.0, 1.0),
    ];
    let mut with_invalid = Vec::with_capacity(rays.len() + rays.len() / 5 + 1);
    for (i, r) in rays.iter().enumerate() {
        if i % 5 == 2 {
            with_invalid.push(invalid[i / 5 % invalid.len()]);
        }
        with_invalid.push(*r);
    }
    vec![
        ("as given", rays.to_vec()),
        ("shuffled", shuffled),
        ("with octants mixed", mixed),
        ("with invalid rays interleaved", with_invalid),
    ]
}

/// Whether two closest-hit answers are the same bits: the same primitive and the same `t`, `u`,
/// `v` (as `f32` bits, so `-0.0` and `0.0` differ).
pub fn same_bits(a: Option<Hit>, b: Option<Hit>) -> bool {
    let bits = |h: Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
    bits(a) == bits(b)
}

/// Checks that `accel`'s bundle queries answer every ray of `rays`, in every order of
/// [`bundle_orders`] and in slices whose lengths cycle through [`BUNDLE_SIZES`] (upwards and
/// downwards), exactly as its single-ray
/// queries do (the same bits, [`same_bits`]); that counting events changes no answer; and that
/// slices of unequal lengths answer as many rays as both have and leave the rest alone; and
/// that the ordered bundle queries answer the rays an order lists in their own slots and leave
/// the others alone. With `any` false, only the closest-hit queries are checked (the ordered
/// occlusion query is checked either way).
///
/// # Errors
/// The first answer that differs, with its ray, the order and the slice length.
pub fn compare_bundles<A: Accel>(accel: &A, rays: &[Ray], any: bool) -> Result<(), String> {
    compare_bundles_probed(accel, rays, any, &Probe::default()).map(drop)
}

/// The single queries' answers to the rays as given: the closest hits, and the any hits (empty
/// when the any hit is not checked).
pub(crate) type Singles = (Vec<Option<Hit>>, Vec<bool>);

pub(crate) fn compare_bundles_probed<A: Accel>(
    accel: &A,
    rays: &[Ray],
    any: bool,
    probe: &Probe,
) -> Result<Singles, String> {
    let name = A::NAME;
    let mut as_given = None;
    for (order, rays) in bundle_orders(rays, 0x5eed_b0d1) {
        let single: Vec<Option<Hit>> = rays.iter().map(|r| accel.intersect(r)).collect();
        let blocked: Vec<bool> = if any {
            rays.iter().map(|r| accel.occluded(r)).collect()
        } else {
            Vec::new()
        };
        if as_given.is_none() {
            // The first order is the rays as given.
            as_given = Some((single.clone(), blocked.clone()));
        }
        for downwards in [false, true] {
            let slices = cycled_slices(rays.len(), downwards);
            let mut hits = vec![None; rays.len()];
            let mut occluded = vec![false; rays.len()];
            for range in &slices {
                let chunk = &rays[range.clone()];
                probe.bundle(&chunk[0], chunk.len());
                accel.intersect_bundle_with(chunk, &mut hits[range.clone()], &mut NoStats);
                if any {
                    accel.occluded_bundle_with(chunk, &mut occluded[range.clone()], &mut NoStats);
                }
            }
            let at = |i: usize| {
                let range = slices
                    .iter()
                    .find(|r| r.contains(&i))
                    .expect("every ray is sliced");
                format!(
                    "in a slice of {} rays (rays {order}, slice lengths cycling {}), slot {} of \
                     the slice, for ray {}\n  rays-file line: {}",
                    range.len(),
                    if downwards { "downwards" } else { "upwards" },
                    i - range.start,
                    rays[i].to_rust(),
                    rays[i].to_line()
                )
            };
            if let Some(i) = (0..rays.len()).find(|&i| !same_bits(hits[i], single[i])) {
                return Err(format!(
                    "{name}: intersect_bundle gives {:?} where intersect gives {:?} {}",
                    hits[i],
                    single[i],
                    at(i)
                ));
            }
            if let Some(i) = (0..blocked.len()).find(|&i| occluded[i] != blocked[i]) {
                return Err(format!(
                    "{name}: occluded_bundle gives {} where occluded gives {} {}",
                    occluded[i],
                    blocked[i],
                    at(i)
                ));
            }
        }
    }
    counted_and_uneven(accel, rays, any, probe)?;
    ordered(accel, rays, any, probe)?;
    Ok(as_given.unwrap_or_default())
}

/// The ordered bundle queries ([`Accel::intersect_bundle_ordered_with`]) answer each ray an
/// order lists in its own slot, as the single queries do, and leave every other slot alone:
/// for every ray shuffled, for every other ray backwards (the others' slots untouched), and
/// with entries past the rays, which are ignored.
fn ordered<A: Accel>(accel: &A, rays: &[Ray], any: bool, probe: &Probe) -> Result<(), String> {
    let name = A::NAME;
    let Some(first) = rays.first() else {
        return Ok(());
    };
    probe.bundle(first, rays.len());
    let n = rays.len() as u32;
    let single: Vec<Option<Hit>> = rays.iter().map(|r| accel.intersect(r)).collect();
    let blocked: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
    let mut rng = Rng::new(0x0d3e_0d3e);
    let mut shuffled: Vec<u32> = (0..n).collect();
    for i in (1..shuffled.len()).rev() {
        shuffled.swap(i, rng.below(i as u32 + 1) as usize);
    }
    let every_other: Vec<u32> = (0..n).rev().step_by(2).collect();
    let past: Vec<u32> = (0..n).flat_map(|i| [i, n + i, u32::MAX]).collect();
    // A slot no entry lists keeps this.
    let marker = Some(Hit {
        prim: 7,
        t: -1.0,
        u: 0.0,
        v: 0.0,
    });
    for (what, order) in [
        ("every ray, shuffled", shuffled),
        ("every other ray, backwards", every_other),
        ("every ray, with entries past the rays", past),
    ] {
        let mut listed = vec![false; rays.len()];
        for &i in order.iter().filter(|&&i| i < n) {
            listed[i as usize] = true;
        }
        let mut hits = vec![marker; rays.len()];
        accel.intersect_bundle_ordered_with(rays, &order, &mut hits, &mut NoStats);
        let want = |i: usize| if listed[i] { single[i] } else { marker };
        if let Some(i) = (0..rays.len()).find(|&i| !same_bits(hits[i], want(i))) {
            return Err(format!(
                "{name}: intersect_bundle_ordered_with ({what}) gives {:?} in slot {i} where it \
                 should hold {:?}, for ray {}",
                hits[i],
                want(i),
                rays[i].to_rust()
            ));
        }
        if any {
            // Every slot starts as the opposite of its answer.
            let mut got: Vec<bool> = blocked.iter().map(|&b| !b).collect();
            accel.occluded_bundle_ordered_with(rays, &order, &mut got, &mut NoStats);
            if let Some(i) = (0..rays.len()).find(|&i| got[i] != (blocked[i] == listed[i])) {
                return Err(format!(
                    "{name}: occluded_bundle_ordered_with ({what}) gives {} in slot {i} where it \
                     should hold {}, for ray {}",
                    got[i],
                    blocked[i] == listed[i],
                    rays[i].to_rust()
                ));
            }
        }
    }
    Ok(())
}

/// Counting changes no answer, and unequal slices answer as many rays as both have.
fn counted_and_uneven<A: Accel>(
    accel: &A,
    rays: &[Ray],
    any: bool,
    probe: &Probe,
) -> Result<(), String> {
    let Some(first) = rays.first() else {
        return Ok(());
    };
    probe.bundle(first, rays.len());
    let slices = SliceQueries {
        what: "bundle",
        counted: |r: &[Ray], o: &mut [Option<Hit>], c: &mut Counters| {
            accel.intersect_bundle_with(r, o, c)
        },
        blocked: |r: &[Ray], o: &mut [bool], c: &mut Counters| accel.occluded_bundle_with(r, o, c),
    };
    slices.check(accel, rays, any)
}

/// A pair of slice queries (the bundle or the stream queries) for [`SliceQueries::check`]:
/// `what` names them in messages (`intersect_{what}`).
pub(crate) struct SliceQueries<I, B> {
    pub what: &'static str,
    pub counted: I,
    pub blocked: B,
}

impl<I, B> SliceQueries<I, B>
where
    I: Fn(&[Ray], &mut [Option<Hit>], &mut Counters),
    B: Fn(&[Ray], &mut [bool], &mut Counters),
{
    /// Counting changes no answer, and unequal slices answer as many rays as both have and
    /// leave the other slots alone; with `any`, the occlusion query too.
    pub fn check<A: Accel>(&self, accel: &A, rays: &[Ray], any: bool) -> Result<(), String> {
        let (name, what) = (A::NAME, self.what);
        let single: Vec<Option<Hit>> = rays.iter().map(|r| accel.intersect(r)).collect();
        let mut counted = vec![None; rays.len()];
        let mut counters = Counters::default();
        (self.counted)(rays, &mut counted, &mut counters);
        if let Some(i) = (0..rays.len()).find(|&i| !same_bits(counted[i], single[i])) {
            return Err(format!(
                "{name}: intersect_{what}_with(Counters) gives {:?} where intersect gives {:?}, \
                 for ray {}",
                counted[i],
                single[i],
                rays[i].to_rust()
            ));
        }
        // Three slots more than rays: the extra ones keep what they held.
        let marker = Some(Hit {
            prim: 7,
            t: -1.0,
            u: 0.0,
            v: 0.0,
        });
        let mut longer = vec![marker; rays.len() + 3];
        (self.counted)(rays, &mut longer, &mut Counters::default());
        if longer[rays.len()..].iter().any(|&h| !same_bits(h, marker))
            || (0..rays.len()).any(|i| !same_bits(longer[i], single[i]))
        {
            return Err(format!(
                "{name}: intersect_{what} with {} rays and {} answer slots must answer the rays \
                 and leave the other slots alone",
                rays.len(),
                longer.len()
            ));
        }
        // Fewer slots than rays: the first rays are answered.
        let mut shorter = vec![None; rays.len() / 2];
        (self.counted)(rays, &mut shorter, &mut Counters::default());
        if (0..shorter.len()).any(|i| !same_bits(shorter[i], single[i])) {
            return Err(format!(
                "{name}: intersect_{what} with {} rays and {} answer slots must answer the first \
                 {} rays",
                rays.len(),
                shorter.len(),
                shorter.len()
            ));
        }
        if any {
            let blocked: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
            let mut got = vec![true; rays.len() + 3];
            (self.blocked)(rays, &mut got, &mut counters);
            if got[..rays.len()] != blocked[..] || got[rays.len()..].iter().any(|&b| !b) {
                return Err(format!(
                    "{name}: occluded_{what}_with(Counters) with {} rays and {} slots must \
                     answer as occluded does and leave the other slots alone",
                    rays.len(),
                    got.len()
                ));
            }
        }
        Ok(())
    }
}

/// Checks that a structure with its own bundle traversal walks coherent rays together: primary
/// rays of a 256×192 image in 8×8 tiles over the sphereflake and the teapot in a stadium, and
/// their shadow rays towards a point light, traced as bundles answer exactly as single rays,
/// with bundle steps counted ([`Counters::lane_slots`]) and fewer than a quarter of the primary
/// rays finished alone; with `any_hit_walks`, the shadow rays' bundles take steps too. For
/// structure crates' own tests: a bundle traversal that quietly sends every ray down the
/// single-ray path fails it.
///
/// # Panics
/// At the first difference, or when the rays did not travel together.
pub fn check_coherent_bundles<A: Accel<Prim = rt_core::Triangle>>(
    params: &A::Params,
    any_hit_walks: bool,
) {
    for name in ["sphereflake", "teapot-in-stadium"] {
        let tris = rt_scene::scenes::builtin(name)
            .expect("a built-in scene")
            .triangles();
        let accel = A::build(&tris, params);
        if let Err(e) = check_coherent_bundles_on(&accel, &tris, (256, 192), any_hit_walks) {
            panic!("{name}: {e}");
        }
    }
}

/// [`check_coherent_bundles`] on one scene: `tris` built into `accel`, primary rays of a
/// `width × height` image framing them in 8×8 tiles and their shadow rays. The first problem
/// found is the error.
pub fn check_coherent_bundles_on<A: Accel>(
    accel: &A,
    tris: &[rt_core::Triangle],
    (width, height): (u32, u32),
    any_hit_walks: bool,
) -> Result<(), String> {
    let bounds = rt_core::valid_bounds(tris);
    let camera = rt_scene::Camera::framing(&bounds, width, height);
    let (primary, _) = camera.tiled_rays(width, height, (8, 8));
    let light = bounds.max + bounds.extent();
    let shadow: Vec<Ray> = primary
        .iter()
        .filter_map(|r| {
            let p = r.at(accel.intersect(r)?.t);
            Some(Ray::with_interval(p, light - p, 1e-3, 1.0))
        })
        .collect();
    let single: Vec<Option<Hit>> = primary.iter().map(|r| accel.intersect(r)).collect();
    let mut hits = vec![None; primary.len()];
    let mut c = Counters::default();
    accel.intersect_bundle_with(&primary, &mut hits, &mut c);
    if let Some(i) = (0..hits.len()).find(|&i| !same_bits(hits[i], single[i])) {
        return Err(format!(
            "primary ray {i}: bundle {:?}, single {:?}",
            hits[i], single[i]
        ));
    }
    if c.lane_slots == 0 {
        return Err(format!("no bundle step at all: {c:?}"));
    }
    if c.single_rays * 4 >= primary.len() as u64 {
        return Err(format!(
            "{} of {} primary rays finished alone",
            c.single_rays,
            primary.len()
        ));
    }
    let blocked: Vec<bool> = shadow.iter().map(|r| accel.occluded(r)).collect();
    let mut got = vec![false; shadow.len()];
    let mut c = Counters::default();
    accel.occluded_bundle_with(&shadow, &mut got, &mut c);
    if let Some(i) = (0..got.len()).find(|&i| got[i] != blocked[i]) {
        return Err(format!(
            "shadow ray {i}: bundle {}, single {}",
            got[i], blocked[i]
        ));
    }
    if any_hit_walks && c.lane_slots == 0 {
        return Err(format!("no shadow bundle step at all: {c:?}"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two passes cut every ray into exactly one slice each, and between them use every
    /// length once the rays are enough.
    #[test]
    fn cycled_slices_cover_the_rays_and_use_every_length() {
        for len in [0, 1, 5, 216, 217, 1000, 1217, 3000] {
            let mut lengths = std::collections::BTreeSet::new();
            for downwards in [false, true] {
                let slices = cycled_slices(len, downwards);
                let mut next = 0;
                for r in &slices {
                    assert_eq!(r.start, next, "{len} rays, {slices:?}");
                    assert!(!r.is_empty(), "{len} rays, {slices:?}");
                    next = r.end;
                    lengths.insert(r.len());
                }
                assert_eq!(next, len, "{len} rays, {slices:?}");
            }
            if len >= 217 + 1000 {
                assert!(
                    BUNDLE_SIZES.iter().all(|s| lengths.contains(s)),
                    "{len}: {lengths:?}"
                );
            }
        }
        assert_eq!(cycled_slices(20, false), [0..1, 1..8, 8..16, 16..20]);
        assert_eq!(cycled_slices(1003, true), [0..1000, 1000..1003]);
    }
}

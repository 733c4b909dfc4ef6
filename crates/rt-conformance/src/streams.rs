//! The stream check: a structure's stream queries ([`Accel::intersect_stream_with`],
//! [`Accel::occluded_stream_with`]) must answer every ray exactly as its single-ray queries do,
//! whatever order the rays come in and however long the stream.

use crate::Probe;
use crate::bundles::{Singles, SliceQueries, bundle_orders, same_bits};
use rt_core::{Accel, Counters, Hit, NoStats, Ray};

/// The stream lengths the kit hands to the stream queries, cycled: none, one ray, about the
/// common bundle width (64), and about a stream's chunk in rt-bvh (256). A longer stream, the
/// rays repeated to at least [`LONG_STREAM`], follows.
pub const STREAM_SIZES: [usize; 9] = [0, 1, 63, 64, 65, 255, 256, 257, 1000];

/// The length of the long stream the kit makes of each order's rays repeated.
pub const LONG_STREAM: usize = 5000;

/// Checks that `accel`'s stream queries answer every ray of `rays`, in every order of
/// [`bundle_orders`], in streams whose lengths cycle through [`STREAM_SIZES`] and (with 64 rays
/// or more, as given and shuffled) in one stream of the rays repeated to [`LONG_STREAM`] rays or
/// more, exactly as its single-ray queries do
/// (the same bits, [`same_bits`]); that counting events changes no answer; and that slices of
/// unequal lengths answer as many rays as both have and leave the rest alone. With `any`
/// false, only the closest-hit query is checked.
///
/// # Errors
/// The first answer that differs, with its ray, the order and the stream's length.
pub fn compare_streams<A: Accel>(accel: &A, rays: &[Ray], any: bool) -> Result<(), String> {
    compare_streams_probed(accel, rays, any, &Probe::default())
}

pub(crate) fn compare_streams_probed<A: Accel>(
    accel: &A,
    rays: &[Ray],
    any: bool,
    probe: &Probe,
) -> Result<(), String> {
    let name = A::NAME;
    if rays.is_empty() {
        return Ok(());
    }
    for (order, rays) in bundle_orders(rays, 0x5eed_57ea) {
        let (single, blocked) = singles(accel, &rays, any);
        let mut streams = Vec::new();
        let mut start = 0;
        for &size in STREAM_SIZES.iter().cycle() {
            let end = (start + size).min(rays.len());
            streams.push(start..end);
            start = end;
            if start >= rays.len() {
                break;
            }
        }
        for range in &streams {
            let chunk = &rays[range.clone()];
            let slots = (
                &single[range.clone()],
                blocked.get(range.clone()).unwrap_or(&[]),
            );
            probe.bundle(chunk.first().unwrap_or(&rays[0]), chunk.len());
            check_stream(accel, chunk, slots).map_err(|e| {
                format!(
                    "{name}: {e} (rays {order}, in a stream of {} rays)",
                    chunk.len()
                )
            })?;
        }
        // The rays repeated into one long stream: for scenes of many rays (the fixed scenes),
        // in the order as given and shuffled. (A random case's few rays repeated thousands of
        // times would cost more than they find.)
        if rays.len() < 64 || !matches!(order, "as given" | "shuffled") {
            continue;
        }
        let copies = LONG_STREAM.div_ceil(rays.len());
        let long: Vec<Ray> = rays
            .iter()
            .copied()
            .cycle()
            .take(copies * rays.len())
            .collect();
        let long_single: Vec<Option<Hit>> =
            single.iter().copied().cycle().take(long.len()).collect();
        let long_blocked: Vec<bool> = blocked.iter().copied().cycle().take(long.len()).collect();
        probe.bundle(&long[0], long.len());
        check_stream(accel, &long, (&long_single, &long_blocked)).map_err(|e| {
            format!(
                "{name}: {e} (rays {order}, repeated into a stream of {} rays)",
                long.len()
            )
        })?;
    }
    counted_and_uneven(accel, rays, any, probe)
}

/// The single queries' answers to `rays`: the closest hits, and the any hits when `any`.
fn singles<A: Accel>(accel: &A, rays: &[Ray], any: bool) -> Singles {
    let single = rays.iter().map(|r| accel.intersect(r)).collect();
    let blocked = if any {
        rays.iter().map(|r| accel.occluded(r)).collect()
    } else {
        Vec::new()
    };
    (single, blocked)
}

/// One stream of `rays` against the single answers `(single, blocked)` (`blocked` empty: the
/// any hit is not checked).
fn check_stream<A: Accel>(
    accel: &A,
    rays: &[Ray],
    (single, blocked): (&[Option<Hit>], &[bool]),
) -> Result<(), String> {
    let mut hits = vec![None; rays.len()];
    accel.intersect_stream_with(rays, &mut hits, &mut NoStats);
    let at = |i: usize| {
        format!(
            "slot {i}, for ray {}\n  rays-file line: {}",
            rays[i].to_rust(),
            rays[i].to_line()
        )
    };
    if let Some(i) = (0..rays.len()).find(|&i| !same_bits(hits[i], single[i])) {
        return Err(format!(
            "intersect_stream gives {:?} where intersect gives {:?} in {}",
            hits[i],
            single[i],
            at(i)
        ));
    }
    if !blocked.is_empty() {
        let mut occluded = vec![false; rays.len()];
        accel.occluded_stream_with(rays, &mut occluded, &mut NoStats);
        if let Some(i) = (0..rays.len()).find(|&i| occluded[i] != blocked[i]) {
            return Err(format!(
                "occluded_stream gives {} where occluded gives {} in {}",
                occluded[i],
                blocked[i],
                at(i)
            ));
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
    probe.bundle(&rays[0], rays.len());
    let slices = SliceQueries {
        what: "stream",
        counted: |r: &[Ray], o: &mut [Option<Hit>], c: &mut Counters| {
            accel.intersect_stream_with(r, o, c)
        },
        blocked: |r: &[Ray], o: &mut [bool], c: &mut Counters| accel.occluded_stream_with(r, o, c),
    };
    slices.check(accel, rays, any)
}

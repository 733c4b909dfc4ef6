//! The batch check: every batch query ([`rt_core::batch`], [`rt_sdf::batch`]) must answer each
//! ray, point and box in its own slot exactly as the structure's single query does, on threads
//! other than the one that built the structure.
//!
//! The single queries are checked against brute force by the other parts; this part checks
//! what the batches add: the slots (chunks of [`CHUNK`](rt_core::batch::CHUNK), Morton order,
//! rays made from flat rows) and a structure that answers the same on every thread. A structure
//! that keeps state for one thread (a cache in a thread-local, say) passes every single-query
//! check and fails this one.

use crate::bundles::{Singles, same_bits};
use crate::{Doing, Probe};
use rt_core::batch::{self, FlatRays};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Accel, Hit, PointHit, Ray};
use rt_sdf::{SignedDistance, SignedPoint, WindingTree};

/// The pool the batches run on: two threads, whatever the machine, so that the rays are split
/// between threads and none of them is the thread that built the structure.
fn pool() -> &'static rayon::ThreadPool {
    static POOL: std::sync::OnceLock<rayon::ThreadPool> = std::sync::OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .thread_name(|i| format!("conformance batch {i}"))
            .build()
            .expect("the kit starts two threads for its batch checks")
    })
}

/// The most inputs a batch check hands to one batch: three chunks and part of a fourth, so that
/// the pool's threads share the chunks and the last is short.
// The single queries are checked on every input by the parts; the slots and the threads show
// as well on these.
const MOST: usize = 3 * batch::CHUNK + 7;

/// At most [`MOST`] of `items`, spread evenly over them (the same ones of any slice as long).
fn spread<T: Clone>(items: &[T]) -> Vec<T> {
    let stride = items.len().div_ceil(MOST).max(1);
    items.iter().step_by(stride).cloned().collect()
}

/// A batch check, to run on the kit's pool ([`on_pool`]) after the single queries it compares
/// with ran on the kit's own thread.
pub(crate) type Check<'a> = Box<dyn FnOnce() -> Result<(), String> + Send + 'a>;

/// Runs `checks` in order on the kit's pool, in one visit: the first error, if any.
// One visit a case rather than one a batch: each visit wakes the pool's threads.
pub(crate) fn on_pool(checks: Vec<Check<'_>>) -> Result<(), String> {
    if checks.is_empty() {
        return Ok(());
    }
    pool().install(|| checks.into_iter().try_for_each(|check| check()))
}

/// The first slot `i` where `same(got[i], want[i])` fails, as an error naming the query and
/// the input.
fn first_difference<T: std::fmt::Debug>(
    query: &str,
    got: &[T],
    want: &[T],
    same: impl Fn(&T, &T) -> bool,
    input: impl Fn(usize) -> String,
) -> Result<(), String> {
    match (0..want.len()).find(|&i| !same(&got[i], &want[i])) {
        None => Ok(()),
        Some(i) => Err(format!(
            "{query} of {} inputs on two threads gives {:?} in slot {i} where the single query \
             gives {:?}\n  for {}",
            want.len(),
            got[i],
            want[i],
            input(i)
        )),
    }
}

fn ray_text(ray: &Ray) -> String {
    format!("ray {}\n  rays-file line: {}", ray.to_rust(), ray.to_line())
}

fn same_hits(a: &[Hit], b: &[Hit]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same_bits(Some(*x), Some(*y)))
}

/// The closest and any hit of `rays` in batches, from the slice and from flat rows of six (the
/// valid rays over the first valid ray's interval, which a row of six cannot carry), against
/// the single queries' answers `single` (the any hit only where they hold it).
pub(crate) fn rays<A: Accel>(
    accel: &A,
    rays: &[Ray],
    (single, blocked): &Singles,
    probe: &Probe,
) -> Result<(), String> {
    let (rays, single, blocked) = (&spread(rays)[..], &spread(single), &spread(blocked));
    let Some(first) = rays.first() else {
        return Ok(());
    };
    probe.set(Doing::Bundle(*first, rays.len()));
    let fail = |m: String| format!("{}: {m}", A::NAME);
    // The rays flat rows make again bit for bit: the valid ones over one interval.
    let interval = rays
        .iter()
        .find(|r| r.is_valid())
        .map(|r| (r.t_min, r.t_max));
    let flat: Vec<usize> = (0..rays.len())
        .filter(|&i| rays[i].is_valid() && Some((rays[i].t_min, rays[i].t_max)) == interval)
        .collect();
    let rows: Vec<f32> = flat
        .iter()
        .flat_map(|&i| {
            let (o, d) = (rays[i].origin, rays[i].dir());
            [o.x, o.y, o.z, d.x, d.y, d.z]
        })
        .collect();
    let (t_min, t_max) = interval.unwrap_or((0.0, f32::INFINITY));
    let rows = FlatRays::new(&rows, t_min, t_max)
        .map_err(|e| fail(format!("FlatRays::new refuses the rows of valid rays: {e}")))?;
    let text = |i: usize| ray_text(&rays[i]);
    let flat_text = |k: usize| ray_text(&rays[flat[k]]);
    let same = |a: &Option<Hit>, b: &Option<Hit>| same_bits(*a, *b);
    let mut got = vec![None; rays.len()];
    let mut got_flat = vec![None; flat.len()];
    batch::intersect(accel, rays, &mut got[..]);
    batch::intersect(accel, &rows, &mut got_flat[..]);
    first_difference("batch::intersect", &got, single, same, text).map_err(fail)?;
    let want: Vec<Option<Hit>> = flat.iter().map(|&i| single[i]).collect();
    first_difference(
        "batch::intersect (FlatRays)",
        &got_flat,
        &want,
        same,
        flat_text,
    )
    .map_err(fail)?;
    if blocked.len() == rays.len() {
        let single = blocked;
        let mut got: Vec<bool> = single.iter().map(|b| !b).collect();
        let want: Vec<bool> = flat.iter().map(|&i| single[i]).collect();
        let mut got_flat: Vec<bool> = want.iter().map(|b| !b).collect();
        batch::occluded(accel, rays, &mut got[..]);
        batch::occluded(accel, &rows, &mut got_flat[..]);
        first_difference("batch::occluded", &got, single, PartialEq::eq, text).map_err(fail)?;
        first_difference(
            "batch::occluded (FlatRays)",
            &got_flat,
            &want,
            PartialEq::eq,
            flat_text,
        )
        .map_err(fail)?;
    }
    Ok(())
}

/// The single queries' hit counts and all hits of `rays`, for [`hits`].
pub(crate) fn single_hits<A: Accel>(accel: &A, rays: &[Ray]) -> (Vec<usize>, Vec<Vec<Hit>>) {
    let counts = rays.iter().map(|r| accel.count_hits(r)).collect();
    (counts, rays.iter().map(|r| accel.all_hits(r)).collect())
}

/// Hit counts and all hits of `rays` in batches against the single queries' answers
/// ([`single_hits`]).
pub(crate) fn hits<A: Accel>(
    accel: &A,
    rays: &[Ray],
    (single, all): &(Vec<usize>, Vec<Vec<Hit>>),
    probe: &Probe,
) -> Result<(), String> {
    let Some(first) = rays.first() else {
        return Ok(());
    };
    probe.set(Doing::Bundle(*first, rays.len()));
    let fail = |m: String| format!("{}: {m}", A::NAME);
    let mut got = vec![usize::MAX; rays.len()];
    batch::count_hits(accel, rays, &mut got[..]);
    first_difference("batch::count_hits", &got, single, PartialEq::eq, |i| {
        ray_text(&rays[i])
    })
    .map_err(fail)?;
    let mut got = vec![Vec::new(); rays.len()];
    batch::all_hits(accel, rays, &mut got[..]);
    first_difference(
        "batch::all_hits",
        &got,
        all,
        |a, b| same_hits(a, b),
        |i| ray_text(&rays[i]),
    )
    .map_err(fail)
}

/// Closest points in batches against the single query's answers `single`: the points of the
/// maximum distance most of them share.
pub(crate) fn points<A: Accel>(
    accel: &A,
    points: &[(Vec3, f32)],
    single: &[Option<PointHit>],
    probe: &Probe,
) -> Result<(), String> {
    if let Some(max_distance) = common_distance(points) {
        let (these, single) = with_distance(points, single, max_distance);
        let (these, single) = (spread(&these), spread(&single));
        probe.set(Doing::Point(these[0], max_distance));
        let mut got = vec![None; these.len()];
        batch::closest_points(accel, &these, max_distance, &mut got[..]);
        first_difference("batch::closest_points", &got, &single, PartialEq::eq, |i| {
            point_text(these[i], max_distance)
        })
        .map_err(|m| format!("{}: {m}", A::NAME))?;
    }
    Ok(())
}

/// The points of `points` with `max_distance`, and their answers of `single`.
fn with_distance<T: Clone>(
    points: &[(Vec3, f32)],
    single: &[T],
    max_distance: f32,
) -> (Vec<Vec3>, Vec<T>) {
    points
        .iter()
        .zip(single)
        .filter(|(p, _)| p.1.to_bits() == max_distance.to_bits())
        .map(|(p, s)| (p.0, s.clone()))
        .unzip()
}

/// The maximum distance most of `points` share (the first such, on a tie): a batch takes one
/// limit for all its points, and the kit's points come with several limits each (see
/// [`scene_points`](crate::scene_points)); each point's own limits are the single query's
/// check.
// PERF: a batch for each limit (most points have three of their own) made the grid's
// conformance suite take 62 s instead of 42 s (test profile, Intel Emerald Rapids); without
// the batch checks it takes 30-39 s (four runs alternating with these, 39-41 s).
fn common_distance(points: &[(Vec3, f32)]) -> Option<f32> {
    let mut counts: Vec<(u32, usize)> = Vec::new();
    for &(_, d) in points {
        match counts.iter_mut().find(|c| c.0 == d.to_bits()) {
            Some(c) => c.1 += 1,
            None => counts.push((d.to_bits(), 1)),
        }
    }
    let most = counts.iter().map(|c| c.1).max()?;
    counts
        .iter()
        .find(|c| c.1 == most)
        .map(|c| f32::from_bits(c.0))
}

fn point_text(p: Vec3, max_distance: f32) -> String {
    format!(
        "the point Vec3::new({:?}, {:?}, {:?}) within {max_distance:?}",
        p.x, p.y, p.z
    )
}

/// Box overlaps in batches against the single query's answers `single`.
pub(crate) fn boxes<A: Accel>(
    accel: &A,
    boxes: &[Aabb],
    single: &[Vec<u32>],
    probe: &Probe,
) -> Result<(), String> {
    let (boxes, single) = (&spread(boxes)[..], &spread(single));
    let Some(first) = boxes.first() else {
        return Ok(());
    };
    probe.set(Doing::Box(*first));
    let mut got = vec![vec![u32::MAX]; boxes.len()];
    batch::overlapping(accel, boxes, &mut got[..]);
    first_difference("batch::overlapping", &got, single, PartialEq::eq, |i| {
        format!("the box {:?}", boxes[i])
    })
    .map_err(|m| format!("{}: {m}", A::NAME))
}

/// Signed distances in batches against the single query's answers `single`: the points of the
/// maximum distance most of them share.
pub(crate) fn signed<A: Accel>(
    accel: &A,
    tree: &WindingTree,
    points: &[(Vec3, f32)],
    single: &[Option<SignedPoint>],
    probe: &Probe,
) -> Result<(), String> {
    let fail = |m: String| format!("{}: {m}", A::NAME);
    if let Some(max_distance) = common_distance(points) {
        let (these, single) = with_distance(points, single, max_distance);
        probe.set(Doing::Inside(these[0], max_distance));
        let mut got = vec![None; these.len()];
        rt_sdf::batch::signed_distances(accel, tree, &these, max_distance, &mut got[..]);
        first_difference(
            "rt_sdf::batch::signed_distances",
            &got,
            &single,
            PartialEq::eq,
            |i| point_text(these[i], max_distance),
        )
        .map_err(fail)?;
    }
    Ok(())
}

/// Checks that every batch query answers as the structure's single query does, slot for slot,
/// on a pool of two threads: the closest and any hit of `rays` (from the slice and from flat
/// rows), their hit counts and all hits, closest points and signed distances at the points
/// [`scene_points`](crate::scene_points) makes from them, and box overlaps of the boxes
/// [`scene_boxes`](crate::scene_boxes) makes. `accel` must be built over `prims`. The parts of
/// [`check_case`](crate::check_case) run these checks beside their own.
///
/// # Errors
/// The first answer that differs, with its query and input.
pub fn compare_batches<A: Accel>(accel: &A, prims: &[A::Prim], rays: &[Ray]) -> Result<(), String> {
    let probe = Probe::default();
    let single = (
        rays.iter().map(|r| accel.intersect(r)).collect(),
        rays.iter().map(|r| accel.occluded(r)).collect(),
    );
    let hit_counts = single_hits(accel, rays);
    let near = crate::scene_points(prims, rays);
    let answers: Vec<_> = near
        .iter()
        .map(|&(p, d)| accel.closest_point(p, d))
        .collect();
    let tree = WindingTree::build(prims).ok();
    let signed_answers: Vec<_> = tree
        .iter()
        .flat_map(|tree| near.iter().map(|&(p, d)| accel.signed_distance(tree, p, d)))
        .collect();
    let boxes = crate::scene_boxes(prims, prims.len() as u64);
    let box_answers: Vec<_> = boxes.iter().map(|b| accel.overlapping(b)).collect();
    let probe = &probe;
    on_pool(vec![
        Box::new(|| self::rays(accel, rays, &single, probe)),
        Box::new(|| hits(accel, rays, &hit_counts, probe)),
        Box::new(|| points(accel, &near, &answers, probe)),
        Box::new(|| match &tree {
            Some(tree) => signed(accel, tree, &near, &signed_answers, probe),
            None => Ok(()),
        }),
        Box::new(|| self::boxes(accel, &boxes, &box_answers, probe)),
    ])
}

//! `compare --query closest-point`, `overlap`, `all-hits`, `filtered` and `signed-distance`: the
//! shootout for
//! queries beyond the closest and any hit.
//!
//! Every row answers the same queries: closest points to [`raygen::query_points`], the
//! primitives meeting boxes around them ([`overlap_boxes`]), every hit along the rays `--rays`
//! names, or those rays' closest and any hits through an alpha mask ([`alpha_mask`]). Brute
//! force checks a random subset, the rows are checked against each other on every query, and
//! brute force settles every query on which they disagree, as for rays. One generic core,
//! [`measure_queries`], runs every kind ([`Queries`] says how each asks and compares).

use super::run::make_rays;
use super::{Args, Report, Row, Source, build_fastest, checked_subset};
use crate::structures;
use rt_core::glam::Vec3;
use rt_core::{Aabb, Counters, DynAccel, Hit, PointHit, PrimHit, Primitive, Ray, Rng, Triangle};
use rt_scene::raygen;
use rt_sdf::{SignedPoint, WindingTree};
use std::fmt::Debug;
use std::time::{Duration, Instant};

/// The report's `ray_kind` for closest-point queries.
pub const KIND: &str = "closest-point";

/// The report's `ray_kind` for box overlap queries.
pub const OVERLAP_KIND: &str = "overlap";

/// The report's `ray_kind` for all-hits queries.
pub const ALL_HITS_KIND: &str = "all-hits";

/// The report's `ray_kind` for filtered queries.
pub const FILTERED_KIND: &str = "filtered";

/// The report's `ray_kind` for signed-distance queries.
pub const SIGNED_KIND: &str = "signed-distance";

/// Whether a report holds queries other than closest and any hits.
pub fn is_query_kind(kind: &str) -> bool {
    [
        KIND,
        OVERLAP_KIND,
        ALL_HITS_KIND,
        FILTERED_KIND,
        SIGNED_KIND,
    ]
    .contains(&kind)
}

/// The alpha mask of `compare --query filtered`: a checkerboard of 8 × 8 squares over each
/// triangle's barycentric coordinates `(u, v)`, the squares with an odd sum of indices cut
/// away, so every triangle keeps about half its surface.
pub fn alpha_mask(_prim: u32, hit: &PrimHit) -> bool {
    ((hit.u * 8.0) as u32 + (hit.v * 8.0) as u32).is_multiple_of(2)
}

/// A query on which a row disagreed with brute force: the query as Rust source to paste into a
/// test, and both answers as `Debug` prints them.
#[derive(Debug)]
pub struct QueryDisagreement {
    pub structure: String,
    pub index: usize,
    pub rust: String,
    pub expected: String,
    pub got: String,
}

/// One kind of non-ray query: how a structure answers a chunk of them, how answers compare,
/// and how a query prints as Rust.
trait Queries {
    type Query: Copy + Send + Sync;
    type Answer: Clone + Debug + Send + Sync;
    /// What every row's queries share beyond the structure, made once per scene: nothing, or
    /// for signed distance the winding tree and the triangles.
    type Context: Sync;
    const KIND: &'static str;
    /// The queries the rows answer, and the view they come from (empty if none).
    fn queries(args: &Args, source: &Source) -> Result<(Vec<Self::Query>, &'static str), String>;
    /// The shared context, and a sentence on what it took to make (empty if nothing).
    fn context(source: &Source) -> (Self::Context, String);
    /// Every answer, counted.
    fn counted(
        s: &dyn DynAccel<Triangle>,
        c: &Self::Context,
        q: &[Self::Query],
    ) -> (Vec<Self::Answer>, Counters);
    /// How many queries found something, uncounted: the timed pass.
    fn timed(s: &dyn DynAccel<Triangle>, c: &Self::Context, q: &[Self::Query]) -> usize;
    /// Brute force's answers, which every row is checked against: by default
    /// [`counted`](Queries::counted) on brute force.
    fn reference(
        s: &dyn DynAccel<Triangle>,
        c: &Self::Context,
        q: &[Self::Query],
    ) -> (Vec<Self::Answer>, Counters) {
        Self::counted(s, c, q)
    }
    fn found(a: &Self::Answer) -> bool;
    fn agree(a: &Self::Answer, b: &Self::Answer) -> bool;
    fn rust(q: &Self::Query) -> String;
}

/// Closest points ([`Accel::closest_point`](rt_core::Accel::closest_point)).
struct ClosestPoints;

impl Queries for ClosestPoints {
    type Query = (Vec3, f32);
    type Answer = Option<PointHit>;
    type Context = ();
    const KIND: &'static str = KIND;
    fn queries(args: &Args, source: &Source) -> Result<(Vec<(Vec3, f32)>, &'static str), String> {
        let max = args.max_distance.unwrap_or(f32::INFINITY);
        if max.is_nan() || max < 0.0 {
            return Err(format!("--max-distance must be at least 0, not {max}"));
        }
        let points = raygen::query_points(&source.mesh, &source.bounds, args.points, args.seed);
        Ok((points.into_iter().map(|p| (p, max)).collect(), ""))
    }
    fn context(_: &Source) -> ((), String) {
        ((), String::new())
    }
    fn counted(
        s: &dyn DynAccel<Triangle>,
        _: &(),
        q: &[(Vec3, f32)],
    ) -> (Vec<Option<PointHit>>, Counters) {
        structures::closest_counted(s, q)
    }
    fn timed(s: &dyn DynAccel<Triangle>, _: &(), q: &[(Vec3, f32)]) -> usize {
        structures::closest_timed(s, q)
    }
    fn found(a: &Option<PointHit>) -> bool {
        a.is_some()
    }
    fn agree(a: &Option<PointHit>, b: &Option<PointHit>) -> bool {
        PointHit::agree(*a, *b)
    }
    fn rust(&(p, max): &(Vec3, f32)) -> String {
        format!(
            "closest_point(Vec3::new({:?}, {:?}, {:?}), {max:?})",
            p.x, p.y, p.z
        )
    }
}

/// Box overlap ([`Accel::overlapping`](rt_core::Accel::overlapping)).
struct Overlaps;

impl Queries for Overlaps {
    type Query = Aabb;
    type Answer = Vec<u32>;
    type Context = ();
    const KIND: &'static str = OVERLAP_KIND;
    fn queries(args: &Args, source: &Source) -> Result<(Vec<Aabb>, &'static str), String> {
        let size = args.box_size;
        if !(size > 0.0 && size <= 1.0) {
            return Err(format!(
                "--box-size must be above 0 and at most 1, not {size}"
            ));
        }
        let boxes = overlap_boxes(&source.mesh, &source.bounds, args.points, size, args.seed);
        Ok((boxes, ""))
    }
    fn context(_: &Source) -> ((), String) {
        ((), String::new())
    }
    fn counted(s: &dyn DynAccel<Triangle>, _: &(), q: &[Aabb]) -> (Vec<Vec<u32>>, Counters) {
        structures::overlap_counted(s, q)
    }
    fn timed(s: &dyn DynAccel<Triangle>, _: &(), q: &[Aabb]) -> usize {
        structures::overlap_timed(s, q)
    }
    fn found(a: &Vec<u32>) -> bool {
        !a.is_empty()
    }
    fn agree(a: &Vec<u32>, b: &Vec<u32>) -> bool {
        a == b
    }
    fn rust(b: &Aabb) -> String {
        format!(
            "overlapping(&Aabb::new(Vec3::new({:?}, {:?}, {:?}), Vec3::new({:?}, {:?}, {:?})))",
            b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
        )
    }
}

/// Signed distances (`rt_sdf::SignedDistance::signed_distance`) at the
/// closest-point queries' points: every row signs its closest point with one shared
/// [`WindingTree`]; brute force signs its own with the exact winding number.
struct SignedDistances;

impl Queries for SignedDistances {
    type Query = (Vec3, f32);
    type Answer = Option<SignedPoint>;
    type Context = (WindingTree, std::sync::Arc<[Triangle]>);
    const KIND: &'static str = SIGNED_KIND;
    fn queries(args: &Args, source: &Source) -> Result<(Vec<(Vec3, f32)>, &'static str), String> {
        ClosestPoints::queries(args, source)
    }
    fn context(source: &Source) -> (Self::Context, String) {
        let t = Instant::now();
        // Triangles are all the mesh holds, so the tree always builds.
        let tree = WindingTree::build(&source.mesh)
            .unwrap_or_else(|_| WindingTree::build::<Triangle>(&[]).expect("an empty tree builds"));
        let note = format!(
            "Every row signs with one winding tree (built in {:.1} ms, {:.2} MiB, not in the rows' \
             figures); brute force signs with the exact sum over every triangle.",
            t.elapsed().as_secs_f64() * 1e3,
            tree.memory_bytes() as f64 / (1024.0 * 1024.0)
        );
        ((tree, source.mesh.clone()), note)
    }
    fn counted(
        s: &dyn DynAccel<Triangle>,
        (tree, _): &Self::Context,
        q: &[(Vec3, f32)],
    ) -> (Vec<Option<SignedPoint>>, Counters) {
        structures::signed_counted(s, tree, q)
    }
    fn timed(s: &dyn DynAccel<Triangle>, (tree, _): &Self::Context, q: &[(Vec3, f32)]) -> usize {
        structures::signed_timed(s, tree, q)
    }
    fn reference(
        s: &dyn DynAccel<Triangle>,
        (_, tris): &Self::Context,
        q: &[(Vec3, f32)],
    ) -> (Vec<Option<SignedPoint>>, Counters) {
        structures::signed_exact(s, tris, q)
    }
    fn found(a: &Option<SignedPoint>) -> bool {
        a.is_some_and(|s| s.inside)
    }
    fn agree(a: &Option<SignedPoint>, b: &Option<SignedPoint>) -> bool {
        PointHit::agree(a.map(|s| s.near), b.map(|s| s.near))
            && a.map(|s| s.inside) == b.map(|s| s.inside)
    }
    fn rust(&(p, max): &(Vec3, f32)) -> String {
        format!(
            "signed_distance(&WindingTree::build(&mesh)?, Vec3::new({:?}, {:?}, {:?}), {max:?})",
            p.x, p.y, p.z
        )
    }
}

/// The rays of `--rays` (and `--view`, `--rays-file`), for the queries made of rays.
/// The report's `view` names the rays, since its `ray_kind` names the query.
fn ray_queries(args: &Args, source: &Source) -> Result<(Vec<Ray>, &'static str), String> {
    use super::ViewKind::{Filled, Sparse};
    let (rays, kind, _) = make_rays(args, source)?;
    let view = match (kind, args.view) {
        ("primary", Filled) => "primary rays from the filled view",
        ("primary", Sparse) => "primary rays from the sparse view",
        ("shadow", Filled) => "shadow rays from the filled view's hits",
        ("shadow", Sparse) => "shadow rays from the sparse view's hits",
        ("incoherent", _) => "incoherent rays",
        _ => "rays from the file",
    };
    Ok((rays, view))
}

/// The rays as Rust source, every float printed to parse back to its bits.
fn ray_rust(call: &str, r: &Ray) -> String {
    format!("{call}(&{})", r.to_rust())
}

/// Every hit along a ray ([`Accel::all_hits`](rt_core::Accel::all_hits)).
struct AllHits;

impl Queries for AllHits {
    type Query = Ray;
    type Answer = Vec<Hit>;
    type Context = ();
    const KIND: &'static str = ALL_HITS_KIND;
    fn queries(args: &Args, source: &Source) -> Result<(Vec<Ray>, &'static str), String> {
        ray_queries(args, source)
    }
    fn context(_: &Source) -> ((), String) {
        ((), String::new())
    }
    fn counted(s: &dyn DynAccel<Triangle>, _: &(), q: &[Ray]) -> (Vec<Vec<Hit>>, Counters) {
        structures::all_hits_counted(s, q)
    }
    fn timed(s: &dyn DynAccel<Triangle>, _: &(), q: &[Ray]) -> usize {
        structures::all_hits_timed(s, q)
    }
    fn found(a: &Vec<Hit>) -> bool {
        !a.is_empty()
    }
    fn agree(a: &Vec<Hit>, b: &Vec<Hit>) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| Hit::agree(Some(*x), Some(*y)))
    }
    fn rust(r: &Ray) -> String {
        ray_rust("all_hits", r)
    }
}

/// Closest and any hit through [`alpha_mask`]
/// ([`Accel::intersect_filtered`](rt_core::Accel::intersect_filtered),
/// [`Accel::occluded_filtered`](rt_core::Accel::occluded_filtered)).
struct Filtered;

impl Queries for Filtered {
    type Query = Ray;
    type Answer = (Option<Hit>, bool);
    type Context = ();
    const KIND: &'static str = FILTERED_KIND;
    fn queries(args: &Args, source: &Source) -> Result<(Vec<Ray>, &'static str), String> {
        ray_queries(args, source)
    }
    fn context(_: &Source) -> ((), String) {
        ((), String::new())
    }
    fn counted(
        s: &dyn DynAccel<Triangle>,
        _: &(),
        q: &[Ray],
    ) -> (Vec<(Option<Hit>, bool)>, Counters) {
        structures::filtered_counted(s, q, alpha_mask)
    }
    fn timed(s: &dyn DynAccel<Triangle>, _: &(), q: &[Ray]) -> usize {
        structures::filtered_timed(s, q, alpha_mask)
    }
    fn found(a: &(Option<Hit>, bool)) -> bool {
        a.0.is_some()
    }
    fn agree(a: &(Option<Hit>, bool), b: &(Option<Hit>, bool)) -> bool {
        Hit::agree(a.0, b.0) && a.1 == b.1
    }
    fn rust(r: &Ray) -> String {
        ray_rust("intersect_filtered", r)
    }
}

/// The boxes of `compare --query overlap`: one around each of `count` query points
/// ([`raygen::query_points`]: half uniform in the scene box grown by a quarter, half near the
/// surface), each side `size` of the scene box's diagonal times a factor drawn from 0.25 to
/// 1.75, so boxes of several shapes, some thin, meet the mesh.
pub fn overlap_boxes(
    tris: &[Triangle],
    bounds: &Aabb,
    count: usize,
    size: f32,
    seed: u64,
) -> Vec<Aabb> {
    let mut rng = Rng::new(seed ^ 0x0b0e);
    let side = bounds.extent().length() * size;
    raygen::query_points(tris, bounds, count, seed)
        .into_iter()
        .map(|c| {
            let half = Vec3::new(
                rng.range(0.25, 1.75),
                rng.range(0.25, 1.75),
                rng.range(0.25, 1.75),
            ) * (0.5 * side);
            Aabb::new(c - half, c + half)
        })
        .collect()
}

pub(super) fn measure(
    args: &Args,
    threads: usize,
    entries: Vec<structures::Entry>,
) -> Result<Report, String> {
    measure_queries::<ClosestPoints>(args, threads, entries)
}

pub(super) fn measure_overlap(
    args: &Args,
    threads: usize,
    entries: Vec<structures::Entry>,
) -> Result<Report, String> {
    measure_queries::<Overlaps>(args, threads, entries)
}

pub(super) fn measure_all_hits(
    args: &Args,
    threads: usize,
    entries: Vec<structures::Entry>,
) -> Result<Report, String> {
    measure_queries::<AllHits>(args, threads, entries)
}

pub(super) fn measure_filtered(
    args: &Args,
    threads: usize,
    entries: Vec<structures::Entry>,
) -> Result<Report, String> {
    measure_queries::<Filtered>(args, threads, entries)
}

pub(super) fn measure_signed(
    args: &Args,
    threads: usize,
    entries: Vec<structures::Entry>,
) -> Result<Report, String> {
    measure_queries::<SignedDistances>(args, threads, entries)
}

fn measure_queries<K: Queries>(
    args: &Args,
    threads: usize,
    entries: Vec<structures::Entry>,
) -> Result<Report, String> {
    if args.instances.is_some() {
        return Err(format!(
            "--query {} runs on one mesh; leave out --instances (the library's Instances answer \
             these queries, compare does not field them yet)",
            K::KIND
        ));
    }
    let source = Source::load(args)?;
    let (scene, tris) = (source.label.clone(), source.mesh.clone());
    let valid = tris.iter().filter(|t| t.is_valid()).count();
    if valid == 0 {
        return Err(format!(
            "{scene}: no valid triangles (all {} are degenerate or non-finite)",
            tris.len()
        ));
    }
    if args.points == 0 {
        return Err("--points must be at least 1".into());
    }
    let (queries, view) = K::queries(args, &source)?;
    let (context, note) = K::context(&source);
    let subset = checked_subset(queries.len(), args.check_rays.unwrap_or(20_000), args.seed);
    let subset_queries: Vec<K::Query> = subset.iter().map(|&i| queries[i]).collect();

    let mut rows = Vec::new();
    let mut answers = Vec::new();
    for entry in &entries {
        let (s, build_ms) = build_fastest(|| source.build(entry), args.repeats)?;
        let (row, found) = query_row::<K>(
            &entry.name,
            s.as_ref(),
            &context,
            false,
            build_ms,
            &queries,
            args.repeats,
        );
        rows.push(row);
        answers.push(found);
    }
    let (brute, build_ms) = build_fastest(|| source.build(&structures::brute_force()), 1)?;
    let (mut brute_row, brute_found) = query_row::<K>(
        "brute-force",
        brute.as_ref(),
        &context,
        true,
        build_ms,
        &subset_queries,
        0,
    );

    let mut disagreements = Vec::new();
    let mut record = |rows: &mut [Row], i: usize, expected: &K::Answer| {
        for (row, found) in rows.iter_mut().zip(&answers) {
            if !K::agree(expected, &found[i]) {
                row.mismatches += 1;
                if disagreements.len() < 8 {
                    disagreements.push(QueryDisagreement {
                        structure: row.name.clone(),
                        index: i,
                        rust: K::rust(&queries[i]),
                        expected: format!("{expected:?}"),
                        got: format!("{:?}", found[i]),
                    });
                }
            }
        }
    };
    let mut in_subset = vec![false; queries.len()];
    for (k, &i) in subset.iter().enumerate() {
        in_subset[i] = true;
        record(&mut rows, i, &brute_found[k]);
    }
    // Outside the subset, brute force settles every query on which the rows disagree.
    let mut settled = 0;
    for i in (0..queries.len()).filter(|&i| !in_subset[i]) {
        let first = answers.first().map(|a| &a[i]);
        if answers
            .iter()
            .any(|a| first.is_some_and(|f| !K::agree(f, &a[i])))
        {
            settled += 1;
            let (expected, _) = K::reference(&*brute, &context, &queries[i..=i]);
            record(&mut rows, i, &expected[0]);
        }
    }

    let base = brute_row.mrays_per_s;
    brute_row.speedup = 1.0;
    for r in &mut rows {
        r.speedup = r.mrays_per_s / base;
    }
    let mut all_rows = vec![brute_row];
    all_rows.extend(rows);
    Ok(Report {
        scene,
        triangles: tris.len(),
        valid_triangles: valid,
        ray_kind: K::KIND,
        view,
        rays: queries.len(),
        threads,
        checked_rays: subset.len() + settled,
        rows: all_rows,
        disagreements: Vec::new(),
        query_disagreements: disagreements,
        per_ray_answers: false,
        note,
    })
}

/// One row's figures: a counted pass, then `repeats` timed passes (the fastest counts; with
/// none, the counted pass is timed). The `reference` row (brute force) answers through
/// [`Queries::reference`].
fn query_row<K: Queries>(
    name: &str,
    s: &dyn DynAccel<Triangle>,
    context: &K::Context,
    reference: bool,
    build_ms: f64,
    queries: &[K::Query],
    repeats: u32,
) -> (Row, Vec<K::Answer>) {
    let t = Instant::now();
    let (found, counters) = if reference {
        K::reference(s, context, queries)
    } else {
        K::counted(s, context, queries)
    };
    let mut best = t.elapsed();
    let mut hits = found.iter().filter(|a| K::found(a)).count();
    if repeats > 0 {
        best = Duration::MAX;
    }
    for _ in 0..repeats {
        let t = Instant::now();
        hits = K::timed(s, context, queries);
        best = best.min(t.elapsed());
    }
    let row = Row::measured(name, s, build_ms, queries.len(), hits, counters, best);
    (row, found)
}

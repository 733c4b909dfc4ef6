//! Box overlap queries: every structure lists exactly the primitives brute force lists.

use crate::{Doing, Probe};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Accel, BruteForce, Counters, OverlapQuery, Primitive, Rng};
use std::fmt;

/// A disagreement between a structure and brute force on one box query.
#[derive(Clone, Debug)]
pub struct BoxMismatch {
    /// The query box.
    pub bounds: Aabb,
    /// What brute force answered (ascending ids).
    pub expected: Vec<u32>,
    /// What the structure answered.
    pub got: Vec<u32>,
    /// Which of the queries disagreed, when it is not `overlapping` itself (else empty).
    pub detail: Box<str>,
}

impl fmt::Display for BoxMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let missing: Vec<u32> = self
            .expected
            .iter()
            .filter(|id| !self.got.contains(id))
            .copied()
            .collect();
        let extra: Vec<u32> = self
            .got
            .iter()
            .filter(|id| !self.expected.contains(id))
            .copied()
            .collect();
        write!(
            f,
            "overlapping disagrees with brute force\n  query: overlapping(&{})\n  expected: {} primitives, got {}; missing {missing:?}, extra {extra:?}",
            aabb_rust(&self.bounds),
            self.expected.len(),
            self.got.len(),
        )?;
        if !self.detail.is_empty() {
            write!(f, "\n  {}", self.detail)?;
        }
        Ok(())
    }
}

/// The box as Rust source that builds it, every float printed to parse back to its bits.
fn aabb_rust(b: &Aabb) -> String {
    let v = |p: Vec3| format!("Vec3::new({:?}, {:?}, {:?})", p.x, p.y, p.z);
    format!("Aabb::new({}, {})", v(b.min), v(b.max))
}

/// Compares `accel`'s box queries with `reference`'s for every box: the primitives listed by
/// [`Accel::overlapping`] (ascending, each once), the same list when counted
/// ([`Accel::overlapping_with`]), [`Accel::overlaps_any`] (true exactly when the list is not
/// empty), and a query that stops at its first find ([`OverlapQuery::first`]), which must
/// report one primitive of the list and test no more primitives than the whole query.
///
/// # Errors
/// The first [`BoxMismatch`].
pub fn compare_boxes<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    boxes: &[Aabb],
) -> Result<(), BoxMismatch> {
    compare_boxes_probed(accel, reference, boxes, &Probe::default()).map(drop)
}

pub(crate) fn compare_boxes_probed<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    boxes: &[Aabb],
    probe: &Probe,
) -> Result<Vec<Vec<u32>>, BoxMismatch> {
    let mut answers = Vec::with_capacity(boxes.len());
    for b in boxes {
        probe.set(Doing::Box(*b));
        let expected = reference.overlapping(b);
        let got = accel.overlapping(b);
        let mismatch = |expected: &[u32], got: &[u32], detail: &str| BoxMismatch {
            bounds: *b,
            expected: expected.to_vec(),
            got: got.to_vec(),
            detail: detail.into(),
        };
        if got != expected {
            return Err(mismatch(&expected, &got, ""));
        }
        let mut all = Counters::default();
        let counted = accel.overlapping_with(b, &mut all);
        if counted != got {
            return Err(mismatch(
                &got,
                &counted,
                "overlapping_with(Counters) answers differently from overlapping",
            ));
        }
        if accel.overlaps_any(b) == expected.is_empty() {
            return Err(mismatch(
                &expected,
                &got,
                &format!(
                    "overlaps_any is {}, but the box meets {} primitives",
                    !expected.is_empty(),
                    expected.len()
                ),
            ));
        }
        let mut first = OverlapQuery::first(*b);
        let mut stopped = Counters::default();
        accel.box_query(&mut first, &mut stopped);
        let found = first.into_ids();
        if found.len() > 1 || found.iter().any(|id| !expected.contains(id)) {
            return Err(mismatch(
                &expected,
                &found,
                "a query that stops at its first find (OverlapQuery::first) must report one \
                 primitive of the list, and be offered nothing after it stopped",
            ));
        }
        if stopped.prim_tests > all.prim_tests {
            return Err(mismatch(
                &expected,
                &got,
                &format!(
                    "a query that stops at its first find made {} primitive tests, more than \
                     the {} of the whole query: the walk went on after it stopped",
                    stopped.prim_tests, all.prim_tests
                ),
            ));
        }
        answers.push(got);
    }
    Ok(answers)
}

/// Box queries probing `prims` as the kit runs them, drawn from the scene so a fixed scene needs
/// no boxes of its own. For 16 primitives spread over the scene (all, if there are fewer): its
/// bounding box (which touches it), that box flattened onto each of its faces (a box of zero
/// thickness on a vertex's plane), its bounding box's corners as boxes of zero size, and boxes
/// of three sizes around its centroid. Then 16 boxes at random in and around the scene box, the
/// scene box itself, one beside it, one unbounded box, and boxes that meet nothing: empty
/// (`min > max`), NaN.
pub fn scene_boxes<P: Primitive>(prims: &[P], seed: u64) -> Vec<Aabb> {
    let bounds = BruteForce::build(prims, &()).bounds();
    let size = if bounds.is_empty() {
        1.0
    } else {
        bounds.extent().max_element().max(f32::MIN_POSITIVE)
    };
    let mut boxes = Vec::new();
    // PERF: 16 primitives spread over the scene and 16 random boxes add 11 s to the five
    // structures' test suites (`cargo test -p <crate> --test suite`, test profile); the first 64
    // primitives and 48 random boxes added 30 s.
    let valid: Vec<&P> = prims.iter().filter(|p| p.is_valid()).collect();
    let step = valid.len().div_ceil(16).max(1);
    for prim in valid.into_iter().step_by(step) {
        let pb = prim.bounds();
        boxes.push(pb);
        for axis in 0..3 {
            for at in [pb.min[axis], pb.max[axis]] {
                let mut flat = pb;
                flat.min[axis] = at;
                flat.max[axis] = at;
                boxes.push(flat);
            }
        }
        boxes.push(Aabb::new(pb.min, pb.min));
        boxes.push(Aabb::new(pb.max, pb.max));
        let c = prim.centroid();
        for r in [1e-3, 0.05, 0.3] {
            let h = Vec3::splat(size * r);
            boxes.push(Aabb::new(c - h, c + h));
        }
    }
    let mut rng = Rng::new(seed);
    if !bounds.is_empty() {
        let grow = bounds.extent() * 0.25;
        let (lo, hi) = (bounds.min - grow, bounds.max + grow);
        for _ in 0..16 {
            let (p, q) = (rng.in_box(lo, hi), rng.in_box(lo, hi));
            boxes.push(Aabb::new(p.min(q), p.max(q)));
        }
        boxes.push(bounds);
        let beside = Vec3::splat(size * 2.0);
        boxes.push(Aabb::new(bounds.max + beside, bounds.max + beside * 2.0));
    }
    boxes.push(Aabb::new(Vec3::NEG_INFINITY, Vec3::INFINITY));
    boxes.push(Aabb::new(Vec3::ONE, Vec3::ZERO));
    boxes.push(Aabb::new(Vec3::splat(f32::NAN), Vec3::ONE));
    boxes
}

//! Inside, outside and signed distance: every structure's signed distance and crossing parity
//! answer as brute force's, and the fast winding number keeps its stated tolerance.

use crate::{Doing, Probe};
use rt_core::{Accel, BruteForce, PointHit, Ray, glam::Vec3};
use rt_sdf::{SignedDistance, SignedPoint, WindingTree, winding_number_exact};
use std::fmt;

/// A disagreement on one point's signed distance, winding number or crossing parity.
#[derive(Clone, Debug)]
pub struct InsideMismatch {
    /// Which query disagreed, as a call.
    pub query: &'static str,
    /// The query point.
    pub point: Vec3,
    /// The query's maximum distance.
    pub max_distance: f32,
    /// What was expected, as text.
    pub expected: Box<str>,
    /// What the structure (or the tree) answered, as text.
    pub got: Box<str>,
}

impl fmt::Display for InsideMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.point;
        write!(
            f,
            "{} disagrees with brute force\n  point: Vec3::new({:?}, {:?}, {:?}), maximum distance {:?}\n  expected: {}\n  got:      {}",
            self.query, p.x, p.y, p.z, self.max_distance, self.expected, self.got
        )
    }
}

/// The most points of one case whose sign the kit checks: each costs an exact winding number
/// over every triangle.
pub(crate) const INSIDE_POINTS: usize = 64;

/// How close to ½ an exact winding number may be and leave the sign open: rounding in the
/// sums, several orders of magnitude above it, far below any winding number a point off the
/// surface has.
pub const SIGN_MARGIN: f64 = 1e-6;

/// The tolerance the kit asks of [`WindingTree::winding_number`].
const TOLERANCE: f64 = 0.01;

/// Compares `accel`'s [`signed_distance`](SignedDistance::signed_distance) and
/// [`inside_by_parity`](SignedDistance::inside_by_parity) with brute force's for every `(point, maximum
/// distance)`, and the fast winding number with the exact one:
/// - the signed distance's closest point agrees with brute force's ([`PointHit::agree`]), its
///   sign is the exact winding number's (above ½ is inside) wherever that is more than
///   [`SIGN_MARGIN`] from ½, and its distance is the closest point's, negated inside;
/// - [`WindingTree::winding_number`] with tolerance 0.01 is within its reported bound (and the
///   bound within the tolerance) of [`winding_number_exact`];
/// - crossing parity is brute force's, whose crossings are the primitives tested one by one.
///
/// Scenes with a primitive that is not a triangle (spheres) check parity only: the winding
/// number is defined for triangles.
///
/// # Errors
/// The first [`InsideMismatch`].
pub fn compare_inside<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    prims: &[A::Prim],
    points: &[(Vec3, f32)],
) -> Result<(), InsideMismatch> {
    let tree = WindingTree::build(prims).ok();
    compare_inside_probed(
        accel,
        reference,
        prims,
        tree.as_ref(),
        points,
        &Probe::default(),
    )
    .map(drop)
}

pub(crate) fn compare_inside_probed<A: Accel>(
    accel: &A,
    reference: &BruteForce<A::Prim>,
    prims: &[A::Prim],
    tree: Option<&WindingTree>,
    points: &[(Vec3, f32)],
    probe: &Probe,
) -> Result<Vec<Option<SignedPoint>>, InsideMismatch> {
    let mut answers = Vec::with_capacity(points.len());
    for &(point, max_distance) in points {
        probe.set(Doing::Inside(point, max_distance));
        let mismatch = |query, expected: String, got: String| InsideMismatch {
            query,
            point,
            max_distance,
            expected: expected.into(),
            got: got.into(),
        };
        let (expected, got) = (
            reference.inside_by_parity(point),
            accel.inside_by_parity(point),
        );
        if expected != got {
            return Err(mismatch(
                "inside_by_parity",
                expected.to_string(),
                got.to_string(),
            ));
        }
        let Some(tree) = tree else {
            answers.push(None);
            continue;
        };
        let exact = winding_number_exact(prims, point).unwrap_or(f64::NAN);
        let fast = tree.winding_number(point, TOLERANCE);
        let kept =
            (fast.value - exact).abs() <= fast.error_bound + 1e-9 && fast.error_bound <= TOLERANCE;
        if exact.is_finite() && !kept {
            return Err(mismatch(
                "WindingTree::winding_number(point, 0.01)",
                format!("{exact} (the exact sum), within the reported bound, itself at most 0.01"),
                format!("{fast:?}"),
            ));
        }
        let near = reference.closest_point(point, max_distance);
        let signed = accel.signed_distance(tree, point, max_distance);
        let described = |s: Option<SignedPoint>| {
            s.map_or("None".to_string(), |s| {
                format!("{:?}, inside {}, signed {:?}", s.near, s.inside, s.distance)
            })
        };
        let expected_text = || {
            format!(
                "{:?}, inside {} (exact winding number {exact})",
                near,
                exact > 0.5
            )
        };
        if !PointHit::agree(near, signed.map(|s| s.near)) {
            return Err(mismatch(
                "signed_distance",
                expected_text(),
                described(signed),
            ));
        }
        if let Some(s) = signed {
            let decided = (exact - 0.5).abs() > SIGN_MARGIN;
            let distance = if s.inside {
                -s.near.distance
            } else {
                s.near.distance
            };
            let finite = point.is_finite() && point.abs().max_element() <= Ray::MAX_ORIGIN;
            if (finite && decided && s.inside != (exact > 0.5))
                || distance.to_bits() != s.distance.to_bits()
            {
                return Err(mismatch(
                    "signed_distance",
                    expected_text(),
                    described(signed),
                ));
            }
        }
        answers.push(signed);
    }
    Ok(answers)
}

/// The points of `points` the kit checks the sign of: at most [`INSIDE_POINTS`], spread evenly.
pub(crate) fn some_points(points: &[(Vec3, f32)]) -> Vec<(Vec3, f32)> {
    let stride = points.len().div_ceil(INSIDE_POINTS).max(1);
    points.iter().step_by(stride).copied().collect()
}

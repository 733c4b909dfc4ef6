//! The surface area heuristic's prediction of what a ray costs in a built structure.
//!
//! For lines spread uniformly over all positions and directions (Crofton's formula, the
//! assumption behind the SAH of Goldsmith & Salmon and MacDonald & Booth), the chance that a
//! line meeting a convex box `B` also meets a convex region `R` inside it is
//! `area(R) / area(B)`. Summed over a structure's nodes or cells that gives the expected number
//! of regions a ray enters, and, weighted by each leaf's primitive count, the expected number of
//! primitive tests, for any structure that describes itself ([`Accel::regions`]): the cost its
//! builder's model assumes. Real rays differ (they start inside the scene or at a camera, they
//! stop at the first hit, mailboxes skip repeats), which is what comparing the prediction with
//! the measured counts shows.
//!
//! [`Accel::regions`]: crate::Accel::regions

use crate::{Aabb, Region};

/// Expected regions entered and primitives tested by a line that meets the structure's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PredictedCost {
    /// Nodes or cells entered, the root included.
    pub visits: f64,
    /// Primitive tests, without mailboxing.
    pub tests: f64,
}

/// The SAH's expected cost per line through the box of the depth-0 regions (the root, or a
/// grid's top cells), or `None` when there are no regions or that box has no area.
///
/// ```
/// use rt_core::{Aabb, Region, predicted_cost, glam::Vec3};
/// let root = Aabb::new(Vec3::ZERO, Vec3::ONE);
/// let half = Aabb::new(Vec3::ZERO, Vec3::new(0.5, 1.0, 1.0));
/// let regions = [
///     Region { bounds: root, depth: 0, prims: None, split: Some((0, 0.5)) },
///     Region { bounds: half, depth: 1, prims: Some(4), split: None },
/// ];
/// let cost = predicted_cost(&regions).unwrap();
/// // The half box has 4/6 of the cube's area: entered with probability 2/3.
/// assert!((cost.visits - (1.0 + 2.0 / 3.0)).abs() < 1e-9);
/// assert!((cost.tests - 4.0 * 2.0 / 3.0).abs() < 1e-9);
/// ```
pub fn predicted_cost(regions: &[Region]) -> Option<PredictedCost> {
    let root = regions
        .iter()
        .filter(|r| r.depth == 0)
        .fold(Aabb::EMPTY, |b, r| b.union(r.bounds));
    let root_area = root.surface_area() as f64;
    if regions.is_empty() || !(root_area > 0.0 && root_area.is_finite()) {
        return None;
    }
    let mut cost = PredictedCost {
        visits: 0.0,
        tests: 0.0,
    };
    for r in regions {
        let p = (r.bounds.surface_area() as f64 / root_area).clamp(0.0, 1.0);
        cost.visits += p;
        cost.tests += p * r.prims.unwrap_or(0) as f64;
    }
    Some(cost)
}

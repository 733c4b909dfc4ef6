//! What a shootout measured: a [`Report`] per scene, with a [`Row`] per structure and every
//! disagreement with brute force. `compare` fills them; the Markdown report, the grade and the
//! JSON read them.

use crate::compare::points;
use rt_core::{Aabb, DynAccel, Hit, PredictedCost, Ray, Triangle, predicted_cost};

/// One row of the report.
#[derive(Debug)]
pub struct Row {
    pub name: String,
    pub build_ms: f64,
    pub memory_bytes: usize,
    pub nodes: usize,
    pub leaves: usize,
    pub empty_leaves: usize,
    pub max_depth: usize,
    pub avg_leaf_prims: f64,
    pub prim_refs: usize,
    pub duplication: f64,
    pub rays_traced: usize,
    pub hits: usize,
    pub mismatches: usize,
    pub avg_visits: f64,
    pub avg_prim_tests: f64,
    /// Primitive tests a mailbox skipped, per ray (0 for structures without one).
    pub avg_mailbox_skips: f64,
    /// The structure's own named figures ([`BuildStats::extra`](rt_core::BuildStats::extra)).
    pub extra: Vec<(&'static str, f64)>,
    pub mrays_per_s: f64,
    pub speedup: f64,
    /// The SAH's expected visits and tests per traced ray (see [`predicted_per_ray`]), for
    /// structures that describe their regions.
    pub predicted: Option<PredictedCost>,
    /// Every ray's answer (kept only when the report prints them, with `--rays-file`).
    pub(crate) answers: Vec<Option<Hit>>,
}

/// The cost the surface area heuristic predicts per traced ray: its expectation for a line
/// through the structure's box ([`predicted_cost`]), times the share of `rays` that enter the
/// scene box (`bounds`), so that it compares with the measured averages over all rays.
pub fn predicted_per_ray(
    s: &dyn DynAccel<Triangle>,
    rays: &[Ray],
    bounds: &Aabb,
) -> Option<PredictedCost> {
    let per_line = predicted_cost(&s.regions_dyn())?;
    let entering = rays
        .iter()
        .filter(|r| bounds.intersect(r, r.t_max).is_some())
        .count() as f64
        / rays.len().max(1) as f64;
    Some(PredictedCost {
        visits: per_line.visits * entering,
        tests: per_line.tests * entering,
    })
}

/// A ray on which a structure disagreed with brute force.
#[derive(Debug)]
pub struct Disagreement {
    pub structure: String,
    pub ray_index: usize,
    pub ray: Ray,
    pub expected: Option<Hit>,
    pub got: Option<Hit>,
}

/// Everything `compare` measured.
#[derive(Debug)]
pub struct Report {
    pub scene: String,
    pub triangles: usize,
    pub valid_triangles: usize,
    pub ray_kind: &'static str,
    pub rays: usize,
    pub threads: usize,
    pub checked_rays: usize,
    pub rows: Vec<Row>,
    pub disagreements: Vec<Disagreement>,
    /// Closest-point queries on which a row disagreed with brute force (the first few).
    pub point_disagreements: Vec<points::PointDisagreement>,
    pub per_ray_answers: bool,
}

impl Report {
    /// Mismatches over every row.
    pub fn total_mismatches(&self) -> usize {
        self.rows.iter().map(|r| r.mismatches).sum()
    }

    /// The share of the rays that hit the scene (any-hit rays: that are occluded), from the first
    /// row that traced them all (brute force traces only the checked ones); `None` for
    /// closest-point queries or when no row traced. A view where most rays miss times little but
    /// the call, so the share belongs beside every speed.
    pub fn hit_share(&self) -> Option<f64> {
        if self.ray_kind == points::KIND {
            return None;
        }
        self.rows
            .iter()
            .find(|row| row.rays_traced == self.rays && row.rays_traced > 0)
            .map(|row| row.hits as f64 / row.rays_traced as f64)
    }
}

/// Three significant digits, so that brute force's 0.000823 and a BVH's 25.5 both read well in
/// a table; `-` for a figure that is not a number.
pub fn three_digits(x: f64) -> String {
    if !x.is_finite() {
        "-".into()
    } else if x.abs() >= 100.0 || x == 0.0 {
        format!("{x:.0}")
    } else {
        let decimals = (2 - x.abs().log10().floor() as i32).clamp(0, 8) as usize;
        format!("{x:.decimals$}")
    }
}

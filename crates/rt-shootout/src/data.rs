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
    /// Every ray's answer, in ray order (see [`Row::answers`]; the JSON report lists them with
    /// `--rays-file`).
    pub(crate) answers: Vec<Option<Hit>>,
    /// The same rays traced as bundles (`compare --bundle`).
    pub bundle: Option<BundleRow>,
    /// The same rays traced as streams (`compare --stream`), in the same form.
    pub stream: Option<BundleRow>,
}

impl Row {
    /// Every ray's answer, in the order of the report's rays; an any-hit answer is `Some` when
    /// the ray is occluded.
    pub fn answers(&self) -> &[Option<Hit>] {
        &self.answers
    }
}

/// A row's rays traced as bundles ([`rt_core::Accel::intersect_bundle`]), beside its single rays.
#[derive(Clone, Debug, PartialEq)]
pub struct BundleRow {
    /// Speed of the bundle pass.
    pub mrays_per_s: f64,
    /// The bundle pass's speed over the same row's single rays, measured in the same run.
    pub over_single: f64,
    /// Nodes or cells entered per ray: a bundle's step counts once for all its lanes.
    pub avg_visits: f64,
    /// Primitive tests per ray.
    pub avg_prim_tests: f64,
    /// The share of a bundle's lanes active at its steps (`None`: the row traced no bundle).
    pub lane_utilisation: Option<f64>,
    /// The share of rays the row traced singly (rays a bundle cannot carry, bundles of one).
    pub single_share: f64,
    /// Rays whose bundle answer differs from the single answer in any bit.
    pub differences: usize,
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
    /// The view primary and shadow rays come from (`filled` or `sparse`); empty for other rays.
    pub view: &'static str,
    pub rays: usize,
    pub threads: usize,
    pub checked_rays: usize,
    pub rows: Vec<Row>,
    pub disagreements: Vec<Disagreement>,
    /// Closest-point or box queries on which a row disagreed with brute force (the first few).
    pub query_disagreements: Vec<points::QueryDisagreement>,
    pub per_ray_answers: bool,
    /// A sentence the table prints under its header, such as what the rows share beyond their
    /// structures (empty if none).
    pub note: String,
}

impl Report {
    /// Mismatches over every row, and bundle answers that differ from the single ones.
    pub fn total_mismatches(&self) -> usize {
        self.rows
            .iter()
            .map(|r| {
                let differences = |b: &Option<BundleRow>| b.as_ref().map_or(0, |b| b.differences);
                r.mismatches + differences(&r.bundle) + differences(&r.stream)
            })
            .sum()
    }

    /// The share of the rays that hit the scene (any-hit rays: that are occluded; box queries:
    /// that meet a primitive; signed distance: points inside), from the first row that traced them all (brute force traces only
    /// the checked ones); `None` for closest-point queries or when no row traced. A view where most rays miss times
    /// little but the call, so the share belongs beside every speed.
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

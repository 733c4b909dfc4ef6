//! Step 5: the any-hit query, for shadow rays.
//!
//! A shadow ray only asks whether anything lies in `[t_min, t_max]`: the first hit found in
//! any cell answers it, so no ordering rule is needed and the walk stops at once.

use crate::{LabGrid, step1, step3, step4, step6};
use rt_core::{Hit, Ray, Stats};

/// Whether anything is hit in the ray's interval; stops at the first hit found.
pub fn any_hit<S: Stats>(grid: &LabGrid, ray: &Ray, stats: &mut S) -> bool {
    todo!("step 5: the any-hit walk")
}

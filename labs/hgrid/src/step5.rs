//! Step 5: the any-hit query.
//!
//! A shadow ray only asks whether anything blocks it: the first triangle found that does
//! ([`Primitive::occludes`] within the ray's whole interval) ends the walk, whichever cell it
//! lies in and wherever along the ray. The walk of step 3 is all you need: a limit of
//! `f32::NEG_INFINITY` ends it. Invalid rays return `false` (the walk visits nothing for them).

use crate::{LabHGrid, step3};
use rt_core::{Primitive, Ray, Stats};

/// Whether any triangle is hit within the ray's interval.
pub fn any_hit<S: Stats>(lab: &LabHGrid, ray: &Ray, stats: &mut S) -> bool {
    todo!("step 5: the any hit")
}

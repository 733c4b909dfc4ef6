//! `cargo xtask compare`: the structure shootout.
//!
//! Builds every selected structure on one scene, traces the same rays through each, and checks
//! every answer: against brute force on a random subset of the rays (all of them when there are
//! few), and against each other on all rays, with brute force settling every ray on which the
//! structures disagree. Reports build time, memory, tree shape, traversal cost per ray and
//! speed, with brute force as the baseline row.

mod args;
mod output;
pub(crate) mod points;
mod run;

pub use crate::data::{Disagreement, Report, Row, predicted_per_ray};
pub use crate::scene::load_scene;
pub use args::{Args, QueryKind, RayKind, ViewKind, after_help};
pub use output::to_table;
pub use points::alpha_mask;
pub use run::run;
pub(crate) use run::{Source, build_fastest, checked_subset};

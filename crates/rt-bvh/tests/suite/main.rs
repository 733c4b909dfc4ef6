//! rt-bvh's integration tests, one module per topic, built as one test binary: every file
//! directly under `tests/` would be a crate of its own that compiles the structures' generic
//! traversals again, which made most of the workspace's test build time.

mod bundles;
mod conformance;
mod degenerate;
mod instances;
mod kernels;
mod order;
mod overlap;
mod parallel;
mod refit;
mod reinsertion;
mod saved;

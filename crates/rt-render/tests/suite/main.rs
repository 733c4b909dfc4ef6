//! rt-render's integration tests, one module per topic, built as one test binary: every file
//! directly under `tests/` would be a crate of its own that compiles the structures' generic
//! traversals again, which made most of the workspace's test build time.

mod acne;
mod path;
mod pictures;

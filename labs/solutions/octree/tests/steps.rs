//! The template's step tests, run against the reference solution (whose library has the
//! template's name, `lab_octree`).

#[path = "../../../octree/tests/steps.rs"]
mod steps;

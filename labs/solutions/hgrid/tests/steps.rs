//! The template's step tests, run against the reference solution (whose library has the
//! template's name, `lab_hgrid`).

#[path = "../../../hgrid/tests/steps.rs"]
mod steps;

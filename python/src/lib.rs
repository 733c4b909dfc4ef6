//! The compiled half of the `rt_accel` Python package: a scene of triangle meshes over one
//! rt-accel structure, and its queries over flat, contiguous arrays.
//!
//! The Python half (`rt_accel/__init__.py`) takes any array the user has (any leading shape,
//! float64, strided), checks its shape and hands this module contiguous `float32` rows; this
//! module checks every value, releases the GIL and answers on a rayon pool. Nothing here
//! panics on bad input: every check returns a `ValueError` naming the element.

mod mesh;
mod params;
mod queries;
mod saved;
mod scene;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::NativeScene>()?;
    m.add_function(wrap_pyfunction!(scene::presets, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::load_mesh, m)?)?;
    m.add("INVALID_ID", u32::MAX)?;
    Ok(())
}

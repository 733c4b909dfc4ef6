//! `load_mesh`: OBJ, PLY and glTF files through rt-scene, as numpy arrays.

use numpy::PyArray2;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use rt_scene::LoadErrorKind;
use std::path::PathBuf;

/// Vertex positions and triangle indices.
type Mesh<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<u32>>);

/// The vertex positions `(n, 3)` float32 and triangle indices `(m, 3)` uint32 of the mesh in
/// `path`; a file that cannot be read or parsed is an exception naming the file (and the line).
#[pyfunction]
pub(crate) fn load_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Mesh<'py>> {
    let mesh = py.detach(|| rt_scene::load_mesh(&path)).map_err(|e| {
        let message = e.to_string();
        match &e.kind {
            LoadErrorKind::Io(_) if !e.path.exists() => PyFileNotFoundError::new_err(message),
            LoadErrorKind::Io(_) => PyOSError::new_err(message),
            _ => PyValueError::new_err(message),
        }
    })?;
    let positions: Vec<f32> = mesh.positions().iter().flat_map(|p| p.to_array()).collect();
    let indices: Vec<u32> = mesh.indices().iter().flatten().copied().collect();
    let (n, m) = (mesh.positions().len(), mesh.indices().len());
    Ok((
        PyArray1::from_vec(py, positions).reshape([n, 3])?,
        PyArray1::from_vec(py, indices).reshape([m, 3])?,
    ))
}

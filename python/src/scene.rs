//! `NativeScene`: the triangles of every mesh added, and the structure built over them on the
//! first query.

use crate::params::{self, Value};
use crate::{queries, saved};
use numpy::{PyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use rt_bvh::{Bvh, BvhParams};
use rt_core::glam::Vec3;
use rt_core::{Accel, BruteForce, Triangle};
use rt_grid::{Grid, GridParams};
use rt_hgrid::{HGrid, HGridParams};
use rt_kdtree::{KdParams, KdTree};
use rt_octree::{Octree, OctreeParams};
use rt_sdf::WindingTree;
use std::sync::OnceLock;

/// A one-dimensional numpy array owned by Python.
type Array<'py, T> = Bound<'py, PyArray1<T>>;

/// `cast_rays`: `t`, geometry ids, primitive ids, `uv` (flat), normals (flat).
type Hits<'py> = (
    Array<'py, f32>,
    Array<'py, u32>,
    Array<'py, u32>,
    Array<'py, f32>,
    Array<'py, f32>,
);
/// `list_intersections`: splits, ray ids, `t`, geometry ids, primitive ids, `uv` (flat).
type Listed<'py> = (
    Array<'py, u32>,
    Array<'py, u32>,
    Array<'py, f32>,
    Array<'py, u32>,
    Array<'py, u32>,
    Array<'py, f32>,
);
/// `closest_points`: points (flat), geometry ids, primitive ids, `uv` (flat), normals (flat),
/// distances, and whether each point is inside when asked.
type Nearest<'py> = (
    Array<'py, f32>,
    Array<'py, u32>,
    Array<'py, u32>,
    Array<'py, f32>,
    Array<'py, f32>,
    Array<'py, f32>,
    Option<Array<'py, bool>>,
);

/// The structures by the names the package takes.
const STRUCTURES: [&str; 6] = ["bvh", "kdtree", "grid", "hgrid", "octree", "brute"];

/// A structure's build parameters, chosen by name.
#[derive(Debug)]
enum Params {
    Bvh(BvhParams),
    KdTree(KdParams),
    Grid(GridParams),
    HGrid(HGridParams),
    Octree(OctreeParams),
    Brute,
}

/// A built structure over the scene's triangles.
#[derive(Debug)]
pub(crate) enum Structure {
    Bvh(Bvh<Triangle>),
    KdTree(KdTree<Triangle>),
    Grid(Grid<Triangle>),
    HGrid(HGrid<Triangle>),
    Octree(Octree<Triangle>),
    Brute(BruteForce<Triangle>),
}

/// Runs `$body` with `$a` bound to the structure inside `$s`, compiled once per structure, so
/// the query loops dispatch once per call and not once per ray.
macro_rules! with_structure {
    ($s:expr, $a:ident => $body:expr) => {
        match $s {
            Structure::Bvh($a) => $body,
            Structure::KdTree($a) => $body,
            Structure::Grid($a) => $body,
            Structure::HGrid($a) => $body,
            Structure::Octree($a) => $body,
            Structure::Brute($a) => $body,
        }
    };
}
pub(crate) use with_structure;

/// The names of `A`'s presets, the first its default.
fn preset_names<A: Accel>() -> Vec<&'static str> {
    A::presets().into_iter().map(|(name, _)| name).collect()
}

/// `A`'s preset called `name`, or its first (the crate's default) for `None`, with its name.
fn find_preset<A: Accel>(
    structure: &str,
    name: Option<&str>,
) -> PyResult<(&'static str, A::Params)> {
    let mut presets = A::presets().into_iter();
    let found = match name {
        None => presets.next(),
        Some(name) => presets.find(|(p, _)| *p == name),
    };
    found.ok_or_else(|| {
        PyValueError::new_err(format!(
            "unknown preset {:?} for structure {structure:?}: one of {}",
            name.unwrap_or(""),
            preset_names::<A>().join(", ")
        ))
    })
}

/// The presets of `structure`, the first its default.
#[pyfunction]
pub(crate) fn presets(structure: &str) -> PyResult<Vec<&'static str>> {
    Ok(match structure {
        "bvh" => preset_names::<Bvh<Triangle>>(),
        "kdtree" => preset_names::<KdTree<Triangle>>(),
        "grid" => preset_names::<Grid<Triangle>>(),
        "hgrid" => preset_names::<HGrid<Triangle>>(),
        "octree" => preset_names::<Octree<Triangle>>(),
        "brute" => preset_names::<BruteForce<Triangle>>(),
        _ => return Err(unknown_structure(structure)),
    })
}

/// A preset's name, and its parameters as [`Params`].
fn with_params<T>(
    (name, params): (&'static str, T),
    wrap: fn(T) -> Params,
) -> (&'static str, Params) {
    (name, wrap(params))
}

fn unknown_structure(structure: &str) -> PyErr {
    PyValueError::new_err(format!(
        "unknown structure {structure:?}: one of {}",
        STRUCTURES.join(", ")
    ))
}

/// What the first query builds: the structure, and the winding-number tree of the signs.
#[derive(Debug)]
pub(crate) struct Built {
    pub structure: Structure,
    /// Built on the first query that needs a sign.
    pub winding: OnceLock<WindingTree>,
    /// The triangles' unit normals, then a zero normal for a miss: made on the first
    /// `cast_rays` ([`queries::normals`]).
    pub normals: OnceLock<Vec<[f32; 3]>>,
}

/// The scene: every mesh added, concatenated, and the structure over them.
#[pyclass(module = "rt_accel._native")]
#[derive(Debug)]
pub(crate) struct NativeScene {
    params: Params,
    structure: String,
    preset: String,
    /// The parameters given by keyword, by name, applied over the preset's.
    overrides: Vec<(String, Value)>,
    pub tris: Vec<Triangle>,
    /// The index in `tris` of each geometry's first triangle.
    pub offsets: Vec<u32>,
    built: OnceLock<Built>,
}

#[pymethods]
impl NativeScene {
    #[new]
    #[pyo3(signature = (structure, preset=None, params=None))]
    fn new(
        structure: &str,
        preset: Option<&str>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let mut overrides = Vec::new();
        for (key, value) in params.into_iter().flat_map(|d| d.iter()) {
            let key: String = key.extract()?;
            let value = Value::of(&key, &value)?;
            overrides.push((key, value));
        }
        Self::create(structure, preset, overrides)
    }

    /// Adds a mesh: `vertices` `(n, 3)` float32, `triangles` `(m, 3)` uint32, both C-contiguous.
    /// Returns its geometry id.
    fn add_triangles(
        &mut self,
        vertices: PyReadonlyArray2<'_, f32>,
        triangles: PyReadonlyArray2<'_, u32>,
    ) -> PyResult<u32> {
        let (vs, ts) = (contiguous(&vertices)?, contiguous(&triangles)?);
        if vertices.shape()[1] != 3 || triangles.shape()[1] != 3 {
            return Err(PyValueError::new_err(
                "vertex_positions must have shape (n, 3) and triangle_indices (m, 3)",
            ));
        }
        let n = vs.len() / 3;
        if ts.is_empty() {
            return Err(PyValueError::new_err(
                "the mesh has no triangles: triangle_indices has shape (0, 3)",
            ));
        }
        let total = self.tris.len() + ts.len() / 3;
        if total >= u32::MAX as usize {
            return Err(PyValueError::new_err(format!(
                "a scene holds fewer than 2**32 - 1 triangles; this mesh would bring it to {total}"
            )));
        }
        let vertex = |i: usize| Vec3::new(vs[3 * i], vs[3 * i + 1], vs[3 * i + 2]);
        let mut tris = Vec::with_capacity(ts.len() / 3);
        for (k, t) in ts.chunks_exact(3).enumerate() {
            if let Some(&i) = t.iter().find(|&&i| i as usize >= n) {
                return Err(PyValueError::new_err(format!(
                    "triangle_indices[{k}] refers to vertex {i}, but there are {n} vertices"
                )));
            }
            for &i in t {
                if !vertex(i as usize).is_finite() {
                    return Err(PyValueError::new_err(format!(
                        "vertex_positions[{i}] (used by triangle {k}) has a non-finite coordinate: {:?}",
                        vertex(i as usize).to_array()
                    )));
                }
            }
            tris.push(Triangle::new(
                vertex(t[0] as usize),
                vertex(t[1] as usize),
                vertex(t[2] as usize),
            ));
        }
        let id = self.offsets.len() as u32;
        self.offsets.push(self.tris.len() as u32);
        self.tris.extend(tris);
        self.built = OnceLock::new();
        Ok(id)
    }

    /// The number of triangles over all geometries.
    fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// The number of geometries added.
    fn geometry_count(&self) -> usize {
        self.offsets.len()
    }

    /// Builds the structure now (queries build it when first needed).
    fn build(&self, py: Python<'_>) -> PyResult<()> {
        self.built(py).map(|_| ())
    }

    /// The scene as bytes (rt-persist's framing), its structure built first if need be.
    fn save<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let built = self.built(py)?;
        let bytes = py.detach(|| {
            saved::save(
                &self.structure,
                &self.preset,
                &self.overrides,
                &self.tris,
                &self.offsets,
                &built.structure,
            )
        });
        Ok(PyBytes::new(py, &bytes))
    }

    /// The scene saved in `bytes`, checked, with nothing rebuilt.
    #[staticmethod]
    fn load(py: Python<'_>, bytes: &[u8]) -> PyResult<Self> {
        let saved = py
            .detach(|| saved::load(bytes))
            .map_err(|e| PyValueError::new_err(format!("not a valid saved scene: {e}")))?;
        let mut scene = Self::create(&saved.structure, Some(&saved.preset), saved.overrides)
            .map_err(|e| PyValueError::new_err(format!("not a valid saved scene: {e}")))?;
        scene.tris = saved.tris;
        scene.offsets = saved.offsets;
        let built = Built {
            structure: saved.built,
            winding: OnceLock::new(),
            normals: OnceLock::new(),
        };
        scene.built = OnceLock::from(built);
        Ok(scene)
    }

    /// The structure's name, its preset, and the parameters given by keyword.
    fn describe<'py>(&self, py: Python<'py>) -> PyResult<(String, String, Bound<'py, PyDict>)> {
        let params = PyDict::new(py);
        for (key, value) in &self.overrides {
            params.set_item(key, value.to_object(py)?)?;
        }
        Ok((self.structure.clone(), self.preset.clone(), params))
    }

    /// Closest hits: `t`, geometry ids, primitive ids, `uv` (flat `(n, 2)`), unit normals
    /// (flat `(n, 3)`).
    #[pyo3(signature = (rays, shape, nthreads))]
    fn cast_rays<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        nthreads: usize,
    ) -> PyResult<Hits<'py>> {
        let out = self.run(py, &rays, nthreads, |built, flat| {
            let rays = queries::rays(flat, 0.0, f32::INFINITY, &shape)?;
            queries::cast(built, &self.tris, &self.offsets, &rays)
        })?;
        Ok((
            PyArray1::from_vec(py, out.t),
            PyArray1::from_vec(py, out.geometry),
            PyArray1::from_vec(py, out.primitive),
            PyArray1::from_vec(py, out.uv),
            PyArray1::from_vec(py, out.normal),
        ))
    }

    /// Every hit of every ray: splits, ray ids, `t`, geometry ids, primitive ids, `uv` (flat).
    #[pyo3(signature = (rays, shape, nthreads))]
    fn list_intersections<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        nthreads: usize,
    ) -> PyResult<Listed<'py>> {
        let out = self.run(py, &rays, nthreads, |built, flat| {
            let rays = queries::rays(flat, 0.0, f32::INFINITY, &shape)?;
            queries::list(built, &self.offsets, self.tris.len(), &rays)
        })?;
        Ok((
            PyArray1::from_vec(py, out.splits),
            PyArray1::from_vec(py, out.ray),
            PyArray1::from_vec(py, out.t),
            PyArray1::from_vec(py, out.geometry),
            PyArray1::from_vec(py, out.primitive),
            PyArray1::from_vec(py, out.uv),
        ))
    }

    /// The triangles meeting each box: splits, geometry ids, primitive ids.
    #[pyo3(signature = (boxes, shape, nthreads))]
    fn overlapping<'py>(
        &self,
        py: Python<'py>,
        boxes: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        nthreads: usize,
    ) -> PyResult<(Array<'py, u32>, Array<'py, u32>, Array<'py, u32>)> {
        let (splits, geometry, primitive) = self.run(py, &boxes, nthreads, |built, flat| {
            let boxes = queries::boxes(flat, &shape)?;
            queries::overlapping(built, &self.offsets, self.tris.len(), &boxes)
        })?;
        Ok((
            PyArray1::from_vec(py, splits),
            PyArray1::from_vec(py, geometry),
            PyArray1::from_vec(py, primitive),
        ))
    }

    /// Whether anything lies on each ray within `[tnear, tfar]`.
    #[pyo3(signature = (rays, shape, tnear, tfar, nthreads))]
    fn test_occlusions<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        tnear: f32,
        tfar: f32,
        nthreads: usize,
    ) -> PyResult<Array<'py, bool>> {
        if !(tnear >= 0.0 && tnear.is_finite() && tnear <= tfar) {
            return Err(PyValueError::new_err(format!(
                "tnear must be finite with 0 <= tnear <= tfar; got tnear={tnear}, tfar={tfar}"
            )));
        }
        let out = self.run(py, &rays, nthreads, |built, flat| {
            let rays = queries::rays(flat, tnear, tfar, &shape)?;
            Ok(queries::occluded(built, &rays))
        })?;
        Ok(PyArray1::from_vec(py, out))
    }

    /// The number of triangles each ray crosses.
    #[pyo3(signature = (rays, shape, nthreads))]
    fn count_intersections<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        nthreads: usize,
    ) -> PyResult<Array<'py, i32>> {
        let out = self.run(py, &rays, nthreads, |built, flat| {
            let rays = queries::rays(flat, 0.0, f32::INFINITY, &shape)?;
            Ok(queries::count(built, &rays))
        })?;
        Ok(PyArray1::from_vec(py, out))
    }

    /// Closest points: the points (flat `(n, 3)`), geometry ids, primitive ids, `uv` (flat
    /// `(n, 2)`), unit normals (flat `(n, 3)`), distances, and when `signed`, whether each query
    /// point is inside by the winding number.
    #[pyo3(signature = (points, shape, signed, nthreads))]
    fn closest_points<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        signed: bool,
        nthreads: usize,
    ) -> PyResult<Nearest<'py>> {
        let out = self.run(py, &points, nthreads, |built, flat| {
            let points = queries::points(flat, &shape)?;
            let winding = signed.then(|| self.winding(built));
            queries::closest(built, &self.tris, &self.offsets, &points, winding)
        })?;
        Ok((
            PyArray1::from_vec(py, out.point),
            PyArray1::from_vec(py, out.geometry),
            PyArray1::from_vec(py, out.primitive),
            PyArray1::from_vec(py, out.uv),
            PyArray1::from_vec(py, out.normal),
            PyArray1::from_vec(py, out.distance),
            out.inside.map(|inside| PyArray1::from_vec(py, inside)),
        ))
    }

    /// The generalised winding number of the scene's triangles at each point (float64), exact
    /// to within `1e-9` wherever its fast expansion is used.
    #[pyo3(signature = (points, shape, nthreads))]
    fn winding_number<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        nthreads: usize,
    ) -> PyResult<Array<'py, f64>> {
        let out = self.run(py, &points, nthreads, |built, flat| {
            let points = queries::points(flat, &shape)?;
            Ok(queries::winding(self.winding(built), &points))
        })?;
        Ok(PyArray1::from_vec(py, out))
    }

    /// Whether each point is inside by the winding number ([`WindingTree::is_inside`]).
    #[pyo3(signature = (points, shape, nthreads))]
    fn inside<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f32>,
        shape: Vec<usize>,
        nthreads: usize,
    ) -> PyResult<Array<'py, bool>> {
        let out = self.run(py, &points, nthreads, |built, flat| {
            let points = queries::points(flat, &shape)?;
            Ok(queries::inside(self.winding(built), &points))
        })?;
        Ok(PyArray1::from_vec(py, out))
    }
}

impl NativeScene {
    /// The scene of `structure` with `preset` (its default for `None`) and `overrides` set
    /// over it, in name order, each checked.
    pub(crate) fn create(
        structure: &str,
        preset: Option<&str>,
        mut overrides: Vec<(String, Value)>,
    ) -> PyResult<Self> {
        let (preset, mut params) = match structure {
            "bvh" => with_params(
                find_preset::<Bvh<Triangle>>(structure, preset)?,
                Params::Bvh,
            ),
            "kdtree" => with_params(
                find_preset::<KdTree<Triangle>>(structure, preset)?,
                Params::KdTree,
            ),
            "grid" => with_params(
                find_preset::<Grid<Triangle>>(structure, preset)?,
                Params::Grid,
            ),
            "hgrid" => with_params(
                find_preset::<HGrid<Triangle>>(structure, preset)?,
                Params::HGrid,
            ),
            "octree" => with_params(
                find_preset::<Octree<Triangle>>(structure, preset)?,
                Params::Octree,
            ),
            "brute" => with_params(
                find_preset::<BruteForce<Triangle>>(structure, preset)?,
                |()| Params::Brute,
            ),
            _ => return Err(unknown_structure(structure)),
        };
        overrides.sort_by(|a, b| a.0.cmp(&b.0));
        for (key, value) in &overrides {
            match &mut params {
                Params::Bvh(p) => params::set_bvh(p, key, value)?,
                Params::KdTree(p) => params::set_kdtree(p, key, value)?,
                Params::Grid(p) => params::set_grid(p, key, value)?,
                Params::HGrid(p) => params::set_hgrid(p, key, value)?,
                Params::Octree(p) => params::set_octree(p, key, value)?,
                Params::Brute => {
                    return Err(PyValueError::new_err(format!(
                        "unknown parameter {key:?}: brute force takes none"
                    )));
                }
            }
        }
        Ok(Self {
            params,
            structure: structure.to_owned(),
            preset: preset.to_owned(),
            overrides,
            tris: Vec::new(),
            offsets: Vec::new(),
            built: OnceLock::new(),
        })
    }

    /// Runs `query` on the built structure and the rows of `input` (in memory order), with the
    /// GIL released, on `nthreads` threads (every core for 0).
    fn run<'a, T: numpy::Element + Sync, R: Send>(
        &'a self,
        py: Python<'_>,
        input: &'a PyReadonlyArray2<'_, T>,
        nthreads: usize,
        query: impl FnOnce(&'a Built, &'a [T]) -> PyResult<R> + Send,
    ) -> PyResult<R> {
        let built = self.built(py)?;
        let flat = contiguous(input)?;
        py.detach(|| queries::pool(nthreads, || query(built, flat)))?
    }

    /// The structure, built now if it is not yet, with the GIL released.
    fn built(&self, py: Python<'_>) -> PyResult<&Built> {
        if self.tris.is_empty() {
            return Err(PyValueError::new_err(
                "the scene has no triangles: add a mesh with add_triangles first",
            ));
        }
        Ok(py.detach(|| self.built.get_or_init(|| self.build_structure())))
    }

    fn build_structure(&self) -> Built {
        let tris = &self.tris;
        let structure = match &self.params {
            Params::Bvh(p) => Structure::Bvh(Bvh::build(tris, p)),
            Params::KdTree(p) => Structure::KdTree(KdTree::build(tris, p)),
            Params::Grid(p) => Structure::Grid(Grid::build(tris, p)),
            Params::HGrid(p) => Structure::HGrid(HGrid::build(tris, p)),
            Params::Octree(p) => Structure::Octree(Octree::build(tris, p)),
            Params::Brute => Structure::Brute(BruteForce::build(tris, &())),
        };
        Built {
            structure,
            winding: OnceLock::new(),
            normals: OnceLock::new(),
        }
    }

    fn winding<'a>(&self, built: &'a Built) -> &'a WindingTree {
        built.winding.get_or_init(|| {
            WindingTree::build(&self.tris)
                .expect("a triangle is always a triangle to the winding tree")
        })
    }
}

/// The array's elements in memory order; the Python half makes every array C-contiguous.
fn contiguous<'a, T: numpy::Element>(array: &'a PyReadonlyArray2<'_, T>) -> PyResult<&'a [T]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err("internal: expected a C-contiguous array"))
}

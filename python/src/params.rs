//! Build parameters by keyword: `Scene("bvh", max_leaf_size=4)`. Each structure's parameters
//! with the values it takes, checked before they reach a builder: a value out of range is a
//! `ValueError` naming the parameter and its range, a value of the wrong kind a `TypeError`.
//!
//! The ranges are those the builders document (clamps included), bounded where a value could
//! only ask for absurd memory or time (cells, levels, depths), so no value from Python makes a
//! builder panic, loop or exhaust memory.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyString};
use rt_bvh::{BvhParams, Layout, SplitMethod};
use rt_grid::GridParams;
use rt_hgrid::HGridParams;
use rt_kdtree::{KdParams, Traversal};
use rt_octree::OctreeParams;

/// A parameter's value as given: a bool, an integer, a float, a word, or `None`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    None,
    Bool(bool),
    Int(i64),
    Float(f64),
    Word(String),
}

impl Value {
    /// The value of a Python object, for parameter `key`.
    pub(crate) fn of(key: &str, v: &Bound<'_, PyAny>) -> PyResult<Self> {
        // `bool` first: Python's bools are ints too.
        Ok(if v.is_none() {
            Self::None
        } else if v.is_instance_of::<PyBool>() {
            Self::Bool(v.extract()?)
        } else if v.is_instance_of::<PyInt>() {
            Self::Int(
                v.extract()
                    .map_err(|_| PyValueError::new_err(format!("{key}: {v} is out of range")))?,
            )
        } else if v.is_instance_of::<PyFloat>() {
            Self::Float(v.extract()?)
        } else if v.is_instance_of::<PyString>() {
            Self::Word(v.extract()?)
        } else {
            return Err(PyTypeError::new_err(format!(
                "{key}: expected a number, a bool or a name, not {}",
                v.get_type().name()?
            )));
        })
    }

    /// The value as one line of a saved scene, which [`Value::parse`] reads back.
    pub(crate) fn text(&self) -> String {
        match self {
            Self::None => "none".into(),
            Self::Bool(b) => b.to_string(),
            Self::Int(i) => i.to_string(),
            // `{:?}` prints the shortest text that parses back to the same bits.
            Self::Float(f) => format!("{f:?}"),
            Self::Word(w) => w.clone(),
        }
    }

    /// The value [`Value::text`] wrote.
    pub(crate) fn parse(text: &str) -> Self {
        match text {
            "none" => Self::None,
            "true" => Self::Bool(true),
            "false" => Self::Bool(false),
            _ => text
                .parse()
                .map(Self::Int)
                .or_else(|_| text.parse().map(Self::Float))
                .unwrap_or_else(|_| Self::Word(text.to_owned())),
        }
    }

    /// The value as Python prints it, for messages.
    fn repr(&self) -> String {
        match self {
            Self::None => "None".into(),
            Self::Bool(true) => "True".into(),
            Self::Bool(false) => "False".into(),
            Self::Int(i) => i.to_string(),
            Self::Float(f) => format!("{f:?}"),
            Self::Word(w) => format!("{w:?}"),
        }
    }

    /// The value as a Python object.
    pub(crate) fn to_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(match self {
            Self::None => py.None().into_bound(py),
            Self::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
            Self::Int(i) => i.into_pyobject(py)?.into_any(),
            Self::Float(f) => f.into_pyobject(py)?.into_any(),
            Self::Word(w) => PyString::new(py, w).into_any(),
        })
    }
}

/// Why a value was refused: the wrong kind (`TypeError`) or out of range (`ValueError`).
pub(crate) enum Refused {
    Kind(String),
    Range(String),
}

impl From<Refused> for PyErr {
    fn from(r: Refused) -> Self {
        match r {
            Refused::Kind(m) => PyTypeError::new_err(m),
            Refused::Range(m) => PyValueError::new_err(m),
        }
    }
}

type Check<T> = Result<T, Refused>;

fn float(key: &str, v: &Value, lo: f64, hi: f64, lo_open: bool) -> Check<f32> {
    let x = match *v {
        Value::Int(i) => i as f64,
        Value::Float(f) => f,
        _ => {
            return Err(Refused::Kind(format!(
                "{key}: expected a number, not {}",
                v.repr()
            )));
        }
    };
    let above_lo = if lo_open { x > lo } else { x >= lo };
    if above_lo && x <= hi {
        Ok(x as f32)
    } else {
        let open = if lo_open { "(" } else { "[" };
        Err(Refused::Range(format!(
            "{key} = {x} is outside {open}{lo}, {hi}]"
        )))
    }
}

fn int(key: &str, v: &Value, lo: i64, hi: i64) -> Check<i64> {
    match *v {
        Value::Int(i) if (lo..=hi).contains(&i) => Ok(i),
        Value::Int(i) => Err(Refused::Range(format!(
            "{key} = {i} is outside [{lo}, {hi}]"
        ))),
        _ => Err(Refused::Kind(format!(
            "{key}: expected an integer, not {}",
            v.repr()
        ))),
    }
}

fn boolean(key: &str, v: &Value) -> Check<bool> {
    match *v {
        Value::Bool(b) => Ok(b),
        _ => Err(Refused::Kind(format!(
            "{key}: expected a bool, not {}",
            v.repr()
        ))),
    }
}

/// The index of `v` among `names`.
fn choice(key: &str, v: &Value, names: &[&str]) -> Check<usize> {
    match v {
        Value::Word(w) => names
            .iter()
            .position(|n| n == w)
            .ok_or_else(|| Refused::Range(format!("{key} = {w:?}: one of {}", names.join(", ")))),
        _ => Err(Refused::Kind(format!(
            "{key}: expected one of {}, not {}",
            names.join(", "),
            v.repr()
        ))),
    }
}

/// The names a structure takes, for the message about an unknown one.
pub(crate) const BVH: &[&str] = &[
    "layout",
    "split",
    "bins",
    "traversal_cost",
    "intersection_cost",
    "max_leaf_size",
    "reinsertion_passes",
    "parallel",
];
pub(crate) const KDTREE: &[&str] = &[
    "traversal_cost",
    "intersection_cost",
    "empty_bonus",
    "perfect_splits",
    "empty_cut",
    "max_depth",
    "depth_base",
    "max_bad_refines",
    "leaf_size",
    "parallel",
    "traversal",
];
pub(crate) const GRID: &[&str] = &[
    "density",
    "max_cells",
    "exact_insertion",
    "mailbox",
    "parallel",
];
pub(crate) const HGRID: &[&str] = &[
    "top_density",
    "density",
    "split_min",
    "max_levels",
    "max_cells",
    "mailbox",
    "parallel",
];
pub(crate) const OCTREE: &[&str] = &[
    "max_prims",
    "max_depth",
    "max_refs_per_prim",
    "mailbox",
    "parallel",
];

/// A cost in the SAH's relative units.
const COST: (f64, f64) = (0.0, 1e6);
/// Cells per primitive.
const DENSITY: (f64, f64) = (0.0, 64.0);
/// The most cells of one grid: 2²⁸ (a GiB of cell entries).
const MAX_CELLS: i64 = 1 << 28;

fn unknown(key: &str, names: &[&str]) -> Refused {
    Refused::Range(format!(
        "unknown parameter {key:?}: one of {}",
        names.join(", ")
    ))
}

pub(crate) fn set_bvh(p: &mut BvhParams, key: &str, v: &Value) -> Check<()> {
    match key {
        "layout" => p.layout = [Layout::Wide, Layout::Binary][choice(key, v, &["wide", "binary"])?],
        "split" => {
            p.split = [SplitMethod::Sah, SplitMethod::Median, SplitMethod::Middle]
                [choice(key, v, &["sah", "median", "middle"])?]
        }
        "bins" => p.bins = int(key, v, 2, 32)? as u32,
        "traversal_cost" => p.traversal_cost = float(key, v, COST.0, COST.1, true)?,
        "intersection_cost" => p.intersection_cost = float(key, v, COST.0, COST.1, true)?,
        "max_leaf_size" => p.max_leaf_size = int(key, v, 1, 255)? as u32,
        "reinsertion_passes" => p.reinsertion_passes = int(key, v, 0, 100)? as u32,
        "parallel" => p.parallel = boolean(key, v)?,
        _ => return Err(unknown(key, BVH)),
    }
    Ok(())
}

pub(crate) fn set_kdtree(p: &mut KdParams, key: &str, v: &Value) -> Check<()> {
    match key {
        "traversal_cost" => p.traversal_cost = float(key, v, COST.0, COST.1, true)?,
        "intersection_cost" => p.intersection_cost = float(key, v, COST.0, COST.1, true)?,
        "empty_bonus" => p.empty_bonus = float(key, v, 0.0, 1.0, false)?,
        "perfect_splits" => p.perfect_splits = boolean(key, v)?,
        "empty_cut" => p.empty_cut = float(key, v, 0.0, 1.0, false)?,
        "max_depth" => {
            p.max_depth = match v {
                Value::None => None,
                _ => Some(int(key, v, 1, rt_kdtree::MAX_DEPTH as i64)? as u32),
            }
        }
        "depth_base" => p.depth_base = float(key, v, 0.0, 64.0, false)?,
        "max_bad_refines" => p.max_bad_refines = int(key, v, 0, 64)? as u32,
        "leaf_size" => p.leaf_size = int(key, v, 0, 1 << 20)? as u32,
        "parallel" => p.parallel = boolean(key, v)?,
        "traversal" => {
            p.traversal =
                [Traversal::Stack, Traversal::Restart][choice(key, v, &["stack", "restart"])?]
        }
        _ => return Err(unknown(key, KDTREE)),
    }
    Ok(())
}

pub(crate) fn set_grid(p: &mut GridParams, key: &str, v: &Value) -> Check<()> {
    match key {
        "density" => p.density = float(key, v, DENSITY.0, DENSITY.1, true)?,
        "max_cells" => p.max_cells = int(key, v, 1, MAX_CELLS)? as usize,
        "exact_insertion" => p.exact_insertion = boolean(key, v)?,
        "mailbox" => p.mailbox = boolean(key, v)?,
        "parallel" => p.parallel = boolean(key, v)?,
        _ => return Err(unknown(key, GRID)),
    }
    Ok(())
}

pub(crate) fn set_hgrid(p: &mut HGridParams, key: &str, v: &Value) -> Check<()> {
    match key {
        "top_density" => p.top_density = float(key, v, DENSITY.0, DENSITY.1, true)?,
        "density" => p.density = float(key, v, DENSITY.0, DENSITY.1, true)?,
        "split_min" => p.split_min = int(key, v, 1, 1 << 20)? as u32,
        "max_levels" => p.max_levels = int(key, v, 1, rt_hgrid::MAX_LEVELS as i64)? as u32,
        "max_cells" => p.max_cells = int(key, v, 1, MAX_CELLS)? as usize,
        "mailbox" => p.mailbox = boolean(key, v)?,
        "parallel" => p.parallel = boolean(key, v)?,
        _ => return Err(unknown(key, HGRID)),
    }
    Ok(())
}

pub(crate) fn set_octree(p: &mut OctreeParams, key: &str, v: &Value) -> Check<()> {
    match key {
        "max_prims" => p.max_prims = int(key, v, 1, 1 << 20)? as u32,
        "max_depth" => p.max_depth = int(key, v, 0, rt_octree::MAX_DEPTH as i64)? as u32,
        "max_refs_per_prim" => p.max_refs_per_prim = float(key, v, 1.0, 1024.0, false)?,
        "mailbox" => p.mailbox = boolean(key, v)?,
        "parallel" => p.parallel = boolean(key, v)?,
        _ => return Err(unknown(key, OCTREE)),
    }
    Ok(())
}

//! Loading scene files: OBJ, PLY and glTF 2.0, chosen by extension, with one error type.
//!
//! Every loader returns a [`Mesh`] or a [`LoadError`] naming the file, and the line (text
//! formats) or the element (binary formats, such as `face 12` or `mesh 0 primitive 1`) to blame.
//! None panics, whatever the bytes: the fuzz targets in `fuzz/` feed each of them arbitrary input.

use crate::Mesh;
use std::fmt;
use std::path::{Path, PathBuf};

/// What went wrong while loading a mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadErrorKind {
    /// The file could not be read.
    Io(String),
    /// The bytes are not UTF-8 (nor UTF-16 with a byte-order mark).
    Encoding,
    /// A line does not follow the OBJ syntax.
    Malformed(String),
    /// A face refers to an element that does not exist (indices start at 1; negative indices
    /// count back from the last element defined so far).
    IndexOutOfRange {
        /// `"vertex"`, `"texture coordinate"` or `"normal"`.
        element: &'static str,
        /// The index as written.
        index: i64,
        /// How many such elements were defined before this line.
        defined: usize,
    },
    /// A face or a glTF primitive refers to a vertex the file does not have (indices start at 0).
    NoSuchVertex {
        /// The index as stored.
        index: i64,
        /// How many vertices there are.
        vertices: usize,
    },
    /// A vertex coordinate is NaN or infinite (or missing, in a PLY vertex).
    NonFinite,
    /// The file holds no triangles (it may hold only points or lines).
    NoTriangles,
    /// The OBJ parser rejected the file for a reason the validation pass did not foresee.
    Parser(String),
    /// A PLY or glTF file breaks its format's rules.
    Invalid(String),
    /// A PLY or glTF file uses something these loaders do not read.
    Unsupported(String),
    /// The file's extension is none of `.obj`, `.ply`, `.gltf` and `.glb`.
    UnknownFormat,
}

/// An error loading a scene file: which file, which line or element (when one is to blame), and
/// what.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadError {
    /// The file.
    pub path: PathBuf,
    /// The 1-based line, when the problem is on one line of a text file.
    pub line: Option<usize>,
    /// The element to blame in a binary or structured file, such as `face 12`, `vertex 3` or
    /// `mesh 0 primitive 1`.
    pub element: Option<String>,
    /// What is wrong.
    pub kind: LoadErrorKind,
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if let Some(element) = &self.element {
            write!(f, ": {element}")?;
        }
        match &self.kind {
            LoadErrorKind::Io(e) => write!(f, ": cannot read file: {e}"),
            LoadErrorKind::Encoding => write!(f, ": not UTF-8 or UTF-16 text"),
            LoadErrorKind::Malformed(what) => write!(f, ": malformed line: {what}"),
            LoadErrorKind::IndexOutOfRange {
                element,
                index,
                defined,
            } => write!(
                f,
                ": {element} index {index} out of range ({defined} defined before this line)"
            ),
            LoadErrorKind::NoSuchVertex { index, vertices } => write!(
                f,
                ": vertex index {index} out of range (the file has {vertices} vertices)"
            ),
            LoadErrorKind::NonFinite => write!(f, ": vertex coordinate is NaN or infinite"),
            LoadErrorKind::NoTriangles => write!(f, ": no triangles in the file"),
            LoadErrorKind::Parser(e) => write!(f, ": OBJ parser error: {e}"),
            LoadErrorKind::Invalid(what) => write!(f, ": {what}"),
            LoadErrorKind::Unsupported(what) => write!(f, ": not supported: {what}"),
            LoadErrorKind::UnknownFormat => write!(
                f,
                ": unknown scene format (expected .obj, .ply, .gltf or .glb, or a built-in scene)"
            ),
        }
    }
}

impl std::error::Error for LoadError {}

/// The scene file formats [`load_mesh`] reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// Wavefront OBJ text ([`load_obj`](crate::load_obj)).
    Obj,
    /// PLY, ASCII or binary.
    Ply,
    /// glTF 2.0: a `.gltf` JSON file (buffers external or embedded as data URIs) or a `.glb`.
    Gltf,
}

impl SceneFormat {
    /// The format a file name's extension names (in any case), if any.
    ///
    /// ```
    /// use rt_core::SceneFormat;
    /// assert_eq!(SceneFormat::from_path("scans/Lucy.PLY"), Some(SceneFormat::Ply));
    /// assert_eq!(SceneFormat::from_path("car.glb"), Some(SceneFormat::Gltf));
    /// assert_eq!(SceneFormat::from_path("notes.txt"), None);
    /// ```
    pub fn from_path(path: impl AsRef<Path>) -> Option<Self> {
        let ext = path.as_ref().extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(Self::Obj),
            "ply" => Some(Self::Ply),
            "gltf" | "glb" => Some(Self::Gltf),
            _ => None,
        }
    }
}

/// Loads the triangles of an OBJ, PLY or glTF file, chosen by its extension.
///
/// glTF files give the triangles of every mesh primitive (in triangle, strip or fan mode) of the
/// default scene's nodes, with the nodes' transforms applied; PLY files give their faces.
///
/// # Errors
/// A [`LoadError`] naming the file, and the line or element to blame where there is one, for an
/// unknown extension, a missing or unreadable file, or any content the format's loader rejects.
/// Never panics.
///
/// ```
/// let err = rt_core::load_mesh("no/such/model.ply").unwrap_err();
/// assert!(err.to_string().starts_with("no/such/model.ply: cannot read file"));
/// let err = rt_core::load_mesh("model.stl").unwrap_err();
/// assert_eq!(err.kind, rt_core::LoadErrorKind::UnknownFormat);
/// ```
pub fn load_mesh(path: impl AsRef<Path>) -> Result<Mesh, LoadError> {
    let path = path.as_ref();
    let Some(format) = SceneFormat::from_path(path) else {
        return Err(Located::none(LoadErrorKind::UnknownFormat).at(path));
    };
    match format {
        SceneFormat::Obj => crate::load_obj(path),
        SceneFormat::Ply => {
            let bytes = read(path)?;
            crate::ply::parse_ply(&bytes).map_err(|e| e.at(path))
        }
        SceneFormat::Gltf => {
            let bytes = read(path)?;
            let folder = path.parent().unwrap_or(Path::new(""));
            crate::gltf::parse_gltf(&bytes, Some(folder)).map_err(|e| e.at(path))
        }
    }
}

/// Loads a scene file's bytes from memory; `name` stands for the path in errors.
///
/// A glTF file whose buffers are external files cannot be loaded this way (there is no folder to
/// read them from): that is an [`LoadErrorKind::Unsupported`] error.
///
/// # Errors
/// As [`load_mesh`], except that nothing is read from disk.
pub fn load_mesh_bytes(name: &str, format: SceneFormat, bytes: &[u8]) -> Result<Mesh, LoadError> {
    match format {
        SceneFormat::Obj => crate::load_obj_bytes(name, bytes),
        SceneFormat::Ply => crate::ply::parse_ply(bytes).map_err(|e| e.at(name)),
        SceneFormat::Gltf => crate::gltf::parse_gltf(bytes, None).map_err(|e| e.at(name)),
    }
}

/// A file's bytes, or the error naming it.
pub(crate) fn read(path: &Path) -> Result<Vec<u8>, LoadError> {
    std::fs::read(path).map_err(|e| Located::none(LoadErrorKind::Io(e.to_string())).at(path))
}

/// A loader's error before the file's name is known: where, and what.
#[derive(Debug)]
pub(crate) struct Located {
    line: Option<usize>,
    element: Option<String>,
    kind: LoadErrorKind,
}

pub(crate) type LoadResult<T> = Result<T, Located>;

impl Located {
    pub(crate) fn none(kind: LoadErrorKind) -> Self {
        Self {
            line: None,
            element: None,
            kind,
        }
    }

    pub(crate) fn line(line: Option<usize>, kind: LoadErrorKind) -> Self {
        Self {
            line,
            element: None,
            kind,
        }
    }

    pub(crate) fn element(element: String, kind: LoadErrorKind) -> Self {
        Self {
            line: None,
            element: Some(element),
            kind,
        }
    }

    /// The error, in file `path`.
    pub(crate) fn at(self, path: impl AsRef<Path>) -> LoadError {
        LoadError {
            path: path.as_ref().to_owned(),
            line: self.line,
            element: self.element,
            kind: self.kind,
        }
    }
}

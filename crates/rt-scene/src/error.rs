//! The one error every loader returns, and the located error loaders build before they know
//! the file's name.

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

/// A file's bytes, or the error naming it.
#[cfg(any(feature = "obj", feature = "ply", feature = "gltf"))]
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

#[cfg(any(feature = "ply", feature = "gltf"))]
pub(crate) type LoadResult<T> = Result<T, Located>;

impl Located {
    pub(crate) fn none(kind: LoadErrorKind) -> Self {
        Self {
            line: None,
            element: None,
            kind,
        }
    }

    #[cfg(any(feature = "obj", feature = "ply"))]
    pub(crate) fn line(line: Option<usize>, kind: LoadErrorKind) -> Self {
        Self {
            line,
            element: None,
            kind,
        }
    }

    #[cfg(any(feature = "ply", feature = "gltf"))]
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

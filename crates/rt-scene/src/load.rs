//! Loading scene files: OBJ, PLY and glTF 2.0, chosen by extension, with one error type.
//!
//! Every loader returns a [`Mesh`] or a [`LoadError`] naming the file, and the line (text
//! formats) or the element (binary formats, such as `face 12` or `mesh 0 primitive 1`) to blame.
//! None panics, whatever the bytes: the fuzz targets in `fuzz/` feed each of them arbitrary input.

use crate::error::{LoadError, LoadErrorKind, Located};
use rt_core::Mesh;
use std::path::Path;

/// The scene file formats [`load_mesh`] reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// Wavefront OBJ text (feature `obj`; [`load_obj`](crate::load_obj)).
    Obj,
    /// PLY, ASCII or binary (feature `ply`).
    Ply,
    /// glTF 2.0: a `.gltf` JSON file (buffers external or embedded as data URIs) or a `.glb`
    /// (feature `gltf`).
    Gltf,
}

impl SceneFormat {
    /// The format a file name's extension names (in any case), if any.
    ///
    /// ```
    /// use rt_scene::SceneFormat;
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
/// let err = rt_scene::load_mesh("no/such/model.obj").unwrap_err();
/// assert!(err.to_string().starts_with("no/such/model.obj: cannot read file"));
/// let err = rt_scene::load_mesh("model.stl").unwrap_err();
/// assert_eq!(err.kind, rt_scene::LoadErrorKind::UnknownFormat);
/// ```
pub fn load_mesh(path: impl AsRef<Path>) -> Result<Mesh, LoadError> {
    let path = path.as_ref();
    let Some(format) = SceneFormat::from_path(path) else {
        return Err(Located::none(LoadErrorKind::UnknownFormat).at(path));
    };
    match format {
        #[cfg(feature = "obj")]
        SceneFormat::Obj => crate::obj::load_obj(path),
        #[cfg(feature = "ply")]
        SceneFormat::Ply => {
            let bytes = crate::error::read(path)?;
            crate::ply::parse_ply(&bytes).map_err(|e| e.at(path))
        }
        #[cfg(feature = "gltf")]
        SceneFormat::Gltf => {
            let bytes = crate::error::read(path)?;
            let folder = path.parent().unwrap_or(Path::new(""));
            crate::gltf::parse_gltf(&bytes, Some(folder)).map_err(|e| e.at(path))
        }
        #[cfg(not(all(feature = "obj", feature = "ply", feature = "gltf")))]
        other => Err(not_built(other).at(path)),
    }
}

/// Loads a scene file's bytes from memory; `name` stands for the path in errors.
///
/// A glTF file whose buffers are external files cannot be loaded this way (there is no folder to
/// read them from): that is an [`LoadErrorKind::Unsupported`] error.
///
/// # Errors
/// As [`load_mesh`], except that nothing is read from disk.
#[cfg_attr(
    not(any(feature = "obj", feature = "ply", feature = "gltf")),
    allow(unused_variables)
)]
pub fn load_mesh_bytes(name: &str, format: SceneFormat, bytes: &[u8]) -> Result<Mesh, LoadError> {
    match format {
        #[cfg(feature = "obj")]
        SceneFormat::Obj => crate::obj::load_obj_bytes(name, bytes),
        #[cfg(feature = "ply")]
        SceneFormat::Ply => crate::ply::parse_ply(bytes).map_err(|e| e.at(name)),
        #[cfg(feature = "gltf")]
        SceneFormat::Gltf => crate::gltf::parse_gltf(bytes, None).map_err(|e| e.at(name)),
        #[cfg(not(all(feature = "obj", feature = "ply", feature = "gltf")))]
        other => Err(not_built(other).at(name)),
    }
}

/// The error for a format whose loader this build left out (its feature is off).
#[cfg(not(all(feature = "obj", feature = "ply", feature = "gltf")))]
fn not_built(format: SceneFormat) -> Located {
    let feature = match format {
        SceneFormat::Obj => "obj",
        SceneFormat::Ply => "ply",
        SceneFormat::Gltf => "gltf",
    };
    Located::none(LoadErrorKind::Unsupported(format!(
        "rt-scene was built without its `{feature}` feature"
    )))
}

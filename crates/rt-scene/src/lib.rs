//! Scenes for rt-accel's structures: meshes loaded from files, procedural scenes made at any
//! size, a pinhole camera, the ray sets the shootout measures with, and animations.
//!
//! The structures themselves (`rt-bvh`, `rt-kdtree`, ...) need none of this: they build from any
//! [`rt_core::Geometry`]. This crate is what a program adds to get that geometry from a file, and
//! rays from a camera.
//!
//! ```no_run
//! use rt_core::Accel;
//! use rt_scene::Camera;
//!
//! # fn main() -> Result<(), rt_scene::LoadError> {
//! let mesh = rt_scene::load_mesh("bunny.ply")?; // OBJ, PLY, glTF or GLB, by extension
//! let accel = rt_core::BruteForce::build_from(&mesh, &());
//! let camera = Camera::framing(&mesh.bounds(), 640, 480);
//! let hits = camera
//!     .primary_rays(640, 480)
//!     .iter()
//!     .filter(|ray| accel.intersect(ray).is_some())
//!     .count();
//! println!("{hits} of 307200 pixels see the mesh");
//! # Ok(())
//! # }
//! ```
//!
//! # What is here
//! - **Loading**: [`load_mesh`] chooses the format by extension ([`SceneFormat`]),
//!   [`load_mesh_bytes`] reads from memory. Every loader returns an [`rt_core::Mesh`] or a
//!   [`LoadError`] naming the file, and the line (text formats) or the element (binary formats)
//!   to blame, and none panics, whatever the bytes (the fuzz targets feed them arbitrary input).
//! - **Writing**: [`save`] writes a mesh as PLY (three encodings), `.gltf` or `.glb`.
//! - **Procedural scenes**: [`scenes`] makes the built-in scenes (`sphereflake`, `random-soup`,
//!   `teapot-in-stadium`, `terrain`, ...) at any size, so tests and benchmarks need no files.
//! - **Rays**: [`Camera`] gives the ray through any point of an image; [`raygen`] makes the
//!   incoherent and shadow ray sets, query points, and reads and writes rays files.
//! - **Animation**: [`motion`] moves triangles frame by frame (a wave, an explosion), for
//!   refitting against rebuilding.
//!
//! # Features
//! Each format's loader is a feature, so a program compiles only the parsers it reads with.
//! With a format's feature off, [`load_mesh`] answers that format with
//! [`LoadErrorKind::Unsupported`], naming the feature.
//!
//! | feature | default | what it adds to a build (`cargo tree -e normal,build`) |
//! | --- | --- | --- |
//! | `obj` | on | tobj: one crate, no procedural macro |
//! | `ply` | off | ply-rs-bw, whose grammar is written with `peg`'s procedural macro: 11 crates, among them `peg-macros`, `proc-macro2` and `quote` |
//! | `gltf` | off | the `gltf` document model and base64: 19 crates, among them the procedural macros `serde_derive` and `gltf-derive`, with `syn` (two major versions) and serde_json |
//!
//! The guide's page on using the crates (`docs/using.md`) has the build times of each.
#![warn(missing_docs)]

mod camera;
mod error;
#[cfg(feature = "gltf")]
mod gltf;
mod load;
pub mod motion;
#[cfg(feature = "obj")]
mod obj;
#[cfg(feature = "ply")]
mod ply;
#[cfg(any(feature = "obj", feature = "ply"))]
mod polygon;
pub mod raygen;
pub mod save;
pub mod scenes;

pub use camera::{Camera, Raster};
pub use error::{LoadError, LoadErrorKind};
pub use load::{SceneFormat, load_mesh, load_mesh_bytes};
#[cfg(feature = "obj")]
pub use obj::{load_obj, load_obj_bytes};

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

//! A small Whitted-style ray tracer over any rt-accel structure: the picture that shows a
//! structure answers right, and the per-pixel cost heatmaps that show where its work goes.
//!
//! - [`RenderScene`]: a triangle [`Mesh`](rt_core::Mesh) (with its normals and texture
//!   coordinates) plus analytic spheres, [`Material`]s, [`PointLight`]s, a camera and a sky;
//!   [`RenderScene::whitted`] is the built-in scene of a glass sphere, a mirror sphere, a
//!   checkerboard floor and the procedural teapot, and [`scene`] also loads the built-in mesh
//!   scenes and OBJ files.
//! - [`render`]: primary rays through every pixel, shadow rays to each light through the
//!   any-hit query, mirror and refracted rays to a fixed depth (see `whitted.rs`), tiles in
//!   parallel on rayon's pool. Each tile's primary rays are traced as bundles of 8×8 pixels,
//!   and their shadow rays as one batch per light ([`rt_core::Accel::intersect_bundle`],
//!   [`rt_core::Accel::occluded_bundle`]); the answers are the single rays' to the bit, so the
//!   picture is the same bytes either way. Secondary rays start at the hit moved off its
//!   surface by an error bound ([`rt_core::SurfacePoint::spawn_ray`]), never by a per-scene
//!   epsilon.
//! - [`render_path`]: a path tracer (next-event estimation toward the lights, cosine-weighted
//!   diffuse bounces, mirror and glass) written as a wavefront, every bounce's rays handed to
//!   the structure together, one at a time, as one batch, or both ways paired ([`Tracing`]),
//!   with the rays and trace time of each bounce depth ([`DepthStats`]); the picture is the
//!   same bytes every way.
//! - [`cost_map`] and [`heatmap_strip`]: the primary rays' node visits or primitive tests per
//!   pixel, several structures side by side on one colour scale with a legend.
//! - [`slice_svg`]: a drawing of a structure's nodes or cells ([`rt_core::Accel::regions`])
//!   where they meet an axis-aligned plane, with the mesh's cross-section, as SVG.
//! - Any structure over [`Shape`](rt_core::Shape)s renders, seen through rt-core's object-safe
//!   [`DynAccel`](rt_core::DynAccel): one call per ray, or per batch of rays, crosses the
//!   trait object.
//!
//! Every correct structure renders the same bytes: the renderer re-derives each hit from the
//! primitive the structure names, and the tie rule makes that primitive unique.
//!
//! ```
//! use rt_core::Accel;
//! use rt_render::{RenderOptions, RenderScene, render};
//!
//! let scene = RenderScene::whitted();
//! let shapes = scene.shapes();
//! let accel = rt_core::BruteForce::build(&shapes, &Default::default());
//! let options = RenderOptions { width: 4, height: 3, depth: 3 };
//! let image = render(&scene, &shapes, &accel, &options, &|_done, _total| {}).unwrap();
//! assert_eq!((image.width, image.height), (4, 3));
//! // image.save_png(std::path::Path::new("whitted.png")) writes it.
//! ```
#![warn(missing_docs)]

mod heatmap;
mod image;
mod path;
mod scene;
mod slice;
mod whitted;

pub use heatmap::{
    CostMap, Metric, Scale, cost_map, draw_text, heatmap_strip, text_width, viridis,
};
pub use image::{Image, ImageError, MAX_SIDE, RenderOptions, TILE, encode, render};
pub use path::{DepthStats, Paired, PathOptions, PathRender, Tracing, render_path};
pub use scene::{Material, PointLight, RenderScene, builtin_names, scene};
pub use slice::{Coloring, SliceOptions, SliceSummary, cross_section, slice_svg, view_axes};

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

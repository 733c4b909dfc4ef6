//! The contract of the `rt-accel` structures: rays, boxes, primitives, the [`Accel`] trait every
//! acceleration structure implements and the queries it answers (closest and any hit, ray
//! queries of one's own, closest points, box overlap), traversal [`Stats`] and traces, and the
//! [`BruteForce`] reference that defines every right answer. It depends on glam, bytemuck and
//! two small crates it re-exports, rt-par ([`par`]: the builders' parallel patterns, on rayon
//! with the `parallel` feature) and rt-pod ([`pod_struct!`]).
//!
//! A student who writes a structure reads this crate and implements six methods of [`Accel`]
//! (`presets`, `build`, `bounds`, `ball_query`, `memory_bytes`, `build_stats`); every query then
//! answers, and the conformance kit checks it. Everything a fast structure shares beyond that
//! lives beside it, in crates a structure opts into:
//!
//! | crate | what | moved from here |
//! | --- | --- | --- |
//! | `rt-simd` | the run-time instruction set, lane vectors, the watertight, Möller–Trumbore and slab kernels written once over the lane width, ray bundles (`Bundle`, `Lanes`, `walk_groups`) | `rt_core::bundle`'s bundles and lanes, `Bundle`, `BUNDLE_LANES`, `LaneBounds` |
//! | `rt-persist` | saved structures: `Persist`, the checked file framing | `rt_core::persist` |
//! | `rt-instance` | two-level scenes: `Instance`, `TwoLevel`, `LinearInstances` | `rt_core::Instance`, ... |
//! | `rt-sdf` | inside, outside and signed distance: `WindingTree`, `SignedDistance` | `rt_core::winding`, `Accel::signed_distance`, `Accel::inside_by_parity` |
//!
//! Around them: `rt-scene` loads meshes (OBJ, PLY, glTF), makes procedural scenes and has the
//! camera; `rt-conformance` is the kit that checks any structure (yours too) against brute
//! force; the structures are crates of their own (`rt-bvh`, `rt-kdtree`, `rt-grid`,
//! `rt-hgrid`, `rt-octree`).
//!
//! # Using a structure
//! Structures live in their own crates (`rt-bvh`, ...) and all follow [`Accel`]:
//!
//! ```
//! use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
//!
//! let tris = vec![
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)),
//!     Triangle::new(Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)),
//! ];
//! let accel = BruteForce::build(&tris, &Default::default());
//! let ray = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
//! let hit = accel.intersect(&ray).expect("the ray hits the first triangle");
//! assert_eq!((hit.prim, hit.t), (0, 5.0));
//! assert!(accel.occluded(&ray));
//! ```
//!
//! # Building from a mesh
//! [`Accel::build_from`] builds over any [`Geometry`]: a slice, a [`Mesh`], or an
//! [`IndexedTriangles`] view of position and index buffers the caller owns. Structures read the
//! triangles through the indices straight into the layout they keep, with no triangle list in
//! between (see the [`Geometry`] documentation).
//!
//! Meshes come from files through `rt-scene` (`rt_scene::load_mesh`: OBJ, PLY, glTF), which
//! also has the camera a renderer needs (`rt_scene::Camera`), or from buffers you already have
//! ([`IndexedTriangles::from_flat`]).
//!
//! # Many rays at once
//! [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`] answer a slice of rays, each
//! exactly as the single-ray query would; structures that trace coherent rays together (a
//! camera's tiles, a light's shadow rays) override them with rt-simd's bundles.
//! [`batch::intersect`] traces a whole ray list that way on all threads, and
//! [`bundle::intersect_image`] a frame whose rays come in image order, bundled by tiles. See the
//! [`bundle`] module.
//!
//! # Every query in batches
//! The [`batch`] module answers many rays, points or boxes in one call on every thread of the
//! current rayon pool (a smaller pool limits the threads): closest and any hits, counts and all
//! hits of rays given as [`Ray`]s or as flat rows of six numbers ([`batch::FlatRays`]), closest
//! points in the Morton order that shares the cache, box overlaps, and answers laid out as the
//! caller wants them.
//!
//! # Closest points
//! [`Accel::closest_point`] finds the primitive nearest to a point (a [`PointHit`]: index, point,
//! distance). Structures implement one traversal, [`Accel::ball_query`], over a [`BallQuery`]
//! whose ball shrinks as primitives are found; [`ClosestPointQuery`] is the standard one, and
//! callers can write others (a transformed instance, all primitives within a radius).
//!
//! # Box overlap
//! [`Accel::overlapping`] lists the primitives that meet an axis-aligned box (a triangle is
//! clipped to the box, not judged by its bounding box), and [`Accel::overlaps_any`]
//! stops at the first. Structures implement one traversal, [`Accel::box_query`], over a
//! [`BoxQuery`] that may end the walk; [`OverlapQuery`] is the standard one.
//!
//! # Conventions
//! - A hit is the smallest `t` in the ray's closed interval `[t_min, t_max]`; equal `t` goes to
//!   the smaller primitive index ([`Hit::beats`]). The answer is unique, so structures can be
//!   compared exactly.
//! - The nearest primitive to a point is unique the same way: equal distances go to the smaller
//!   index ([`PointHit::beats`]).
//! - Invalid primitives (non-finite, zero-area; [`Primitive::is_valid`]) are never hit.
//! - Nothing here panics on bad geometry: invalid primitives are left out, invalid rays miss,
//!   and malformed buffers give a typed [`MeshError`].
//!
//! # Features
//! - `parallel` (off here; the structure crates turn it on by default): the builders' parallel
//!   patterns ([`par`]), the [`batch`] queries and [`bundle::intersect_image`] run on rayon's
//!   threads. Without it they
//!   run in order on the calling thread and give the same answers.
//!
//! Measurements of every structure are on the generated results pages, one per machine kind,
//! listed by `docs/results.md` in the repository (date, commit, CPU; written by `cargo xtask
//! results`).
#![warn(missing_docs)]

mod aabb;
mod accel;
pub mod batch;
mod brute;
pub mod bundle;
mod clip;
mod closest;
mod cost;
mod dyn_accel;
mod event;
mod geometry;
mod hit;
pub mod leaf;
mod mailbox;
mod mesh;
mod overlap;
mod point;
mod primitive;
pub mod query;
mod ray;
mod refit;
mod rng;
mod shape;
mod sphere;
mod stack;
mod stats;
mod surface;
pub mod trace;
mod triangle;

pub use aabb::{Aabb, NEAR_TIE, SLAB_FAR_SCALE};
pub use accel::{Accel, BuildStats, Region, ValidationError};
pub use brute::BruteForce;
pub use clip::{clip_triangle_bounds, split_triangle_bounds};
pub use closest::{BallQuery, ClosestPointQuery};
pub use cost::{PredictedCost, predicted_cost};
pub use dyn_accel::{DynAccel, DynRayQuery};
pub use geometry::{Geometry, IndexedTriangles};
pub use hit::{Hit, PrimHit};
pub use mailbox::{Mailbox, Visited};
pub use mesh::{Mesh, MeshError, Shading};
pub use overlap::{BoxQuery, OverlapQuery};
pub use point::{
    Feature, PointHit, closest_feature_on_triangle, closest_point_on_triangle, point_distance,
};
pub use primitive::{Primitive, TriangleTest, valid_bounds, valid_primitives};
pub use query::{AllHits, AnyHit, ClosestHit, CountHits, Filtered, RayQuery};
pub use ray::{Ray, RayFault};
pub use refit::{Refit, RefitError};
pub use rng::Rng;
pub use shape::Shape;
pub use sphere::Sphere;
pub use stack::Stack;
pub use stats::{Counters, NoStats, Stats};
pub use surface::{OFFSET_ULPS, SurfacePoint, error_bound, offset_origin};
pub use trace::{Event, Outcome, Place, Take, Trace};
pub use triangle::{MtTriangle, Shear, Triangle, moller_trumbore_edges};

/// Re-exported so users name the same `Vec3` the library uses.
pub use glam;

/// Re-exported so users cast the same `Pod` types the library declares (nodes, packs, primitives:
/// see [`pod_struct!`]).
pub use bytemuck;

/// The builders' parallel patterns, from the `rt-par` crate: on rayon's threads with the
/// feature `parallel`, in order on the calling thread without, the same values either way.
pub use rt_par as par;

/// Plain-old-data structs checked at compile time without bytemuck's derive macro, from the
/// `rt-pod` crate.
pub use rt_pod::pod_struct;

/// The README's example, compiled and run as a doctest so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

//! Many rays in one call: what [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`]
//! promise, the loops behind their defaults, and whole frames on all threads.
//!
//! A bundle query answers a slice of rays into a slice of answers. Its default loops over the
//! single-ray queries ([`intersect_each`], [`occluded_each`]), so every structure (a student's
//! too) answers them; a structure that traces coherent rays together overrides them (the
//! structures of this workspace do, with the `rt-simd` crate's `Bundle`s and lane kernels),
//! and must answer every ray exactly as its single-ray query does: the conformance kit checks
//! it.
//!
//! [`intersect_frame`] and [`occluded_frame`] trace a whole ray list in tasks on rayon's
//! threads (with the `parallel` feature; in order on the calling thread without it).
//!
//! # Counting
//! A bundle's walk reports one [`Stats::node_visit`] per node (or cell) the bundle enters,
//! whatever the number of its lanes, and with it [`Stats::bundle_lanes`]: how many lanes the
//! bundle carries and how many of them are active there. Node visits per ray then show what a
//! bundle saves, and [`Counters::lane_utilisation`](crate::Counters::lane_utilisation) how full
//! its steps were. Primitive tests count once per lane and primitive, as single rays count
//! them. A ray a bundle finishes alone (see [`Stats::single_ray`]) counts as a single ray.
//!
//! [`Stats::node_visit`]: crate::Stats::node_visit
//! [`Stats::bundle_lanes`]: crate::Stats::bundle_lanes
//! [`Stats::single_ray`]: crate::Stats::single_ray

pub use crate::accel::{intersect_each, occluded_each};
use crate::{Accel, Hit, NoStats, Ray};

/// Rays per task of [`intersect_frame`] and [`occluded_frame`]: sixteen full bundles of 64
/// rays, enough to amortise a task's start, few enough to balance a frame over the threads.
pub const FRAME_TASK: usize = 1024;

/// [`Accel::intersect_bundle`] over a whole ray list (a frame, a batch of queries), in tasks of
/// [`FRAME_TASK`] rays on rayon's threads with the `parallel` feature. `out` gets as many answers
/// as both slices have slots, each exactly the single-ray answer.
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Triangle, bundle, glam::Vec3};
/// let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y)];
/// let accel = BruteForce::build(&tris, &());
/// let rays: Vec<Ray> = (0..1000)
///     .map(|i| Ray::new(Vec3::new(i as f32 / 1000.0 - 0.5, 0.0, -1.0), Vec3::Z))
///     .collect();
/// let mut hits = vec![None; rays.len()];
/// bundle::intersect_frame(&accel, &rays, &mut hits);
/// assert!(hits.iter().all(|h| h.is_some_and(|h| h.prim == 0 && h.t == 1.0)));
/// ```
pub fn intersect_frame<A: Accel>(accel: &A, rays: &[Ray], out: &mut [Option<Hit>]) {
    crate::par::zip_chunks_mut(rays, out, FRAME_TASK, |r, o| {
        accel.intersect_bundle_with(r, o, &mut NoStats)
    });
}

/// [`Accel::occluded_bundle`] over a whole ray list, as [`intersect_frame`] does.
pub fn occluded_frame<A: Accel>(accel: &A, rays: &[Ray], out: &mut [bool]) {
    crate::par::zip_chunks_mut(rays, out, FRAME_TASK, |r, o| {
        accel.occluded_bundle_with(r, o, &mut NoStats)
    });
}

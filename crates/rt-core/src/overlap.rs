//! Box overlap queries: the primitives whose surface meets an axis-aligned box.
//!
//! Collision and editing tools ask which triangles lie in a region: the triangles under a brush,
//! the candidates a physics step must test against a moving body's box, the part of a mesh to
//! re-mesh. A structure answers through one traversal, [`Accel::box_query`](crate::Accel),
//! which prunes every box or cell that does not meet the query box and offers the primitives of
//! the rest to a [`BoxQuery`]. The query decides, with [`Primitive::overlaps_box`], and
//! may stop the walk at any primitive ([`ControlFlow::Break`]), which is how
//! [`Accel::overlaps_any`](crate::Accel::overlaps_any) stops at the first one.
//!
//! # Exactness
//! Every structure reports exactly what [`BruteForce`](crate::BruteForce) reports, because the
//! answer depends only on each primitive's own [`Primitive::overlaps_box`] and pruning is
//! conservative: a structure skips a box or cell only when it does not meet the query box, and
//! boxes are closed, so a triangle that only touches the query box is found. A triangle's test
//! clips it to the box ([`clip_triangle_bounds`](crate::clip_triangle_bounds)), so a triangle
//! whose bounding box meets the query box while the triangle passes beside it is not reported.
//! The clip runs in `f64` from the `f32` vertices: a vertex on a face of the box is decided
//! exactly, and an edge crossing the box is placed to within `f64` rounding, about 2⁻⁵² of the
//! coordinates, which brute force and every structure share.

use crate::{Aabb, BallQuery, Primitive};
use glam::Vec3;
use std::ops::ControlFlow;

/// What a box overlap traversal ([`Accel::box_query`](crate::Accel::box_query)) works for: a
/// fixed box, and a test of each primitive offered that may end the walk.
///
/// A structure offers every valid primitive it holds that may meet [`bounds`](BoxQuery::bounds)
/// and may skip a box (or cell) only when it does not meet it. Once a test returns
/// [`ControlFlow::Break`], the structure offers nothing more.
pub trait BoxQuery<P> {
    /// The query box (closed). An empty box, or one with a NaN coordinate, meets nothing.
    fn bounds(&self) -> Aabb;

    /// Offers primitive `id` of the build input; `Break` ends the walk. A structure calls it for
    /// each primitive it reaches (possibly more than once for the same one) and reports it to
    /// its [`Stats`](crate::Stats) as a primitive test.
    fn test(&mut self, prim: &P, id: u32) -> ControlFlow<()>;

    /// Offers primitive `id` as the triangle with vertices `v`: what a structure that keeps
    /// triangles pre-processed in its own layout calls instead of [`test`](BoxQuery::test), for
    /// primitives whose [`Primitive::as_triangle`] is `Some`. The vertices are those the
    /// primitive's own [`overlaps_box`](Primitive::overlaps_box) clips: a Möller–Trumbore
    /// triangle's are its first vertex plus each edge ([`MtTriangle`](crate::MtTriangle)).
    fn test_triangle(&mut self, v: [Vec3; 3], id: u32) -> ControlFlow<()>;
}

/// A query behind a mutable reference (`&mut dyn BoxQuery<P>` included) is a query, so a
/// structure known only as a trait object can still run a caller's query.
impl<P, Q: BoxQuery<P> + ?Sized> BoxQuery<P> for &mut Q {
    #[inline(always)]
    fn bounds(&self) -> Aabb {
        (**self).bounds()
    }
    #[inline(always)]
    fn test(&mut self, prim: &P, id: u32) -> ControlFlow<()> {
        (**self).test(prim, id)
    }
    #[inline(always)]
    fn test_triangle(&mut self, v: [Vec3; 3], id: u32) -> ControlFlow<()> {
        (**self).test_triangle(v, id)
    }
}

/// Whether a query box can meet anything: no NaN and no axis with `min > max`.
#[inline]
pub(crate) fn query_box_valid(b: &Aabb) -> bool {
    !b.is_empty()
}

/// The query behind [`Accel::overlapping`](crate::Accel::overlapping) and
/// [`Accel::overlaps_any`](crate::Accel::overlaps_any): collects the primitives that meet a box,
/// or stops at the first.
///
/// ```
/// use rt_core::{Aabb, Accel, BruteForce, OverlapQuery, Triangle, glam::Vec3};
/// let tris = [
///     Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
///     Triangle::new(Vec3::new(5.0, 0.0, 0.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(5.0, 1.0, 0.0)),
/// ];
/// let accel = BruteForce::build(&tris, &());
/// let mut query = OverlapQuery::all(Aabb::new(Vec3::splat(-1.0), Vec3::splat(0.5)));
/// accel.box_query(&mut query, &mut rt_core::NoStats);
/// assert_eq!(query.into_ids(), vec![0]);
/// ```
#[derive(Clone, Debug)]
pub struct OverlapQuery {
    bounds: Aabb,
    first_only: bool,
    ids: Vec<u32>,
}

impl OverlapQuery {
    /// Collects every primitive that meets `bounds`.
    pub fn all(bounds: Aabb) -> Self {
        Self {
            bounds,
            first_only: false,
            ids: Vec::new(),
        }
    }

    /// Stops at the first primitive found that meets `bounds` (not necessarily the one with the
    /// smallest index).
    pub fn first(bounds: Aabb) -> Self {
        Self {
            first_only: true,
            ..Self::all(bounds)
        }
    }

    /// The primitives found, in ascending order, each once (a structure may offer a primitive
    /// listed in several cells more than once).
    pub fn into_ids(mut self) -> Vec<u32> {
        self.ids.sort_unstable();
        self.ids.dedup();
        self.ids
    }

    /// Whether any primitive was found.
    pub fn found(&self) -> bool {
        !self.ids.is_empty()
    }

    #[inline]
    fn keep(&mut self, overlaps: bool, id: u32) -> ControlFlow<()> {
        if overlaps {
            self.ids.push(id);
            if self.first_only {
                return ControlFlow::Break(());
            }
        }
        ControlFlow::Continue(())
    }
}

impl<P: Primitive> BoxQuery<P> for OverlapQuery {
    #[inline]
    fn bounds(&self) -> Aabb {
        self.bounds
    }
    #[inline]
    fn test(&mut self, prim: &P, id: u32) -> ControlFlow<()> {
        let overlaps = prim.overlaps_box(&self.bounds);
        self.keep(overlaps, id)
    }
    #[inline]
    fn test_triangle(&mut self, v: [Vec3; 3], id: u32) -> ControlFlow<()> {
        let overlaps = crate::clip_triangle_bounds(v, &self.bounds).is_some();
        self.keep(overlaps, id)
    }
}

/// A box query run as the ball query of the ball around its box: the default
/// [`Accel::box_query`](crate::Accel::box_query), for structures that implement only the ball
/// traversal. Every primitive that meets the box has a point in the ball, so the ball query
/// offers it; after a `Break` the radius turns negative, which prunes everything left.
pub(crate) struct BallOfBox<'a, Q> {
    query: &'a mut Q,
    center: Vec3,
    radius_sq: f32,
}

impl<'a, Q> BallOfBox<'a, Q> {
    /// The ball around `query`'s box, or `None` if the box meets nothing.
    pub(crate) fn new<P>(query: &'a mut Q) -> Option<Self>
    where
        Q: BoxQuery<P>,
    {
        let b = query.bounds();
        if !query_box_valid(&b) {
            return None;
        }
        // Computed in f64 and widened by a relative 2⁻²⁰, so that rounding in the structures'
        // f32 box distances cannot prune a box that meets the query box. An infinite side is
        // cut to the largest f32 first, which keeps the centre finite (the radius is then
        // infinite, and prunes nothing).
        let (lo, hi) = (
            b.min.max(Vec3::splat(-f32::MAX)).as_dvec3(),
            b.max.min(Vec3::splat(f32::MAX)).as_dvec3(),
        );
        let center = ((lo + hi) * 0.5).as_vec3();
        let far = (lo - center.as_dvec3())
            .abs()
            .max((hi - center.as_dvec3()).abs());
        let radius_sq = (far.length_squared() * (1.0 + 1.0 / 1_048_576.0)) as f32;
        Some(Self {
            query,
            center,
            radius_sq,
        })
    }
}

impl<P, Q: BoxQuery<P>> BallQuery<P> for BallOfBox<'_, Q> {
    fn center(&self) -> Vec3 {
        self.center
    }
    fn radius_sq(&self) -> f32 {
        self.radius_sq
    }
    fn test(&mut self, prim: &P, id: u32) {
        if self.radius_sq >= 0.0 && self.query.test(prim, id).is_break() {
            self.radius_sq = -1.0;
        }
    }
    fn test_triangle(&mut self, v0: Vec3, e1: Vec3, e2: Vec3, id: u32) {
        if self.radius_sq >= 0.0
            && self
                .query
                .test_triangle([v0, v0 + e1, v0 + e2], id)
                .is_break()
        {
            self.radius_sq = -1.0;
        }
    }
}

//! The renderer's view of a structure: an object-safe trait, so one renderer serves every
//! structure (and a list of them) without being compiled once per structure.

use rt_core::{Accel, Counters, Hit, Ray, Shape};

/// The queries the renderer makes. Every [`Accel`] over [`Shape`]s implements it.
///
/// The renderer calls it once per ray through a `dyn` pointer: a few nanoseconds against the
/// hundreds a traversal and shading take.
pub trait Tracer: Send + Sync {
    /// The closest hit ([`Accel::intersect`]).
    fn closest_hit(&self, ray: &Ray) -> Option<Hit>;
    /// Whether anything is hit ([`Accel::occluded`]).
    fn any_hit(&self, ray: &Ray) -> bool;
    /// The closest hit, counting node visits and primitive tests into `counters`.
    fn closest_hit_counted(&self, ray: &Ray, counters: &mut Counters) -> Option<Hit>;
}

impl<A: Accel<Prim = Shape>> Tracer for A {
    #[inline]
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        Accel::intersect(self, ray)
    }

    #[inline]
    fn any_hit(&self, ray: &Ray) -> bool {
        Accel::occluded(self, ray)
    }

    #[inline]
    fn closest_hit_counted(&self, ray: &Ray, counters: &mut Counters) -> Option<Hit> {
        self.intersect_with(ray, counters)
    }
}

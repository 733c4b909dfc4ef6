//! The slab test of `N` boxes against one ray, over the lane width: lane by lane
//! [`rt_core::Aabb::intersect`].

use crate::Simd;
use rt_core::{Ray, SLAB_FAR_SCALE};

/// What the slab test needs of a ray, broadcast into `N` lanes once per ray.
#[derive(Clone, Copy, Debug)]
pub struct SlabRay<V> {
    /// The origin along x, y, z.
    pub origin: [V; 3],
    /// The reciprocal direction along x, y, z.
    pub inv_dir: [V; 3],
    /// `t_min`.
    pub t_min: V,
}

impl<V: Copy> SlabRay<V> {
    /// `ray` in every lane.
    #[inline(always)]
    pub fn new<const N: usize, S: Simd<N, V = V>>(s: S, ray: &Ray) -> Self {
        let (o, inv) = (ray.origin, ray.inv_dir());
        // Written out lane by lane: closures passed to `array::map` are not inlined into the
        // AVX2 entry point, and the broadcasts then run as calls (measured: a third of the cost
        // of a ray that misses the root).
        Self {
            origin: [s.splat(o.x), s.splat(o.y), s.splat(o.z)],
            inv_dir: [s.splat(inv.x), s.splat(inv.y), s.splat(inv.z)],
            t_min: s.splat(ray.t_min),
        }
    }
}

/// The slab test of `N` boxes, given as rows `bounds` (minimum x, y, z, then maximum x, y, z;
/// lane `i` of each row is box `i`), against `[t_min, t_max]`: a bit mask of the boxes entered
/// and each box's entry distance.
///
/// Lane by lane this is [`rt_core::Aabb::intersect`]: the near and far planes chosen by the sign
/// of the reciprocal direction, `(plane − origin) · inv_dir`, the interval narrowed by
/// comparisons that ignore NaN (an origin in a face plane with a zero direction component), the
/// far end widened by [`SLAB_FAR_SCALE`]. Empty lanes (`+inf` minimum, `−inf` maximum) never
/// pass.
#[inline(always)]
pub fn slab<const N: usize, S: Simd<N>>(
    s: S,
    bounds: &[[f32; N]; 6],
    r: &SlabRay<S::V>,
    t_max: f32,
) -> (u32, S::V) {
    let (entered, t0) = slab_lanes(s, bounds, r, t_max);
    (s.bits(entered), t0)
}

/// [`slab`] with the boxes entered as a lane mask rather than bits, for a caller that goes on
/// computing with it lane by lane (a stream's sums of entry distances).
#[inline(always)]
pub fn slab_lanes<const N: usize, S: Simd<N>>(
    s: S,
    bounds: &[[f32; N]; 6],
    r: &SlabRay<S::V>,
    t_max: f32,
) -> (S::M, S::V) {
    let mut t0 = r.t_min;
    let mut t1 = s.splat(t_max);
    for a in 0..3 {
        // The near plane is the minimum row for a positive reciprocal direction and the maximum
        // row for a negative one (`-0` included), chosen lane by lane from the reciprocal's sign
        // (one blend) rather than by row indices kept per ray. PERF: the indices were reloaded
        // from the stack at every node; with the blend the AVX2 walk of 60,000 incoherent
        // bunny rays ran 603 instead of 669 instructions per ray (cachegrind), 1.00-1.04 of the
        // speed before (in one process, on the four peer scenes and three ray kinds).
        let (lo, hi) = (s.load(&bounds[a]), s.load(&bounds[a + 3]));
        let inv = r.inv_dir[a];
        let (near, far) = (s.select_sign(inv, hi, lo), s.select_sign(inv, lo, hi));
        let tn = s.mul(s.sub(near, r.origin[a]), inv);
        let tf = s.mul(s.sub(far, r.origin[a]), inv);
        t0 = s.max(tn, t0);
        t1 = s.min(tf, t1);
    }
    (s.le(t0, s.mul(t1, s.splat(SLAB_FAR_SCALE))), t0)
}

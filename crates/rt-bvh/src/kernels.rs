//! The wide layout's kernels: rt-simd's slab test and triangle tests, written once over the lane
//! width, applied to a [`WideNode`]'s eight children and a [`TriPack`]'s four triangles.
//!
//! Every lane performs the operations of the scalar function it mirrors
//! ([`rt_core::Aabb::intersect`], [`rt_core::Triangle::intersect_sheared`],
//! [`rt_core::moller_trumbore_edges`]) in the same order: no fused multiply-adds, IEEE
//! division, comparisons with the same NaN behaviour. So the results are the same bits on every
//! instruction set, and the tests compare them exactly.

use crate::node::{PACK, TriPack, WIDTH, WideNode};
use rt_core::{Ray, Shear};
use rt_simd::{Hits, Simd, SlabRay};

/// The lane operations the wide layout needs: eight lanes for a node's child boxes, four for a
/// pack's triangles.
pub(crate) trait Wide: Simd<4> + Simd<8> {}
impl<S: Simd<4> + Simd<8>> Wide for S {}

/// Four lanes of `S`.
pub(crate) type V4<S> = <S as Simd<4>>::V;
/// Eight lanes of `S`.
pub(crate) type V8<S> = <S as Simd<8>>::V;
/// What the slab test needs of a ray, in eight lanes.
pub(crate) type BoxRay<S> = SlabRay<V8<S>>;

/// What the kernels need of a ray, computed once per ray: broadcast into vectors where the
/// kernels use it lane-wise.
#[derive(Clone, Copy)]
pub(crate) struct RayData<S: Wide> {
    pub boxes: BoxRay<S>,
    pub shear: Shear,
    /// The origin along the shear's axes kx, ky, kz, the shear factors, and `t_min`, as
    /// four-lane vectors for the watertight test.
    pub o4: [V4<S>; 3],
    pub s4: [V4<S>; 3],
    /// The origin and direction along x, y, z, for Möller–Trumbore.
    pub origin4: [V4<S>; 3],
    pub dir4: [V4<S>; 3],
    pub t_min4: V4<S>,
}

/// The slab part of [`RayData`], for a ray's first box test.
#[inline(always)]
pub(crate) fn box_ray<S: Wide>(s: S, ray: &Ray) -> BoxRay<S> {
    SlabRay::new::<8, S>(s, ray)
}

impl<S: Wide> RayData<S> {
    /// The ray's data for the whole traversal, from its slab-test part.
    #[inline(always)]
    pub fn new(s: S, ray: &Ray, boxes: BoxRay<S>) -> Self {
        Self::with_shear(s, ray, boxes, Shear::new(ray.dir()))
    }

    /// [`RayData::new`] with the ray's shear computed already (a bundle keeps each lane's).
    #[inline(always)]
    pub fn with_shear(s: S, ray: &Ray, boxes: BoxRay<S>, shear: Shear) -> Self {
        let (o, d) = (ray.origin, ray.dir());
        let s4 = |x| Simd::<4>::splat(s, x);
        // An array, not the `Vec3`: glam indexes a `Vec3` by a runtime axis with a `match`,
        // branches that go either way for scattered rays. PERF: Intel Emerald Rapids, private
        // harness, three alternating runs, incoherent rays, Mrays/s: woody 12.16 11.83 12.29 ->
        // 12.58 12.71 12.72, the bunny 5.45 5.31 5.47 -> 5.59 5.51 5.58, the teapot 5.72 5.63
        // 5.84 -> 5.94 5.98 5.96; primary and shadow rays within ±1%.
        let oa = o.to_array();
        Self {
            boxes,
            shear,
            o4: [s4(oa[shear.kx]), s4(oa[shear.ky]), s4(oa[shear.kz])],
            s4: [s4(shear.sx), s4(shear.sy), s4(shear.sz)],
            origin4: [s4(o.x), s4(o.y), s4(o.z)],
            dir4: [s4(d.x), s4(d.y), s4(d.z)],
            t_min4: s4(ray.t_min),
        }
    }
}

/// The slab test of all eight children against `[t_min, t_max]` ([`rt_simd::slab`]): a bit
/// mask of the children entered and each child's entry distance.
#[inline(always)]
pub(crate) fn slab8<S: Wide>(s: S, node: &WideNode, r: &BoxRay<S>, t_max: f32) -> (u32, V8<S>) {
    rt_simd::slab::<8, S>(s, &node.bounds, r, t_max)
}

/// The watertight test ([`rt_simd::watertight`]) of the four triangles of a pack: a mask of
/// the lanes hit within `[t_min, t_max]`, and per lane `t`, `u`, `v`. Unused lanes hold NaN,
/// which is never hit.
#[inline(always)]
pub(crate) fn watertight4<S: Wide>(s: S, p: &TriPack, r: &RayData<S>, t_max: f32) -> Hits<V4<S>> {
    let Shear { kx, ky, kz, .. } = r.shear;
    let row = |k: usize| Simd::<4>::load(s, &p.rows[k]);
    let vertex = |v: usize| [row(3 * v + kx), row(3 * v + ky), row(3 * v + kz)];
    let t_max = Simd::<4>::splat(s, t_max);
    rt_simd::watertight::<4, S>(
        s,
        [vertex(0), vertex(1), vertex(2)],
        r.o4,
        r.s4,
        r.t_min4,
        t_max,
        0b1111,
    )
}

/// Möller–Trumbore ([`rt_simd::moller_trumbore`]) on the four triangles of a pack, from their
/// stored first vertex and edges. Unused lanes hold NaN and are rejected.
#[inline(always)]
pub(crate) fn moller_trumbore4<S: Wide>(
    s: S,
    p: &TriPack,
    r: &RayData<S>,
    t_max: f32,
) -> Hits<V4<S>> {
    let row = |k: usize| Simd::<4>::load(s, &p.rows[k]);
    let t_max = Simd::<4>::splat(s, t_max);
    rt_simd::moller_trumbore::<4, S>(
        s,
        [row(0), row(1), row(2)],
        [row(3), row(4), row(5)],
        [row(6), row(7), row(8)],
        r.origin4,
        r.dir4,
        r.t_min4,
        t_max,
    )
}

const _: () = assert!(WIDTH == 8 && PACK == 4);

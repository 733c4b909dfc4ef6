//! Triangles, with the Möller–Trumbore and the watertight ray–triangle tests.

use crate::{PrimHit, Ray, SurfacePoint};
use glam::{DVec3, Vec3};

crate::pod_struct! {
    /// A triangle given by its three vertices.
    ///
    /// As a [`Primitive`] it uses the watertight test ([`Triangle::intersect_watertight`], Woop,
    /// Benthin & Wald 2013). That is the default because it is the only one of the two that never
    /// lets a ray slip through the shared edge or vertex of two triangles, so the conformance kit
    /// can demand that every structure finds such hits. A test costs somewhat more than
    /// Möller–Trumbore's, and a BVH traces a few percent slower with it (`cargo bench -p
    /// rt-benches --bench primitives` and `--bench trace` measure both); wrap triangles in
    /// [`MtTriangle`] to use Möller–Trumbore instead.
    ///
    /// Zero-area triangles (and triangles with a non-finite vertex) are invalid: they never report a
    /// hit and structures leave them out.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Triangle {
        /// First vertex.
        pub v0: Vec3,
        /// Second vertex.
        pub v1: Vec3,
        /// Third vertex.
        pub v2: Vec3,
    }
}

const _: () = assert!(std::mem::size_of::<Triangle>() == 36);

impl Triangle {
    /// The triangle `(v0, v1, v2)`.
    #[inline]
    pub const fn new(v0: Vec3, v1: Vec3, v2: Vec3) -> Self {
        Self { v0, v1, v2 }
    }

    /// The (unnormalized) geometric normal `(v1 - v0) × (v2 - v0)`; its length is twice the area.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        (self.v1 - self.v0).cross(self.v2 - self.v0)
    }

    /// Möller–Trumbore (1997): solves `o + t·d = (1 - u - v)·v0 + u·v1 + v·v2` by Cramer's rule,
    /// reusing the cross products `p = d × e2` and `q = s × e1` for the determinant and all three
    /// unknowns.
    ///
    /// Fast, but not watertight: rounding can make a ray through a shared edge miss both
    /// triangles. Only an exactly zero determinant is rejected (no epsilon), so thin triangles are
    /// still hit.
    #[inline]
    pub fn intersect_moller_trumbore(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        moller_trumbore_edges(self.v0, self.v1 - self.v0, self.v2 - self.v0, ray, t_max)
    }

    /// The watertight test of Woop, Benthin & Wald (JCGT 2013).
    ///
    /// The vertices are translated to the ray origin and sheared so that the ray becomes the +z
    /// axis of the dominant direction component; the 2D edge functions `U`, `V`, `W` of the
    /// sheared triangle then decide the hit. Edges shared by two triangles produce the same edge
    /// function values with opposite signs in both, so a ray can never pass between them. If an
    /// edge function is exactly zero it is recomputed in `f64`, as the paper prescribes, so the
    /// sign decision is exact. Points on an edge count as inside.
    #[inline]
    pub fn intersect_watertight(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        self.intersect_sheared(&Shear::new(ray.dir()), ray, t_max)
    }

    /// [`Triangle::intersect_watertight`] with the ray's [`Shear`] computed beforehand (it
    /// depends on the ray only), for callers that test many triangles against one ray.
    #[inline]
    pub fn intersect_sheared(&self, shear: &Shear, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let Shear {
            kx,
            ky,
            kz,
            sx,
            sy,
            sz,
        } = *shear;
        // Arrays, not `Vec3`s: glam indexes a `Vec3` by a runtime axis with a `match`, two
        // branches per access, where an array takes one bounds check that the compiler can
        // share between the accesses with the same index. (PERF: cachegrind on 60 000 bunny rays,
        // instructions per ray: the kd-tree 1690 -> 1591 (primary rays), the octree 5257 -> 4782
        // and the binary BVH 2008 -> 1895 (incoherent rays), with 10-21% fewer branches.)
        let a = (self.v0 - ray.origin).to_array();
        let b = (self.v1 - ray.origin).to_array();
        let c = (self.v2 - ray.origin).to_array();
        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];

        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (
                ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
            );
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        // `!(det != 0)` also rejects NaN from non-finite input.
        if det == 0.0 || det.is_nan() {
            return None;
        }
        let az = sz * a[kz];
        let bz = sz * b[kz];
        let cz = sz * c[kz];
        let inv = 1.0 / det;
        let t = (u * az + v * bz + w * cz) * inv;
        if t >= ray.t_min && t <= t_max {
            Some(PrimHit {
                t,
                u: v * inv,
                v: w * inv,
            })
        } else {
            None
        }
    }

    /// The same geometry in double precision, for tests that need an exact-enough reference.
    pub fn to_f64(&self) -> [DVec3; 3] {
        [self.v0.as_dvec3(), self.v1.as_dvec3(), self.v2.as_dvec3()]
    }
}

/// Möller–Trumbore from the first vertex and the two edges `e1 = v1 - v0`, `e2 = v2 - v0`, which
/// [`Triangle::intersect_moller_trumbore`] computes per call and pre-processed triangles store:
/// both give the same answer, bit for bit, for the same edges.
#[inline]
pub fn moller_trumbore_edges(
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    ray: &Ray,
    t_max: f32,
) -> Option<PrimHit> {
    let p = ray.dir().cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.origin - v0;
    let u = s.dot(p) * inv;
    // `contains` is false for NaN, so non-finite input fails every test.
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir().dot(q) * inv;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(q) * inv;
    if t >= ray.t_min && t <= t_max {
        Some(PrimHit { t, u, v })
    } else {
        None
    }
}

/// The per-ray part of the watertight test: the axis permutation (`kz` is the dominant
/// direction axis; `kx`, `ky` are swapped when `dir[kz]` is negative so the triangle's winding is
/// preserved) and the shear that maps the ray onto the +z axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shear {
    /// The axis that becomes x.
    pub kx: usize,
    /// The axis that becomes y.
    pub ky: usize,
    /// The dominant axis, which becomes z.
    pub kz: usize,
    /// `dir[kx] / dir[kz]`.
    pub sx: f32,
    /// `dir[ky] / dir[kz]`.
    pub sy: f32,
    /// `1 / dir[kz]`.
    pub sz: f32,
}

impl Shear {
    /// The shear of a ray with direction `dir`.
    #[inline]
    pub fn new(dir: Vec3) -> Self {
        let a = dir.abs();
        // The largest component, x on ties with y or z and y on ties with z, chosen without
        // branches: for scattered rays they go either way. PERF: rt-bvh's wide walk, Intel
        // Emerald Rapids, private harness, three alternating runs, incoherent rays, Mrays/s:
        // woody 12.61 12.61 12.58 -> 13.17 13.24 13.32, the bunny 5.50 5.44 5.39 -> 5.58 5.62
        // 5.55, the teapot 6.00 5.99 5.88 -> 6.14 6.12 5.99, random soup 1.78 1.78 1.77 -> 1.83
        // 1.83 1.82; primary and shadow rays within ±1%. (A table lookup for kx and ky instead
        // of the shifts: primary rays 1% slower.)
        let (x_largest, y_over_z) = ((a.x >= a.y) & (a.x >= a.z), a.y >= a.z);
        let kz = usize::from(!x_largest) * (1 + usize::from(!y_over_z));
        // The next two axes after kz, cyclically: two bits per kz in a constant.
        let (kx, ky) = ((0b00_10_01 >> (2 * kz)) & 3, (0b01_00_10 >> (2 * kz)) & 3);
        // An array for the runtime axes, as in `intersect_sheared`.
        let d = dir.to_array();
        let (kx, ky) = if d[kz] < 0.0 { (ky, kx) } else { (kx, ky) };
        let sz = 1.0 / d[kz];
        Self {
            kx,
            ky,
            kz,
            sx: d[kx] * sz,
            sy: d[ky] * sz,
            sz,
        }
    }
}

impl Triangle {
    /// The [`SurfacePoint`] at barycentrics `u` (weight of `v1`) and `v` (weight of `v2`).
    #[inline]
    pub fn surface_at(&self, u: f32, v: f32) -> SurfacePoint {
        let magnitude = self
            .v0
            .abs()
            .max(self.v1.abs())
            .max(self.v2.abs())
            .max_element();
        SurfacePoint {
            point: (1.0 - u - v) * self.v0 + u * self.v1 + v * self.v2,
            normal: self.normal().normalize_or(Vec3::Z),
            error: crate::surface::error_bound(magnitude),
        }
    }
}

crate::pod_struct! {
    /// A [`Triangle`] intersected with Möller–Trumbore instead of the watertight test.
    ///
    /// Use it where speed matters more than closed edges; see [`Triangle`] for the trade-off.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct MtTriangle(pub Triangle);
}

impl MtTriangle {
    /// The triangle as the Möller–Trumbore test sees it: the first vertex and the edges to the
    /// others, each rounded to `f32` as the test computes them, added back (`v0 + (v1 - v0)`
    /// may differ from `v1` in the last bit). rt-bvh's packs keep only this form, so box
    /// overlap and clipping use it, and every structure stores the triangle under the same cells.
    #[inline]
    pub fn edge_form(&self) -> [Vec3; 3] {
        let Triangle { v0, v1, v2 } = self.0;
        [v0, v0 + (v1 - v0), v0 + (v2 - v0)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Primitive;
    use proptest::prelude::*;

    fn tri() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    #[test]
    fn both_tests_agree_on_a_simple_hit() {
        let r = Ray::new(Vec3::new(0.25, 0.5, 1.0), -Vec3::Z);
        let a = tri().intersect_moller_trumbore(&r, f32::INFINITY).unwrap();
        let b = tri().intersect_watertight(&r, f32::INFINITY).unwrap();
        assert_eq!(a.t, 1.0);
        assert!((a.t - b.t).abs() < 1e-6 && (a.u - b.u).abs() < 1e-6 && (a.v - b.v).abs() < 1e-6);
        assert!((a.u - 0.25).abs() < 1e-6 && (a.v - 0.5).abs() < 1e-6);
    }

    #[test]
    fn interval_is_inclusive_and_respected() {
        let r = Ray::with_interval(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z, 0.0, 1.0);
        assert!(tri().intersect(&r, 1.0).is_some());
        assert!(tri().intersect(&r, 0.999).is_none());
        let r = Ray::with_interval(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z, 1.001, 5.0);
        assert!(tri().intersect(&r, 5.0).is_none());
    }

    #[test]
    fn degenerate_and_non_finite_triangles_are_invalid_and_never_hit() {
        let r = Ray::new(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z);
        let point = Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        let line = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        let nan = Triangle::new(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y);
        for t in [point, line, nan] {
            assert!(!t.is_valid());
            assert!(t.intersect_watertight(&r, f32::INFINITY).is_none(), "{t:?}");
            assert!(
                t.intersect_moller_trumbore(&r, f32::INFINITY).is_none(),
                "{t:?}"
            );
        }
        assert!(tri().is_valid());
    }

    #[test]
    fn watertight_hits_shared_edge_and_vertex() {
        // A quad split along its diagonal; rays through points exactly on the diagonal, the
        // outer edges and the shared corners hit at least one of the two halves.
        let a = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::ONE.with_z(0.0));
        let b = Triangle::new(Vec3::ZERO, Vec3::ONE.with_z(0.0), Vec3::Y);
        for i in 0..=64 {
            let s = i as f32 / 64.0;
            let target = Vec3::new(s, s, 0.0);
            for o in [
                Vec3::new(0.3, -0.7, 2.0),
                Vec3::new(-1.0, 2.0, 0.5),
                Vec3::new(s, s, 1.0),
            ] {
                let r = Ray::new(o, target - o);
                let hit = a.intersect_watertight(&r, f32::INFINITY).is_some()
                    || b.intersect_watertight(&r, f32::INFINITY).is_some();
                assert!(hit, "ray {} slipped through the diagonal", r.to_rust());
            }
        }
    }

    proptest! {
        /// Rays aimed at random points on a random shared edge never slip through (watertight),
        /// whatever the origin.
        #[test]
        fn watertight_never_slips(
            p in prop::array::uniform3(-10.0f32..10.0),
            q in prop::array::uniform3(-10.0f32..10.0),
            r1 in prop::array::uniform3(-10.0f32..10.0),
            r2 in prop::array::uniform3(-10.0f32..10.0),
            o in prop::array::uniform3(-20.0f32..20.0),
            s in 0.0f32..=1.0,
        ) {
            let (p, q, r1, r2, o) = (Vec3::from(p), Vec3::from(q), Vec3::from(r1), Vec3::from(r2), Vec3::from(o));
            let a = Triangle::new(p, q, r1);
            // The second triangle shares edge pq and lies on the other side of it.
            let b = Triangle::new(q, p, r2);
            prop_assume!(a.is_valid() && b.is_valid());
            let target = p + s * (q - p);
            prop_assume!(target != o);
            let ray = Ray::new(o, target - o);
            // Only a ray that crosses the edge between the two triangles must hit: when both
            // triangles lie on the same side (a fold), the ray may graze the edge from outside.
            let n_a = a.normal();
            let n_b = b.normal();
            let side_a = (r1 - p).dot(ray.dir().cross(q - p));
            let side_b = (r2 - p).dot(ray.dir().cross(q - p));
            prop_assume!(side_a * side_b < 0.0 && n_a.dot(ray.dir()) * n_b.dot(ray.dir()) > 0.0);
            let hit = a.intersect_watertight(&ray, f32::INFINITY).is_some()
                || b.intersect_watertight(&ray, f32::INFINITY).is_some();
            prop_assert!(hit, "slipped: {}", ray.to_rust());
        }

        /// The two tests agree (within rounding) away from edges.
        #[test]
        fn tests_agree_in_the_interior(
            v in prop::array::uniform9(-10.0f32..10.0),
            o in prop::array::uniform3(-20.0f32..20.0),
            bary in (0.05f32..0.9, 0.05f32..0.9),
        ) {
            let t = Triangle::new(Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]), Vec3::new(v[6], v[7], v[8]));
            prop_assume!(t.normal().length() > 1.0);
            let (bu, bv) = bary;
            prop_assume!(bu + bv < 0.95);
            let target = (1.0 - bu - bv) * t.v0 + bu * t.v1 + bv * t.v2;
            let o = Vec3::from(o);
            let d = target - o;
            prop_assume!(d.length() > 0.5 && t.normal().normalize().dot(d.normalize()).abs() > 0.1);
            let ray = Ray::new(o, d);
            let a = t.intersect_moller_trumbore(&ray, f32::INFINITY);
            let b = t.intersect_watertight(&ray, f32::INFINITY);
            prop_assert!(a.is_some() && b.is_some());
            let (a, b) = (a.unwrap(), b.unwrap());
            prop_assert!((a.t - 1.0).abs() < 1e-3 && (b.t - 1.0).abs() < 1e-3);
            prop_assert!((a.u - bu).abs() < 1e-2 && (b.u - bu).abs() < 1e-2);
            prop_assert!((a.v - bv).abs() < 1e-2 && (b.v - bv).abs() < 1e-2);
        }
    }
}

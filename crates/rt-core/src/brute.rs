//! The O(N) reference every structure is checked against.

use crate::{
    Aabb, Accel, BallQuery, BoxQuery, BuildStats, Geometry, Primitive, Ray, RayQuery, Stats,
};
use glam::{Vec3, Vec4};

/// Tests every primitive for every ray and keeps the closest: the definition of the right answer.
///
/// The cost is one primitive test per valid primitive per ray; there is nothing to tune. A ray
/// first meets four primitives' boxes at a time, grown well past rounding, and
/// only the primitives whose boxes it meets are tested; the others cannot be hit, are counted
/// as tested, and are skipped. Every primitive is still considered for every ray, in index
/// order, so the answers are those of testing each one.
#[derive(Clone, Debug)]
pub struct BruteForce<P: Primitive> {
    pub(crate) prims: Vec<P>,
    pub(crate) ids: Vec<u32>,
    pub(crate) bounds: Aabb,
    /// The primitives' grown boxes, four to a pack, in the order of `prims`.
    culls: Vec<Culls>,
}

/// The grown boxes of four primitives, one coordinate of four boxes to a vector: a ray meets
/// all four with a few vector operations, where each primitive's own test costs several times
/// that.
///
/// A box is the primitive's [`bounds`](Primitive::bounds) grown on every side by
/// [`CULL_GROWTH`] times its largest coordinate in magnitude, and by as much again for the
/// ray's origin when a ray meets it ([`Culls::meets`]). A primitive's computed hit lies within
/// some tens of units in the last place of those magnitudes of the true one (a triangle hit
/// from ten million units away, on its edge, needs more than sixteen: the tests below fail
/// with a growth of `2⁻²⁰`), so a ray that misses the grown box cannot be reported hitting
/// the primitive. The structures cull with their boxes too, grown only along the ray, by
/// [`SLAB_FAR_SCALE`](crate::SLAB_FAR_SCALE). Slots past
/// the last primitive are never read.
// PERF: Intel Emerald Rapids, the sphereflake (82,002 triangles), `xtask compare -s bvh` in the
// test profile, 2 threads, two alternating runs, the brute-force row: 0.00129 and 0.00125
// Mrays/s testing every triangle, 0.00575 and 0.00682 with the culling. rt-bvh's conformance
// suite (test profile, CI=true): 59.5 and 69.9 s before, 52.4 and 63.9 s after.
#[derive(Clone, Copy, Debug)]
struct Culls {
    min: [Vec4; 3],
    max: [Vec4; 3],
}

/// How far a primitive's box and a ray's origin are grown for [`Culls`], relative to their
/// largest coordinate in magnitude: `2⁻¹⁴`, about a thousand units in the last place of an
/// `f32`.
const CULL_GROWTH: f32 = 1.0 / 16384.0;

impl Culls {
    const EMPTY: Self = Self {
        min: [Vec4::INFINITY; 3],
        max: [Vec4::NEG_INFINITY; 3],
    };

    /// The grown boxes of up to four primitives.
    fn of<P: Primitive>(prims: &[P]) -> Self {
        let mut c = Self::EMPTY;
        for (i, p) in prims.iter().enumerate() {
            let b = p.bounds();
            let grow = Vec3::splat(CULL_GROWTH * b.min.abs().max(b.max.abs()).max_element());
            let (lo, hi) = (b.min - grow, b.max + grow);
            for a in 0..3 {
                c.min[a][i] = lo[a];
                c.max[a][i] = hi[a];
            }
        }
        c
    }

    /// A bit per box that `ray` may meet within `[t_min, t_far]` (both also grown), from its
    /// origin grown by `grow` on every side; `ray`'s reciprocal direction must be finite.
    #[inline(always)]
    fn meets(&self, ray: &Ray, grow: f32, t_min: f32, t_far: f32) -> u32 {
        let mut near = Vec4::splat(t_min);
        let mut far = Vec4::splat(t_far);
        for a in 0..3 {
            let inv = Vec4::splat(ray.inv_dir()[a]);
            let o = ray.origin[a];
            // The box grown by `grow` as seen from the origin: `min - grow - o`, `max + grow - o`.
            let t0 = (self.min[a] - Vec4::splat(o + grow)) * inv;
            let t1 = (self.max[a] - Vec4::splat(o - grow)) * inv;
            near = near.max(t0.min(t1));
            far = far.min(t0.max(t1));
        }
        near.cmple(far).bitmask()
    }
}

impl<P: Primitive> BruteForce<P> {
    /// The valid primitives it keeps, in input order.
    pub fn prims(&self) -> &[P] {
        &self.prims
    }

    /// The input index of each primitive of [`prims`](BruteForce::prims), increasing.
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// The reference over primitives already filtered and numbered (a saved reference read
    /// back): `prims[i]` has input index `ids[i]`. Nothing is checked here; a loader checks
    /// that the primitives are valid and the indices increase before the reference answers.
    pub fn from_parts(prims: Vec<P>, ids: Vec<u32>) -> Self {
        let bounds = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(p.bounds()));
        let culls = prims.chunks(4).map(Culls::of).collect();
        Self {
            prims,
            ids,
            bounds,
            culls,
        }
    }

    /// Tests every valid primitive, in index order, until the query stops: what
    /// [`ray_query`](Accel::ray_query) answers, without skipping the primitives whose boxes
    /// the ray misses.
    pub(crate) fn test_all<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        for (p, &id) in self.prims.iter().zip(&self.ids) {
            if crate::leaf::offer_hit(p, id, ray, query, stats).is_break() {
                return;
            }
        }
    }
}

impl<P: Primitive> Accel for BruteForce<P> {
    type Prim = P;
    type Params = ();
    const NAME: &'static str = "brute-force";

    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }

    fn build(prims: &[P], _: &()) -> Self {
        Self::build_from(prims, &())
    }

    fn build_from<G: Geometry<Prim = P> + ?Sized>(geometry: &G, _: &()) -> Self {
        let (ids, prims): (Vec<u32>, Vec<P>) = (0..geometry.len().min(u32::MAX as usize))
            .map(|i| (i as u32, geometry.prim(i)))
            .filter(|(_, p)| p.is_valid())
            .unzip();
        Self::from_parts(prims, ids)
    }

    /// Tests every valid primitive whose grown box the ray meets, in index order,
    /// until the query stops; counts the others as tested.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        // Outside the precondition (NaN, huge origins, ...): no answer is meaningful.
        if !ray.is_valid() {
            return;
        }
        // A trace lists every test; a ray parallel to an axis (an infinite reciprocal) would
        // need the slab test's special cases: both test every primitive.
        if S::TRACE || !ray.inv_dir().is_finite() {
            self.test_all(ray, query, stats);
            return;
        }
        let grow = CULL_GROWTH * ray.origin.abs().max_element();
        let t_min = ray.t_min - ray.t_min * CULL_GROWTH;
        for (k, culls) in self.culls.iter().enumerate() {
            let t_far = query.t_far() + query.t_far() * CULL_GROWTH;
            let meets = culls.meets(ray, grow, t_min, t_far);
            let first = 4 * k;
            let last = self.prims.len().min(first + 4);
            for i in first..last {
                if meets & 1 << (i - first) == 0 {
                    stats.prim_test();
                } else if crate::leaf::offer_hit(&self.prims[i], self.ids[i], ray, query, stats)
                    .is_break()
                {
                    return;
                }
            }
        }
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Offers every valid primitive, in index order, pruning nothing (but an invalid query's
    /// negative radius).
    fn ball_query<Q: BallQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        if query.radius_sq() < 0.0 {
            return;
        }
        for (p, &id) in self.prims.iter().zip(&self.ids) {
            stats.prim_test();
            query.test(p, id);
        }
    }

    /// Tests every valid primitive, in index order, until the query stops: a primitive whose
    /// bounding box meets the query box is offered to the query, which decides; the others
    /// cannot meet it ([`Primitive::overlaps_box`] implies that their boxes meet) and are
    /// counted as tested without being offered.
    // PERF: with the bounding-box check first, brute force answers the bunny's box queries at
    // 0.00864 Mqueries/s against 0.00146 offering all 69,451 triangles (`cargo xtask compare
    // --query overlap --scene ../shared/meshes/stanford-bunny.obj -s bvh`, 2 threads).
    fn box_query<Q: BoxQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        let b = query.bounds();
        if b.is_empty() {
            return;
        }
        for (p, &id) in self.prims.iter().zip(&self.ids) {
            stats.prim_test();
            if p.bounds().overlaps(&b) && query.test(p, id).is_break() {
                return;
            }
        }
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.prims.capacity() * size_of::<P>()
            + self.ids.capacity() * 4
            + self.culls.capacity() * size_of::<Culls>()
    }

    fn build_stats(&self) -> BuildStats {
        BuildStats {
            nodes: 0,
            leaves: 1,
            empty_leaves: usize::from(self.prims.is_empty()),
            max_depth: 0,
            prim_refs: self.prims.len(),
            valid_prims: self.prims.len(),
            extra: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AllHits, AnyHit, ClosestHit, MtTriangle, NoStats, Rng, Sphere, Triangle};

    /// Rays that test the culling's edges: from near and far (origins up to `far` away, every
    /// octant, components as small as `1e-6` relative), aimed at each primitive's box corners
    /// and at random points, some with `t_min > 0` or a finite `t_max`.
    fn rays(rng: &mut Rng, targets: &[Vec3], far: f32, n: usize) -> Vec<Ray> {
        (0..n)
            .map(|i| {
                let origin = rng.unit_vector() * rng.range(0.0, far);
                let target = targets[rng.below(targets.len() as u32) as usize];
                let mut dir = if i % 5 == 4 {
                    rng.unit_vector()
                } else {
                    target - origin
                };
                if i % 7 == 3 {
                    // A component a million times smaller than the others: a huge reciprocal.
                    dir[rng.below(3) as usize] *= 1e-6;
                }
                match i % 4 {
                    1 => Ray::with_interval(origin, dir, rng.range(0.0, 1.0), f32::INFINITY),
                    2 => Ray::with_interval(origin, dir, 0.0, rng.range(0.5, 1.5)),
                    _ => Ray::new(origin, dir),
                }
            })
            .collect()
    }

    /// Every answer with the culling is the answer of testing every primitive: closest hit,
    /// any hit and all hits, for each ray.
    fn agrees<P: Primitive>(prims: &[P], rays: &[Ray]) -> usize {
        let brute = BruteForce::build(prims, &());
        let mut hits = 0;
        for ray in rays {
            let (mut culled, mut all) = (ClosestHit::new(ray), ClosestHit::new(ray));
            brute.ray_query(ray, &mut culled, &mut NoStats);
            brute.test_all(ray, &mut all, &mut NoStats);
            assert_eq!(culled.hit(), all.hit(), "{ray:?}");
            hits += usize::from(all.hit().is_some());
            let (mut culled, mut all) = (AnyHit::new(ray), AnyHit::new(ray));
            brute.ray_query(ray, &mut culled, &mut NoStats);
            brute.test_all(ray, &mut all, &mut NoStats);
            assert_eq!(culled.blocker(), all.blocker(), "{ray:?}");
            let (mut culled, mut all) = (AllHits::new(ray), AllHits::new(ray));
            brute.ray_query(ray, &mut culled, &mut NoStats);
            brute.test_all(ray, &mut all, &mut NoStats);
            assert_eq!(culled.hits(), all.hits(), "{ray:?}");
        }
        hits
    }

    /// A grid of triangles sharing edges and vertices (`n` by `n` squares of side `size`,
    /// shifted by `at`), each corner of each box a target.
    fn sheet(n: usize, size: f32, at: Vec3) -> (Vec<Triangle>, Vec<Vec3>) {
        let p = |i: usize, j: usize| {
            at + Vec3::new(i as f32, j as f32 * 0.5, (i * j) as f32 * 0.1) * size
        };
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..n {
                tris.push(Triangle::new(p(i, j), p(i + 1, j), p(i, j + 1)));
                tris.push(Triangle::new(p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)));
            }
        }
        let targets = tris
            .iter()
            .flat_map(|t| {
                [
                    t.v0,
                    t.v1,
                    t.v2,
                    (t.v0 + t.v1) * 0.5,
                    t.bounds().min,
                    t.bounds().max,
                ]
            })
            .collect();
        (tris, targets)
    }

    #[test]
    fn culling_answers_as_testing_every_triangle() {
        let mut rng = Rng::new(7);
        for (size, at, far) in [
            (1.0, Vec3::ZERO, 20.0),
            (1e-3, Vec3::splat(1e4), 1e5),
            (1e3, Vec3::new(-3e6, 1e6, 0.0), 1e7),
        ] {
            let (tris, targets) = sheet(9, size, at);
            let rays = rays(&mut rng, &targets, far, 4000);
            let hits = agrees(&tris, &rays);
            // Most rays are aimed at the sheet: the comparison is not over misses alone.
            assert!(hits > rays.len() / 3, "{hits} of {}", rays.len());
            let mt: Vec<MtTriangle> = tris.iter().map(|&t| MtTriangle(t)).collect();
            agrees(&mt, &rays);
        }
    }

    #[test]
    fn culling_answers_as_testing_every_sphere() {
        let mut rng = Rng::new(11);
        let spheres: Vec<Sphere> = (0..150)
            .map(|_| {
                let c = rng.in_box(Vec3::splat(-10.0), Vec3::splat(10.0));
                Sphere::new(c, rng.range(0.01, 2.0))
            })
            .collect();
        let targets: Vec<Vec3> = spheres
            .iter()
            .flat_map(|s| {
                [
                    s.center + Vec3::X * s.radius,
                    s.bounds().min,
                    s.bounds().max,
                ]
            })
            .collect();
        let rays = rays(&mut rng, &targets, 1e4, 4000);
        let hits = agrees(&spheres, &rays);
        assert!(hits > rays.len() / 3, "{hits} of {}", rays.len());
    }

    /// The culling does cull: a ray past every box skips every test, and one through the
    /// first square of the sheet tests its two triangles only (their boxes are the square's).
    #[test]
    fn a_ray_tests_only_the_primitives_whose_boxes_it_meets() {
        let (tris, _) = sheet(4, 1.0, Vec3::ZERO);
        let brute = BruteForce::build(&tris, &());
        let met = |ray: &Ray| -> u32 {
            brute
                .culls
                .iter()
                .map(|c| c.meets(ray, 0.0, ray.t_min, ray.t_max).count_ones())
                .sum()
        };
        assert_eq!(
            met(&Ray::new(
                Vec3::new(-5.0, -5.0, 10.0),
                Vec3::new(0.1, 0.2, 1.0)
            )),
            0
        );
        let centre = (tris[0].v0 + tris[0].v1 + tris[0].v2) / 3.0;
        let down = Ray::new(
            centre + Vec3::new(1e-3, 2e-3, 5.0),
            Vec3::new(-2e-4, -4e-4, -1.0),
        );
        assert_eq!(met(&down), 2);
        assert!(brute.intersect(&down).is_some_and(|h| h.prim == 0));
    }
}

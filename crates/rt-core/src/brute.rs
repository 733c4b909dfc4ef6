//! The O(N) reference every structure is checked against.

use crate::bundle::{Group, bundles_ray, for_each_bundle, octant};
use crate::lanes::Lanes;
use crate::{
    Aabb, Accel, BallQuery, BoxQuery, BuildStats, Geometry, Hit, Primitive, Ray, RayQuery, Stats,
};

/// Tests every primitive for every ray and keeps the closest: the definition of the right answer.
///
/// The cost is one primitive test per valid primitive per ray; there is nothing to tune.
#[derive(Clone, Debug)]
pub struct BruteForce<P: Primitive> {
    pub(crate) prims: Vec<P>,
    pub(crate) ids: Vec<u32>,
    pub(crate) bounds: Aabb,
}

impl<P: Primitive> BruteForce<P> {
    /// The bundle queries' loop: `answer(slot, hit)` for every ray of `rays` (with `ANY`,
    /// `Some` when the ray is blocked).
    fn bundles<S: Stats, const ANY: bool>(
        &self,
        rays: &[Ray],
        stats: &mut S,
        mut answer: impl FnMut(usize, Option<Hit>),
    ) {
        // Rays that cannot travel in a bundle go last, as `for_each_bundle` sends them singly
        // wherever they are.
        let key = |r: &Ray| {
            if bundles_ray(r) { octant(r) } else { 8 }
        };
        let mut order: Vec<u32> = (0..rays.len() as u32).collect();
        order.sort_by_key(|&i| key(&rays[i as usize]));
        let sorted: Vec<Ray> = order.iter().map(|&i| rays[i as usize]).collect();
        for_each_bundle(&sorted, |group| match group {
            Group::Single(k, ray) => {
                stats.single_ray();
                let hit = crate::bundle::single::<_, S, ANY>(self, ray, stats);
                answer(order[k] as usize, hit);
            }
            Group::Bundle(b) => {
                let mut lanes = Lanes::new(b);
                let mut live = b.all_lanes();
                for (p, &id) in self.prims.iter().zip(&self.ids) {
                    if ANY {
                        live &= !lanes.occluded(p, id, live, stats);
                        if live == 0 {
                            break;
                        }
                    } else {
                        lanes.intersect(p, id, live, stats);
                    }
                }
                for (i, &slot) in b.slot[..b.len()].iter().enumerate() {
                    let hit = if ANY {
                        (live >> i & 1 == 0).then_some(crate::bundle::BLOCKED)
                    } else {
                        lanes.hit(i)
                    };
                    answer(order[slot as usize] as usize, hit);
                }
            }
        });
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
        let bounds = prims
            .iter()
            .fold(Aabb::EMPTY, |b, p: &P| b.union(p.bounds()));
        Self { prims, ids, bounds }
    }

    /// Tests every valid primitive, in index order, until the query stops.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        // Outside the precondition (NaN, huge origins, ...): no answer is meaningful.
        if !ray.is_valid() {
            return;
        }
        for (p, &id) in self.prims.iter().zip(&self.ids) {
            if crate::leaf::offer_hit(p, id, ray, query, stats).is_break() {
                return;
            }
        }
    }

    /// Every primitive against a bundle's lanes at once ([`Lanes`], the watertight test over
    /// eight or sixteen lanes per vector step, each lane with its single ray's arithmetic), so
    /// each answer is the single-ray one, bit for bit. The rays are first put in order of
    /// their direction octant, whatever order they come in: brute force tests every
    /// primitive for every ray, so unlike a structure it gains from a full bundle whether or
    /// not its rays are coherent.
    fn intersect_bundle_with<S: Stats>(
        &self,
        rays: &[Ray],
        out: &mut [Option<Hit>],
        stats: &mut S,
    ) {
        let n = rays.len().min(out.len());
        self.bundles::<S, false>(&rays[..n], stats, |slot, hit| out[slot] = hit);
    }

    fn occluded_bundle_with<S: Stats>(&self, rays: &[Ray], out: &mut [bool], stats: &mut S) {
        let n = rays.len().min(out.len());
        self.bundles::<S, true>(&rays[..n], stats, |slot, hit| out[slot] = hit.is_some());
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
        size_of::<Self>() + self.prims.capacity() * size_of::<P>() + self.ids.capacity() * 4
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

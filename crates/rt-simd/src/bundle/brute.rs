//! Brute force with bundle queries: the reference that answers many rays fast.

use super::{Group, Lanes, bundles_ray, for_each_bundle, octant, single};
use rt_core::{
    Aabb, Accel, BallQuery, BoxQuery, BruteForce, BuildStats, Geometry, Hit, Primitive, Ray,
    RayQuery, Region, Stats,
};

/// [`BruteForce`] whose bundle queries test every primitive against a bundle's lanes at once
/// ([`Lanes`], the watertight test over eight or sixteen lanes per vector step, each lane with
/// its single ray's arithmetic), so each answer is the single-ray one, bit for bit. Every other
/// query is brute force's own.
///
/// The rays are first put in order of their direction octant, whatever order they come in:
/// brute force tests every primitive for every ray, so unlike a structure it gains from a full
/// bundle whether or not its rays are coherent. `compare` takes the reference answers of the
/// rays it checks from it.
// PERF: brute force alone, 2,000 (bunny) and 4,000 (teapot) random rays of the filled view, one
// thread, three passes: single rays 22.1-22.4 ns per ray-triangle test on the bunny and 15.5
// on the teapot; bundles 0.80-0.93 and 0.80-0.83, so 24-28x and 19x faster (commit daba1f1).
#[derive(Clone, Debug)]
pub struct BundledBruteForce<P: Primitive>(pub BruteForce<P>);

impl<P: Primitive> BundledBruteForce<P> {
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
        let (prims, ids) = (self.0.prims(), self.0.ids());
        for_each_bundle(&sorted, |group| match group {
            Group::Single(k, ray) => {
                stats.single_ray();
                let hit = single::<_, S, ANY>(&self.0, ray, stats);
                answer(order[k] as usize, hit);
            }
            Group::Bundle(b) => {
                let mut lanes = Lanes::new(b);
                let mut live = b.all_lanes();
                for (p, &id) in prims.iter().zip(ids) {
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
                        (live >> i & 1 == 0).then_some(super::BLOCKED)
                    } else {
                        lanes.hit(i)
                    };
                    answer(order[slot as usize] as usize, hit);
                }
            }
        });
    }
}

impl<P: Primitive> Accel for BundledBruteForce<P> {
    type Prim = P;
    type Params = ();
    const NAME: &'static str = BruteForce::<P>::NAME;

    fn presets() -> Vec<(&'static str, ())> {
        BruteForce::<P>::presets()
    }

    fn build(prims: &[P], params: &()) -> Self {
        Self(BruteForce::build(prims, params))
    }

    fn build_from<G: Geometry<Prim = P> + ?Sized>(geometry: &G, params: &()) -> Self {
        Self(BruteForce::build_from(geometry, params))
    }

    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        self.0.ray_query(ray, query, stats);
    }

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
        self.0.bounds()
    }

    fn ball_query<Q: BallQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.ball_query(query, stats);
    }

    fn box_query<Q: BoxQuery<P>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.0.box_query(query, stats);
    }

    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }

    fn build_stats(&self) -> BuildStats {
        self.0.build_stats()
    }

    fn regions(&self, visit: &mut dyn FnMut(Region)) {
        self.0.regions(visit);
    }
}

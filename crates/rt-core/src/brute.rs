//! The O(N) reference every structure is checked against.

use crate::{
    Aabb, Accel, BallQuery, BoxQuery, BuildStats, Geometry, Primitive, Ray, RayQuery, Stats,
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
        Self { prims, ids, bounds }
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

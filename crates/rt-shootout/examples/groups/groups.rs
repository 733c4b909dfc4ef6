//! A small structure of the kind a student writes first, for the shootout example and its test.

use rt_core::{Aabb, Accel, BallQuery, BuildStats, Primitive, Ray, RayQuery, Stats, Triangle};

/// A one-level hierarchy: triangles sorted along x in groups of 16, each group with its box; a
/// ray tests every group's box, then the triangles of the groups it enters.
pub struct Groups {
    /// The valid triangles with their input indices, sorted by centroid x.
    pub tris: Vec<(u32, Triangle)>,
    /// The box of each group of [`GROUP`] consecutive triangles.
    pub boxes: Vec<Aabb>,
}

/// Triangles per group.
pub const GROUP: usize = 16;

impl Accel for Groups {
    type Prim = Triangle;
    type Params = ();
    const NAME: &'static str = "groups";
    fn presets() -> Vec<(&'static str, ())> {
        vec![("default", ())]
    }
    fn build(prims: &[Triangle], _: &()) -> Self {
        let mut tris: Vec<(u32, Triangle)> = prims
            .iter()
            .enumerate()
            .filter(|(_, t)| t.is_valid())
            .map(|(i, t)| (i as u32, *t))
            .collect();
        tris.sort_by(|a, b| a.1.centroid().x.total_cmp(&b.1.centroid().x));
        let boxes = tris
            .chunks(GROUP)
            .map(|c| c.iter().fold(Aabb::EMPTY, |b, (_, t)| b.union(t.bounds())))
            .collect();
        Self { tris, boxes }
    }
    /// Offers the query every hit in the groups whose box the ray enters before its far end.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if !ray.is_valid() {
            return;
        }
        for (g, b) in self.boxes.iter().enumerate() {
            stats.node_visit();
            if b.intersect(ray, query.t_far()).is_none() {
                continue;
            }
            for &(id, t) in &self.tris[g * GROUP..((g + 1) * GROUP).min(self.tris.len())] {
                stats.prim_test();
                if let Some(h) = t.intersect(ray, query.t_far())
                    && query.offer(id, h).is_break()
                {
                    return;
                }
            }
        }
    }
    fn bounds(&self) -> Aabb {
        self.boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b))
    }
    /// Every group whose box the ball still reaches, in order.
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        for (g, b) in self.boxes.iter().enumerate() {
            if b.distance_squared(query.center()) > query.radius_sq() {
                continue;
            }
            stats.node_visit();
            for (id, t) in &self.tris[g * GROUP..((g + 1) * GROUP).min(self.tris.len())] {
                stats.prim_test();
                query.test(t, *id);
            }
        }
    }
    fn memory_bytes(&self) -> usize {
        self.tris.capacity() * size_of::<(u32, Triangle)>()
            + self.boxes.capacity() * size_of::<Aabb>()
    }
    fn build_stats(&self) -> BuildStats {
        BuildStats {
            nodes: self.boxes.len(),
            leaves: self.boxes.len(),
            prim_refs: self.tris.len(),
            valid_prims: self.tris.len(),
            max_depth: 0,
            ..BuildStats::default()
        }
    }
}

//! Two-level scenes: a binary BVH over the world boxes of instances of any structure.

use crate::{Bvh, BvhParams, Layout, MAX_DEPTH};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Accel, PrimHit, Primitive, Ray, SLAB_FAR_SCALE, Stack, Stats};
use rt_instance::{
    Instance, InstanceHit, InstancePointHit, InstancePointQuery, InstanceTransform,
    TransformPrimitive, TwoLevel,
};

/// A field of instances under one BVH: the top level of a two-level scene.
///
/// The top level is a binary BVH (the same builder, SAH over the instances' world boxes, one
/// instance per leaf) whose traversal, near child first, carries the ray into each instance it
/// reaches ([`Instance::intersect`]) and keeps the closest hit by [`InstanceHit::beats`]. Bottom
/// levels can be any structure and may differ from instance to instance; one built structure
/// can back any number of instances, since an [`Instance`] shares it through an `Arc`.
///
/// It answers exactly as [`LinearInstances`](rt_instance::LinearInstances) over the same instances
/// (see [`rt_instance::TwoLevel`] and the crate documentation of rt-instance for what that means against
/// the flattened world-space triangles).
///
/// ```
/// use rt_bvh::{Bvh, Instances};
/// use rt_core::{Accel, Ray, Triangle, glam::{Affine3A, Vec3}};
/// use rt_instance::{Instance, TwoLevel};
/// use std::sync::Arc;
/// let tri = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
/// let mesh = Arc::new(Bvh::build(&tri, &Default::default()));
/// let field: Vec<_> = (0..100u32)
///     .map(|i| {
///         let at = Affine3A::from_translation(Vec3::new(2.0 * i as f32, 0.0, 0.0));
///         Instance::new(mesh.clone(), at, 1000 + i).unwrap()
///     })
///     .collect();
/// let scene = Instances::build(field);
/// let hit = scene.intersect(&Ray::new(Vec3::new(6.2, 0.2, 5.0), -Vec3::Z)).unwrap();
/// assert_eq!((hit.instance, hit.id, hit.prim), (3, 1003, 0));
/// assert!((hit.t - 5.0).abs() < 1e-5);
/// ```
#[derive(Clone, Debug)]
pub struct Instances<P> {
    instances: Vec<Instance<P>>,
    top: Bvh<InstanceBox>,
    bounds: Aabb,
    reach: f32,
    condition: f32,
}

/// An instance's world box, as the top level's primitive.
#[derive(Clone, Copy, Debug)]
struct InstanceBox(Aabb);

impl Primitive for InstanceBox {
    fn bounds(&self) -> Aabb {
        self.0
    }
    fn is_valid(&self) -> bool {
        !self.0.is_empty() && self.0.min.is_finite() && self.0.max.is_finite()
    }
    /// Entering the box is a hit: the top level's tree is only ever walked by this module.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        self.0
            .intersect(ray, t_max)
            .map(|(t, _)| PrimHit { t, u: 0.0, v: 0.0 })
    }
    fn closest_point(&self, p: Vec3) -> Vec3 {
        p.clamp(self.0.min, self.0.max)
    }
}

impl<P: Primitive> Instances<P> {
    /// The parameters of the top level: binary nodes, binned SAH with a primitive test priced
    /// at 8 node visits (a visit to an instance transforms the ray and walks a whole bottom
    /// level), one instance per leaf.
    fn top_params() -> BvhParams {
        BvhParams {
            layout: Layout::Binary,
            intersection_cost: 8.0,
            max_leaf_size: 1,
            ..BvhParams::sah()
        }
    }

    /// Bytes of the top level alone: the instance records and the tree over them, without the
    /// bottom levels.
    pub fn top_level_bytes(&self) -> usize {
        size_of::<Self>()
            + self.instances.capacity() * size_of::<Instance<P>>()
            + self.top.memory_bytes()
    }
}

impl<P: Primitive> TwoLevel<P> for Instances<P> {
    const NAME: &'static str = "bvh";

    fn build(instances: Vec<Instance<P>>) -> Self {
        let boxes: Vec<InstanceBox> = instances
            .iter()
            .map(|i| InstanceBox(i.world_bounds()))
            .collect();
        let top = Bvh::build(&boxes, &Self::top_params());
        let (reach, condition) = rt_instance::scene_margins(&instances);
        Self {
            bounds: top.bounds(),
            instances,
            top,
            reach,
            condition,
        }
    }

    fn instances(&self) -> &[Instance<P>] {
        &self.instances
    }

    fn intersect_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> Option<InstanceHit> {
        self.walk::<S, false>(ray, stats)
    }

    fn occluded_with<S: Stats>(&self, ray: &Ray, stats: &mut S) -> bool {
        self.walk::<S, true>(ray, stats).is_some()
    }

    fn closest_point_with<S: Stats>(
        &self,
        point: Vec3,
        max_distance: f32,
        stats: &mut S,
    ) -> Option<InstancePointHit>
    where
        P: TransformPrimitive,
    {
        let mut query = InstancePointQuery::new(point, max_distance, self.reach, self.condition);
        let nodes = self.top.nodes();
        let ids = self.top.primitive_ids();
        if ids.is_empty() || nodes[0].bounds.distance_squared(point) > query.radius_sq() {
            return None;
        }
        let mut stack = Stack::<(u32, f32), MAX_DEPTH>::new();
        let mut current = 0usize;
        loop {
            stats.node_visit();
            let node = &nodes[current];
            if node.is_leaf() {
                for &k in &ids[node.prim_range()] {
                    self.instances[k as usize].ball_query(k, &mut query, stats);
                }
            } else {
                let (a, b) = (current + 1, node.index as usize);
                let da = nodes[a].bounds.distance_squared(point);
                let db = nodes[b].bounds.distance_squared(point);
                let (near, d_near, far, d_far) = if da <= db {
                    (a, da, b, db)
                } else {
                    (b, db, a, da)
                };
                if d_near <= query.radius_sq() {
                    if d_far <= query.radius_sq() {
                        stack.push((far as u32, d_far));
                    }
                    current = near;
                    continue;
                }
            }
            // The next pushed subtree still within the ball, which may have shrunk.
            loop {
                let Some((index, d)) = stack.pop() else {
                    return query.best().map(|h| InstancePointHit {
                        id: self.instances[h.instance as usize].id(),
                        ..h
                    });
                };
                if d <= query.radius_sq() {
                    current = index as usize;
                    break;
                }
            }
        }
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn memory_bytes(&self) -> usize {
        self.top_level_bytes() + rt_instance::bottom_bytes(&self.instances)
    }
}

impl<P: Primitive> Instances<P> {
    /// The top-level walk, near child first. `ANY = false` finds the closest hit; `ANY = true`
    /// returns at the first instance that blocks the ray (its hit fields then mean nothing).
    ///
    /// Node boxes are tested grown by [`InstanceTransform::ray_pad`], so no instance holding a
    /// hit is culled by the rounding of the ray's transform into its space.
    fn walk<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Option<InstanceHit> {
        let nodes = self.top.nodes();
        let ids = self.top.primitive_ids();
        if !ray.is_valid() || ids.is_empty() {
            return None;
        }
        let pad = InstanceTransform::ray_pad(ray, self.condition, self.reach);
        let mut best = InstanceHit {
            instance: u32::MAX,
            id: 0,
            prim: u32::MAX,
            t: ray.t_max,
            u: 0.0,
            v: 0.0,
        };
        nodes[0].bounds.padded(pad).intersect(ray, best.t)?;
        let mut stack = Stack::<(u32, f32), MAX_DEPTH>::new();
        let mut current = 0usize;
        loop {
            stats.node_visit();
            let node = &nodes[current];
            if node.is_leaf() {
                for &k in &ids[node.prim_range()] {
                    let inst = &self.instances[k as usize];
                    if ANY {
                        if inst.occluded_with(ray, stats) {
                            return Some(InstanceHit {
                                instance: k,
                                ..best
                            });
                        }
                        continue;
                    }
                    if let Some(h) = inst.intersect_with(ray, best.t, stats)
                        && InstanceHit::beats(h.t, k, h.prim, &best)
                    {
                        best = InstanceHit {
                            instance: k,
                            id: inst.id(),
                            prim: h.prim,
                            t: h.t,
                            u: h.u,
                            v: h.v,
                        };
                    }
                }
            } else {
                let (a, b) = (current + 1, node.index as usize);
                let ta = nodes[a].bounds.padded(pad).entry(ray, best.t);
                let tb = nodes[b].bounds.padded(pad).entry(ray, best.t);
                let (near, t_near, far, t_far) = if ta <= tb {
                    (a, ta, b, tb)
                } else {
                    (b, tb, a, ta)
                };
                if t_near != f32::INFINITY {
                    if t_far != f32::INFINITY {
                        stack.push((far as u32, t_far));
                    }
                    current = near;
                    continue;
                }
            }
            loop {
                let Some((index, t_entry)) = stack.pop() else {
                    return (best.instance != u32::MAX).then_some(best);
                };
                if ANY || t_entry <= best.t * SLAB_FAR_SCALE {
                    current = index as usize;
                    break;
                }
            }
        }
    }
}

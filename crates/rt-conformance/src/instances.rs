//! The kit for two-level scenes ([`TwoLevel`]): exactness against [`LinearInstances`], and
//! fidelity to the flattened world-space triangles within the rounding the transforms allow.

use super::{STALL_LIMIT, proptest_failure, scene, scene_points, stall_stops_shrinking};
use glam::{Affine3A, Quat, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use rt_core::{Accel, BruteForce, Counters, DynAccel, Hit, Primitive, Ray, Rng, Triangle};
use rt_instance::{
    Instance, InstanceHit, InstancePointHit, LinearInstances, TwoLevel, scene_margins,
};
use std::collections::HashMap;
use std::sync::Arc;

/// Builds a bottom level over triangles: how the kit is told which structures to put under
/// the instances (`|t| Arc::new(KdTree::build(t, &Default::default()))`, say).
pub type BottomBuilder = fn(&[Triangle]) -> Arc<dyn DynAccel<Triangle>>;

/// One instance of a case: which mesh, built by which of the kit's bottom builders, placed by
/// which transform, with which id.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// Index into [`InstancedCase::meshes`].
    pub mesh: usize,
    /// Index into the bottom builders the kit was given (taken modulo their number).
    pub bottom: usize,
    /// Object space to world.
    pub to_world: Affine3A,
    /// The instance's id.
    pub id: u32,
}

/// A two-level scene and the rays that probe it.
#[derive(Clone, Debug)]
pub struct InstancedCase {
    /// The meshes instances refer to.
    pub meshes: Vec<Vec<Triangle>>,
    /// The instances, in index order.
    pub placements: Vec<Placement>,
    /// Rays to compare on (closest-point queries are drawn from the world triangles and the
    /// rays' origins, as [`scene_points`] does).
    pub rays: Vec<Ray>,
}

impl InstancedCase {
    /// The world-space triangles, instance after instance, and for each its instance and
    /// primitive index. A triangle that is invalid in object space (degenerate or not finite) is
    /// left invalid (NaN), since instances decide validity there: rounding could otherwise turn
    /// three collinear vertices into a sliver in the world.
    pub fn flattened(&self) -> (Vec<Triangle>, Vec<(u32, u32)>) {
        let mut tris = Vec::new();
        let mut ids = Vec::new();
        for (k, p) in self.placements.iter().enumerate() {
            for (i, t) in self.meshes[p.mesh].iter().enumerate() {
                let w = |v: Vec3| p.to_world.transform_point3(v);
                tris.push(if t.is_valid() {
                    Triangle::new(w(t.v0), w(t.v1), w(t.v2))
                } else {
                    Triangle::new(Vec3::NAN, Vec3::NAN, Vec3::NAN)
                });
                ids.push((k as u32, i as u32));
            }
        }
        (tris, ids)
    }
}

/// Names of the fixed two-level scenes, in the order [`two_level_scene`] knows them: each of
/// the one-level adversarial scenes ([`super::SCENES`]) as one instance under the identity
/// transform (`identity:NAME`), then fields that mix mirrored, non-uniformly scaled,
/// rotated and exactly coinciding instances.
pub const TWO_LEVEL_SCENES: &[&str] = &[
    "identity",
    "coinciding_instances",
    "mirrored_and_scaled",
    "far_field",
];

/// The fixed two-level scene called `name` (one of [`TWO_LEVEL_SCENES`]; `identity` holds
/// every one-level adversarial scene, one after the other, and `check_two_level_scene` runs
/// them as separate cases).
///
/// # Panics
/// If `name` is not in [`TWO_LEVEL_SCENES`].
pub fn two_level_scene(name: &str) -> Vec<InstancedCase> {
    let mut rng = Rng::new(7);
    match name {
        "identity" => super::SCENES
            .iter()
            .map(|s| {
                let s = scene(s);
                InstancedCase {
                    meshes: vec![s.triangles],
                    placements: vec![Placement {
                        mesh: 0,
                        bottom: 0,
                        to_world: Affine3A::IDENTITY,
                        id: 0,
                    }],
                    rays: s.rays,
                }
            })
            .collect(),
        "coinciding_instances" => {
            // Three instances in the same place (exact ties between instances), and two that
            // overlap them half way.
            let mesh = super::lattice_triangles(3, 30);
            let at = Affine3A::from_rotation_y(0.5);
            let shifted = Affine3A::from_translation(Vec3::new(0.5, 0.0, 0.0)) * at;
            let placements: Vec<Placement> = [at, at, at, shifted, shifted]
                .iter()
                .enumerate()
                .map(|(k, &to_world)| Placement {
                    mesh: 0,
                    bottom: k,
                    to_world,
                    id: 100 + k as u32,
                })
                .collect();
            let rays = aimed(
                &mut rng,
                std::slice::from_ref(&mesh),
                &placements_of(&placements),
                600,
            );
            vec![InstancedCase {
                meshes: vec![mesh],
                placements,
                rays,
            }]
        }
        "mirrored_and_scaled" => {
            let mesh = super::lattice_triangles(4, 40);
            let transforms = [
                Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
                Affine3A::from_scale(Vec3::new(4.0, 1.0, 0.25)),
                Affine3A::from_scale_rotation_translation(
                    Vec3::new(1.0, -3.0, 0.5),
                    Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
                    Vec3::new(3.0, -2.0, 1.0),
                ),
                Affine3A::from_cols_array(&[
                    1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -4.0, 0.0, 0.0,
                ]), // a shear
            ];
            let placements: Vec<Placement> = transforms
                .iter()
                .enumerate()
                .map(|(k, &to_world)| Placement {
                    mesh: 0,
                    bottom: k,
                    to_world,
                    id: k as u32,
                })
                .collect();
            let rays = aimed(
                &mut rng,
                std::slice::from_ref(&mesh),
                &placements_of(&placements),
                800,
            );
            vec![InstancedCase {
                meshes: vec![mesh],
                placements,
                rays,
            }]
        }
        "far_field" => {
            // Instances a thousand units out, seen from the origin and from beside them.
            let meshes = vec![
                super::small_triangles(5, 20, 0.3),
                super::lattice_triangles(6, 20),
            ];
            let placements: Vec<Placement> = (0..24)
                .map(|k| Placement {
                    mesh: k % 2,
                    bottom: k,
                    to_world: Affine3A::from_scale_rotation_translation(
                        Vec3::splat(0.5 + (k % 3) as f32),
                        Quat::from_rotation_z(k as f32),
                        Vec3::new(1000.0 + 3.0 * (k / 4) as f32, 3.0 * (k % 4) as f32, 0.0),
                    ),
                    id: k as u32,
                })
                .collect();
            let rays = aimed(&mut rng, &meshes, &placements_of(&placements), 800);
            vec![InstancedCase {
                meshes,
                placements,
                rays,
            }]
        }
        _ => panic!("unknown two-level scene `{name}`; see rt_conformance::TWO_LEVEL_SCENES"),
    }
}

fn placements_of(p: &[Placement]) -> Vec<(usize, Affine3A)> {
    p.iter().map(|p| (p.mesh, p.to_world)).collect()
}

/// `n` rays: half from random points of the field's box grown by half towards a vertex, edge
/// midpoint or centroid of a random instanced triangle, the others from the origin's side in
/// random directions; every fourth with a finite `t_max`.
fn aimed(rng: &mut Rng, meshes: &[Vec<Triangle>], at: &[(usize, Affine3A)], n: usize) -> Vec<Ray> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for &(m, xf) in at {
        for t in &meshes[m] {
            for v in [t.v0, t.v1, t.v2] {
                let w = xf.transform_point3(v);
                if w.is_finite() {
                    lo = lo.min(w);
                    hi = hi.max(w);
                }
            }
        }
    }
    if !(lo.cmple(hi).all()) {
        (lo, hi) = (Vec3::splat(-1.0), Vec3::ONE);
    }
    let grow = (hi - lo) * 0.5 + Vec3::ONE;
    let (lo, hi) = (lo - grow, hi + grow);
    (0..n)
        .map(|i| {
            let o = rng.in_box(lo, hi);
            let dir = if i % 2 == 0 && !at.is_empty() {
                let (m, xf) = at[rng.below(at.len() as u32) as usize];
                if meshes[m].is_empty() {
                    rng.unit_vector()
                } else {
                    let t = meshes[m][rng.below(meshes[m].len() as u32) as usize];
                    let target = match rng.below(3) {
                        0 => t.v0,
                        1 => 0.5 * (t.v0 + t.v1),
                        _ => (t.v0 + t.v1 + t.v2) / 3.0,
                    };
                    xf.transform_point3(target) - o
                }
            } else {
                rng.unit_vector()
            };
            let t_max = if i % 4 == 3 {
                rng.range(0.5, 20.0)
            } else {
                f32::INFINITY
            };
            Ray::with_interval(o, dir, 0.0, t_max)
        })
        .collect()
}

/// Checks two-level scene type `T` on the named fixed scene ([`TWO_LEVEL_SCENES`]), with bottom
/// levels from `bottoms` (instance `k` gets `bottoms[k % len]`, so several kinds mix).
///
/// # Panics
/// With the first disagreement.
pub fn check_two_level_scene<T: TwoLevel<Triangle> + 'static>(
    bottoms: &[BottomBuilder],
    name: &str,
) {
    for (i, case) in two_level_scene(name).iter().enumerate() {
        if let Err(e) = check_two_level_case::<T>(bottoms, case) {
            let which = if name == "identity" {
                format!("identity:{}", super::SCENES[i])
            } else {
                name.to_string()
            };
            panic!("two-level conformance scene `{which}` failed: {e}");
        }
    }
}

/// Checks one case: `T` against [`LinearInstances`] with brute-force bottom levels, exactly,
/// for closest hits, any hits and closest points (counted and uncounted); and both against the
/// flattened world-space triangles within the rounding of the transforms (see the `instance`
/// module of rt-core): `t` within `E / |cos θ|` plus a relative `1e-5` on the same triangle,
/// another triangle (or a miss) only where the nearer hit lies within `E / |cos θ|` of an edge
/// or of an end of the ray's interval, and closest-point distances within `E` plus a relative
/// `1e-5`, where `E = 2⁻¹⁸ · condition · (|origin|∞ + reach)` ([`scene_margins`]) and `θ` is
/// the angle between the ray and the triangle's normal.
///
/// # Errors
/// A description of the first disagreement, naming the ray or point.
pub fn check_two_level_case<T: TwoLevel<Triangle> + 'static>(
    bottoms: &[BottomBuilder],
    case: &InstancedCase,
) -> Result<(), String> {
    if bottoms.is_empty() {
        return Err("the kit needs at least one bottom-level builder".into());
    }
    let (bottoms, case) = (bottoms.to_vec(), case.clone());
    let small =
        case.meshes.iter().map(Vec::len).sum::<usize>() <= 24 && case.placements.len() <= 12;
    let summary = if small {
        format!(
            "\n  meshes: {:?}\n  placements: {:?}",
            case.meshes, case.placements
        )
    } else {
        format!(
            "\n  case: {} meshes, {} instances",
            case.meshes.len(),
            case.placements.len()
        )
    };
    let shown = summary.clone();
    super::watched(T::NAME, STALL_LIMIT, &shown, move |probe| {
        probe.building(case.placements.len());
        let mut built: HashMap<(usize, usize), Arc<dyn DynAccel<Triangle>>> = HashMap::new();
        let mut reference_bottoms: HashMap<usize, Arc<dyn DynAccel<Triangle>>> = HashMap::new();
        let mut instances = Vec::new();
        let mut reference = Vec::new();
        for p in &case.placements {
            let b = p.bottom % bottoms.len();
            let mesh = &case.meshes[p.mesh];
            let bottom = built
                .entry((p.mesh, b))
                .or_insert_with(|| bottoms[b](mesh))
                .clone();
            let brute = reference_bottoms
                .entry(p.mesh)
                .or_insert_with(|| Arc::new(BruteForce::build(mesh, &())))
                .clone();
            let make = |bottom| {
                Instance::new(bottom, p.to_world, p.id).map_err(|e| format!("placement {p:?}: {e}"))
            };
            instances.push(make(bottom)?);
            reference.push(make(brute)?);
        }
        let scene = T::build(instances);
        let linear = LinearInstances::build(reference);
        probe.checking();
        let (world, ids) = case.flattened();
        let flat = BruteForce::build(&world, &());
        let (reach, condition) = scene_margins(linear.instances());
        let margin = |p: Vec3| condition * (p.abs().max_element() + reach) / 262_144.0;
        let name = T::NAME;
        let fail = |m: String| format!("{m}{summary}");

        for ray in &case.rays {
            probe.tracing(ray);
            let expected = linear.intersect(ray);
            let got = scene.intersect(ray);
            let mut counters = Counters::default();
            let counted = scene.intersect_with(ray, &mut counters);
            if !(InstanceHit::agree(expected, got) && expected.map(|h| h.id) == got.map(|h| h.id)) {
                return Err(format!(
                    "{name}: intersect disagrees with the linear reference\n  ray: {}\n  expected: {expected:?}\n  got:      {got:?}",
                    ray.to_rust()
                ));
            }
            if counted != got {
                return Err(format!(
                    "{name}: intersect_with(Counters) answered {counted:?} but intersect {got:?}\n  ray: {}",
                    ray.to_rust()
                ));
            }
            let occluded = scene.occluded(ray);
            if occluded != expected.is_some() || scene.occluded_with(ray, &mut counters) != occluded
            {
                return Err(format!(
                    "{name}: occluded is {occluded} but the closest hit is {expected:?}\n  ray: {}",
                    ray.to_rust()
                ));
            }
            let flat_hit = flat.intersect(ray).map(|h| {
                let (instance, prim) = ids[h.prim as usize];
                (instance, prim, h)
            });
            faithful(ray, expected, flat_hit, &world, &ids, margin(ray.origin)).map_err(|m| {
                fail(format!(
                    "{name}: {m}\n  ray: {}\n  two-level: {expected:?}\n  flattened: {flat_hit:?}",
                    ray.to_rust()
                ))
            })?;
        }
        let coherent = coherent_rays(scene.bounds());
        for rays in [&case.rays, &coherent] {
            check_bundles(&scene, rays)?;
            check_batches(&scene, rays)?;
        }
        for (p, max) in scene_points(&world, &case.rays) {
            probe.set(super::Doing::Point(p, max));
            let expected = linear.closest_point(p, max);
            let got = scene.closest_point(p, max);
            let mut counters = Counters::default();
            let counted = scene.closest_point_with(p, max, &mut counters);
            if !(InstancePointHit::agree(expected, got)
                && expected.map(|h| h.id) == got.map(|h| h.id))
                || counted != got
            {
                return Err(format!(
                    "{name}: closest_point(Vec3::new({:?}, {:?}, {:?}), {max:?}) disagrees with the linear reference\n  expected: {expected:?}\n  got:      {got:?}\n  counted:  {counted:?}",
                    p.x, p.y, p.z
                ));
            }
            let flat_point = flat.closest_point(p, max);
            let near_limit = |d: f32| max.is_finite() && (d - max).abs() <= margin(p) + 1e-5 * max;
            let close = match (expected, flat_point) {
                (None, None) => true,
                (Some(a), Some(b)) => {
                    (a.distance - b.distance).abs() <= margin(p) + 1e-5 * b.distance
                }
                // A limit that one side's rounding puts its answer just beyond.
                (Some(a), None) => near_limit(a.distance),
                (None, Some(b)) => near_limit(b.distance),
            };
            if !close {
                return Err(format!(
                    "{name}: closest_point(Vec3::new({:?}, {:?}, {:?}), {max:?}) is farther from the flattened scene's than rounding allows\n  two-level: {expected:?}\n  flattened: {flat_point:?}",
                    p.x, p.y, p.z
                ));
            }
        }
        Ok(())
    })
}

/// The batch queries ([`TwoLevel::intersect_batch`], [`TwoLevel::occluded_batch`]) against the
/// single ones, the same bits in every slot: over the case's rays as they come, reversed, and
/// cut to the first 0, 1, 255, 256 and 257 (a batch's chunk is 256 rays).
fn check_batches<T: TwoLevel<Triangle>>(scene: &T, rays: &[Ray]) -> Result<(), String> {
    let reversed: Vec<Ray> = rays.iter().rev().copied().collect();
    let mut lists: Vec<&[Ray]> = vec![rays, &reversed];
    for n in [0, 1, 255, 256, 257] {
        lists.push(&rays[..n.min(rays.len())]);
    }
    let bits = |h: Option<InstanceHit>| {
        h.map(|h| (h.instance, h.id, h.prim, [h.t, h.u, h.v].map(f32::to_bits)))
    };
    for list in lists {
        let mut hits = vec![None; list.len()];
        scene.intersect_batch(list, &mut hits);
        let mut blocked = vec![false; list.len()];
        scene.occluded_batch(list, &mut blocked);
        for ((ray, &hit), &blocked) in list.iter().zip(&hits).zip(&blocked) {
            let single = scene.intersect(ray);
            if bits(hit) != bits(single) || blocked != scene.occluded(ray) {
                return Err(format!(
                    "{}: a batch of {} rays answered {hit:?} (blocked: {blocked}) where the single queries answer {single:?} (blocked: {})\n  ray: {}",
                    T::NAME,
                    list.len(),
                    scene.occluded(ray),
                    ray.to_rust()
                ));
            }
        }
    }
    Ok(())
}

/// The bundle and stream queries ([`TwoLevel::intersect_bundle_with`],
/// [`TwoLevel::intersect_stream_with`] and their any-hit forms) against the single ones, the
/// same bits in every slot: in every order of [`bundle_orders`](crate::bundle_orders), in
/// slices whose lengths cycle through [`BUNDLE_SIZES`](crate::BUNDLE_SIZES) (counted and
/// uncounted in turn) and in streams whose lengths cycle through
/// [`STREAM_SIZES`](crate::STREAM_SIZES).
fn check_bundles<T: TwoLevel<Triangle>>(scene: &T, rays: &[Ray]) -> Result<(), String> {
    let bits = |h: Option<InstanceHit>| {
        h.map(|h| (h.instance, h.id, h.prim, [h.t, h.u, h.v].map(f32::to_bits)))
    };
    for (order, rays) in crate::bundle_orders(rays, 0x5eed_1257) {
        let single: Vec<_> = rays.iter().map(|r| scene.intersect(r)).collect();
        let blocked: Vec<bool> = rays.iter().map(|r| scene.occluded(r)).collect();
        let mut streams = Vec::new();
        let mut start = 0;
        for &size in crate::STREAM_SIZES.iter().cycle() {
            if start >= rays.len() {
                break;
            }
            streams.push(start..(start + size).min(rays.len()));
            start += size;
        }
        let mut slices = crate::bundles::cycled_slices(rays.len(), false);
        slices.extend(crate::bundles::cycled_slices(rays.len(), true));
        let kinds = slices
            .iter()
            .map(|_| "bundle")
            .chain(streams.iter().map(|_| "stream"));
        for (i, (kind, range)) in kinds.zip(slices.iter().chain(&streams)).enumerate() {
            let chunk = &rays[range.clone()];
            let mut hits = vec![None; chunk.len()];
            let mut occluded = vec![false; chunk.len()];
            let mut counters = Counters::default();
            match (kind, i % 2 == 0) {
                ("bundle", true) => {
                    scene.intersect_bundle(chunk, &mut hits);
                    scene.occluded_bundle(chunk, &mut occluded);
                }
                ("bundle", false) => {
                    scene.intersect_bundle_with(chunk, &mut hits, &mut counters);
                    scene.occluded_bundle_with(chunk, &mut occluded, &mut counters);
                }
                (_, true) => {
                    scene.intersect_stream(chunk, &mut hits);
                    scene.occluded_stream(chunk, &mut occluded);
                }
                (_, false) => {
                    scene.intersect_stream_with(chunk, &mut hits, &mut counters);
                    scene.occluded_stream_with(chunk, &mut occluded, &mut counters);
                }
            }
            let expected = single[range.clone()].iter().zip(&blocked[range.clone()]);
            for (k, ((hit, o), (s, b))) in hits.iter().zip(&occluded).zip(expected).enumerate() {
                if bits(*hit) != bits(*s) || o != b {
                    return Err(format!(
                        "{}: a {kind} of {} rays (rays {order}) answered {hit:?} (blocked: {o}) in slot {k} where the single queries answer {s:?} (blocked: {b})\n  ray: {}",
                        T::NAME,
                        chunk.len(),
                        chunk[k].to_rust()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Rays that travel together through a scene with box `b`, in runs of 64: a pinhole camera's
/// 16 × 16 rays in 8 × 8 tiles, a parallel projection's 8 × 8, and shadow rays from an 8 × 8
/// grid of points across the box toward one light above it, each ending at the light. None for
/// an empty box.
// PERF: rt-bvh's two-level tests (`cargo test -p rt-bvh --test suite instances`) took 9.8 s
// without these rays and 12.1 s with them; with 24 × 24, 16 × 16 and 16 × 16 rays (and a
// top-level walk of their own), 25 s: the random cases, each checked on them, took most.
fn coherent_rays(b: rt_core::Aabb) -> Vec<Ray> {
    if b.is_empty() || !b.min.is_finite() || !b.max.is_finite() {
        return Vec::new();
    }
    let (center, extent) = (
        (b.min + b.max) * 0.5,
        (b.max - b.min).max(Vec3::splat(1e-3)),
    );
    let size = extent.length();
    let eye = center + Vec3::new(0.4, 0.7, 1.0).normalize() * 1.5 * size;
    let toward = (center - eye).normalize();
    let right = toward.cross(Vec3::Y).normalize();
    let up = right.cross(toward);
    let mut rays = Vec::new();
    // The pixels of an `n` × `n` image, tile by tile, as `(u, v)` in [-0.5, 0.5].
    let tiles = |n: usize| {
        (0..n / 8).flat_map(move |ty| {
            (0..n / 8).flat_map(move |tx| {
                (0..64).map(move |i| {
                    let (x, y) = (tx * 8 + i % 8, ty * 8 + i / 8);
                    (
                        (x as f32 + 0.5) / n as f32 - 0.5,
                        (y as f32 + 0.5) / n as f32 - 0.5,
                    )
                })
            })
        })
    };
    for (u, v) in tiles(16) {
        rays.push(Ray::new(eye, toward + (u * right + v * up) * 0.8));
    }
    for (u, v) in tiles(8) {
        rays.push(Ray::new(eye + (u * right + v * up) * size, toward));
    }
    let light = center + Vec3::new(0.2, 1.0, 0.1) * size;
    for (u, v) in tiles(8) {
        let p = center + Vec3::new(u * extent.x, 0.0, v * extent.z);
        rays.push(Ray::with_interval(p, light - p, 1e-4, 1.0));
    }
    rays
}

/// Whether the two-level answer `got` matches the flattened scene's `flat` within the rounding
/// of the transforms (`e`: the world-space error bound for this ray; see
/// [`check_two_level_case`]).
fn faithful(
    ray: &Ray,
    got: Option<InstanceHit>,
    flat: Option<(u32, u32, Hit)>,
    world: &[Triangle],
    ids: &[(u32, u32)],
    e: f32,
) -> Result<(), String> {
    let index = |instance: u32, prim: u32| {
        ids.iter()
            .position(|&k| k == (instance, prim))
            .expect("every hit names a flattened triangle")
    };
    let len = ray.dir().length();
    // The world-space slack of a hit on triangle `i` at `t`, as a distance along its plane.
    let slack = |i: usize| {
        let n = world[i].normal().normalize_or_zero();
        let cos = (ray.dir().dot(n) / len).abs().max(1e-6);
        e / cos
    };
    match (got, flat) {
        (None, None) => Ok(()),
        (Some(g), Some((instance, prim, f))) if (g.instance, g.prim) == (instance, prim) => {
            let i = index(instance, prim);
            if ((g.t - f.t).abs() * len) <= slack(i) + 1e-5 * f.t.abs() * len {
                Ok(())
            } else {
                Err(format!(
                    "t is off by {} on the same triangle",
                    (g.t - f.t).abs()
                ))
            }
        }
        _ => {
            // Another triangle, or a miss: the nearer hit must graze an edge of its triangle
            // or an end of the ray's interval.
            let g = got.map(|h| (index(h.instance, h.prim), h.t));
            let f = flat.map(|(instance, prim, h)| (index(instance, prim), h.t));
            // Two surfaces meeting where the ray crosses them: a tie up to rounding.
            if let (Some(a), Some(b)) = (g, f)
                && (a.1 - b.1).abs() * len <= slack(a.0) + slack(b.0) + 1e-5 * a.1.abs() * len
            {
                return Ok(());
            }
            let (i, t) = match (g, f) {
                (Some(a), Some(b)) => {
                    if a.1 <= b.1 {
                        a
                    } else {
                        b
                    }
                }
                (Some(a), None) | (None, Some(a)) => a,
                (None, None) => unreachable!("handled above"),
            };
            let at = ray.at(t);
            let s = slack(i);
            let tri = world[i];
            let edge = [(tri.v0, tri.v1), (tri.v1, tri.v2), (tri.v2, tri.v0)]
                .iter()
                .map(|&(a, b)| segment_distance(at, a, b))
                .fold(f32::INFINITY, f32::min);
            let ends = ((t - ray.t_min).abs().min((t - ray.t_max).abs())) * len;
            if edge <= s || ends <= s {
                Ok(())
            } else {
                Err(format!(
                    "another triangle or a miss, {edge} from the nearer hit's edges (rounding allows {s})"
                ))
            }
        }
    }
}

/// The distance from `p` to the segment `a b`.
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let (p, a, b) = (p.as_dvec3(), a.as_dvec3(), b.as_dvec3());
    let d = b - a;
    let len2 = d.length_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + s * d)).length() as f32
}

/// Runs proptest on random two-level scenes for `T`: one to three meshes of up to 16 lattice
/// triangles, up to ten instances (identity, mirrors, non-uniform scales, rotations, shears,
/// and the same transform repeated) on bottom levels from `bottoms`, and rays aimed at the
/// instanced triangles.
///
/// # Panics
/// With the shrunk failing case.
pub fn check_two_level_random<T: TwoLevel<Triangle> + 'static>(bottoms: &[BottomBuilder]) {
    let coord = || {
        prop_oneof![
            (-4i32..=4).prop_map(|i| i as f32 * 0.5),
            crate::float_in(-2.0, 2.0)
        ]
    };
    let vec3 = move || (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let tri = (vec3(), vec3(), vec3()).prop_map(|(a, b, c)| Triangle::new(a, b, c));
    let scale_c = || {
        prop_oneof![
            Just(1.0f32),
            Just(-1.0f32),
            Just(2.0f32),
            Just(0.5f32),
            crate::float_in(0.25, 4.0)
        ]
    };
    let transform = prop_oneof![
        2 => Just(Affine3A::IDENTITY),
        4 => (
            (scale_c(), scale_c(), scale_c()),
            prop::array::uniform3(crate::float_in(-1.0, 1.0)),
            crate::float_in(0.0, 6.3),
            vec3(),
            prop::bool::ANY,
        )
            .prop_map(|((sx, sy, sz), axis, angle, at, shear)| {
                let axis = Vec3::from(axis).try_normalize().unwrap_or(Vec3::Z);
                let m = Affine3A::from_scale_rotation_translation(
                    Vec3::new(sx, sy, sz),
                    Quat::from_axis_angle(axis, angle),
                    at * 4.0,
                );
                if shear {
                    m * Affine3A::from_cols_array(&[
                        1.0, 0.0, 0.7, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,
                    ])
                } else {
                    m
                }
            }),
    ];
    let placement = (
        any::<prop::sample::Index>(),
        0usize..8,
        transform,
        prop::bool::weighted(0.2),
    );
    let strategy = (
        prop::collection::vec(prop::collection::vec(tri, 0..16), 1..4),
        prop::collection::vec(placement, 0..10),
        any::<u64>(),
    );
    let mut runner = TestRunner::new(Config {
        failure_persistence: None,
        ..Config::default()
    });
    let stalled = std::sync::atomic::AtomicBool::new(false);
    let result = runner.run(&strategy, |(meshes, specs, seed)| {
        if stalled.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(());
        }
        let mut placements: Vec<Placement> = Vec::new();
        for (k, (mesh, bottom, to_world, repeat)) in specs.into_iter().enumerate() {
            // Sometimes the previous instance's transform again: exact ties between instances.
            let to_world = match placements.last() {
                Some(last) if repeat => last.to_world,
                _ => to_world,
            };
            placements.push(Placement {
                mesh: mesh.index(meshes.len()),
                bottom,
                to_world,
                id: 1000 + k as u32,
            });
        }
        let mut rng = Rng::new(seed);
        let rays = aimed(&mut rng, &meshes, &placements_of(&placements), 48);
        let case = InstancedCase {
            meshes,
            placements,
            rays,
        };
        check_two_level_case::<T>(bottoms, &case).map_err(|e| stall_stops_shrinking(&stalled, e))
    });
    if let Err(e) = result {
        panic!("{}", proptest_failure(T::NAME, "two-level ", e));
    }
}

//! A path tracer written as a wavefront, the way a renderer that hands its rays over in batches
//! is: every path of a tile advances one bounce at a time, each bounce's closest-hit rays are
//! traced together, then its shadow rays together ([`Tracing`] says how), and the rays each
//! bounce depth traced and the time spent tracing them are counted ([`DepthStats`]).
//!
//! The light transport is the textbook one (Pharr, Jakob & Humphreys, *Physically Based
//! Rendering*, 4th ed., ch. 13): at a diffuse surface, next-event estimation toward every point
//! light through a shadow ray, then a cosine-weighted bounce; a mirror or glass surface is
//! chosen in proportion to its weight and followed without a shadow ray (Schlick's Fresnel
//! term picks reflection or refraction); rays that leave the scene see the sky, the only other
//! source of light. Paths stop after [`PathOptions::bounces`] bounces.
//!
//! Each path draws its random numbers from its own generator, seeded by its pixel and sample,
//! and consumes them in the same order whatever the tracing, so the picture depends on the
//! structures' answers alone: single rays and batches give the same bytes, as do all correct
//! structures.

use crate::image::{TILE, block_order, encode, per_tile};
use crate::whitted::{Context, albedo};
use crate::{Image, ImageError, RenderScene};
use rt_core::glam::Vec3;
use rt_core::{DynAccel, Hit, Ray, Rng, Shape};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How the path tracer hands a bounce's rays to the structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Tracing {
    /// One ray at a time ([`DynAccel::intersect_all`], [`DynAccel::occluded_all`]): each ray
    /// walks the structure alone.
    Single,
    /// The bounce's rays as one batch ([`DynAccel::intersect_bundle_dyn`],
    /// [`DynAccel::occluded_bundle_dyn`]): the structure chooses per run of rays between
    /// walking them together as bundles and singly.
    Batch,
    /// Each bounce's rays both ways, singly and as one batch, one after the other (which goes
    /// first alternates from depth to depth and from tile to tile), each timed; the batch's
    /// answers drive the paths, and every answer that differs from its single ray's is counted
    /// ([`Paired`]). Both ways run on the same rays a moment apart, so their ratio holds even
    /// while the machine's speed drifts, as it does between two whole renders.
    Paired,
}

/// How to render a path-traced picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Paths per pixel, each through a random point of the pixel.
    pub samples: u32,
    /// Bounces after the primary hit (0: direct light and sky only).
    pub bounces: u32,
    /// Seeds every path's random numbers.
    pub seed: u64,
}

impl Default for PathOptions {
    /// 1024×768, 4 paths per pixel, 3 bounces, seed 1.
    fn default() -> Self {
        Self {
            width: 1024,
            height: 768,
            samples: 4,
            bounces: 3,
            seed: 1,
        }
    }
}

/// The rays one bounce depth traced, over every tile and thread: depth 0 is the primary rays
/// and the shadow rays from their hits.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthStats {
    /// Closest-hit rays traced.
    pub rays: u64,
    /// How many of them hit something.
    pub hits: u64,
    /// Time spent in the closest-hit calls, summed over threads.
    pub trace: Duration,
    /// Shadow rays traced (toward the lights, from the diffuse hits of `rays`).
    pub shadow_rays: u64,
    /// How many of them were blocked.
    pub blocked: u64,
    /// Time spent in the shadow-ray calls, summed over threads.
    pub shadow_trace: Duration,
    /// With [`Tracing::Paired`] (where `trace` and `shadow_trace` are the batches' times), the
    /// same rays traced singly.
    pub paired: Option<Paired>,
}

/// The rays of one bounce depth traced singly beside their batches ([`Tracing::Paired`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Paired {
    /// Time spent in the single closest-hit calls, summed over threads.
    pub trace: Duration,
    /// Time spent in the single shadow-ray calls, summed over threads.
    pub shadow_trace: Duration,
    /// Answers of the batches that differ from their single rays' in any bit.
    pub differences: u64,
}

impl DepthStats {
    fn add(&mut self, o: &DepthStats) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.trace += o.trace;
        self.shadow_rays += o.shadow_rays;
        self.blocked += o.blocked;
        self.shadow_trace += o.shadow_trace;
        if let Some(o) = o.paired {
            let p = self.paired.get_or_insert_default();
            p.trace += o.trace;
            p.shadow_trace += o.shadow_trace;
            p.differences += o.differences;
        }
    }
}

/// A path-traced picture and what each bounce depth traced.
#[derive(Clone, Debug, PartialEq)]
pub struct PathRender {
    /// The picture.
    pub image: Image,
    /// Index `d`: the rays of bounce depth `d`, up to the deepest any path reached.
    pub depths: Vec<DepthStats>,
}

/// One path between bounces.
struct Path {
    ray: Ray,
    /// What the light arriving along `ray` is multiplied by on its way to the pixel.
    throughput: Vec3,
    /// The pixel, as an index into the tile.
    pixel: u32,
    rng: Rng,
}

/// Renders `scene`, whose [`RenderScene::shapes`] `tracer` was built over, as a path tracer
/// with `options`, handing its rays to `tracer` as `tracing` says; tiles in parallel on rayon's
/// current pool. `progress` is called with the tiles done and the total after each tile.
///
/// # Errors
/// [`ImageError::BadSize`] for an unusable size.
///
/// ```
/// use rt_core::Accel;
/// use rt_render::{PathOptions, RenderScene, Tracing, render_path};
/// let scene = RenderScene::whitted();
/// let shapes = scene.shapes();
/// let accel = rt_core::BruteForce::build(&shapes[..2000], &Default::default());
/// let options = PathOptions { width: 8, height: 6, samples: 2, bounces: 2, seed: 1 };
/// let single = render_path(&scene, &shapes, &accel, &options, Tracing::Single, &|_, _| {})?;
/// let batch = render_path(&scene, &shapes, &accel, &options, Tracing::Batch, &|_, _| {})?;
/// assert_eq!(single.image, batch.image);
/// assert_eq!(single.depths[0].rays, 8 * 6 * 2);
/// # Ok::<(), rt_render::ImageError>(())
/// ```
pub fn render_path(
    scene: &RenderScene,
    shapes: &[Shape],
    tracer: &dyn DynAccel<Shape>,
    options: &PathOptions,
    tracing: Tracing,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<PathRender, ImageError> {
    let ctx = Context {
        scene,
        shapes,
        tracer,
        max_depth: 1,
    };
    let raster = scene.camera.raster(options.width, options.height);
    let depths = Mutex::new(Vec::<DepthStats>::new());
    let pixels = per_tile(options.width, options.height, progress, |x0, y0, w, h| {
        // The tile's paths, sample by sample, each sample's pixels in blocks of 8×8 row by row:
        // a block's primary rays make one coherent bundle.
        let mut paths = Vec::with_capacity((w * h * options.samples) as usize);
        for sample in 0..options.samples {
            for (x, y) in block_order(w, h) {
                let (px, py) = (x0 + x, y0 + y);
                let key = (u64::from(py) * u64::from(options.width) + u64::from(px))
                    * u64::from(options.samples)
                    + u64::from(sample);
                let mut rng = Rng::new(options.seed ^ key.wrapping_mul(0x9e37_79b9_7f4a_7c15));
                let ray = raster.ray(px as f32 + rng.f32(), py as f32 + rng.f32());
                paths.push(Path {
                    ray,
                    throughput: Vec3::ONE,
                    pixel: y * w + x,
                    rng,
                });
            }
        }
        let mut sums = vec![Vec3::ZERO; (w * h) as usize];
        // Paired tracing: neighbouring tiles take the two ways in opposite orders.
        let odd = (x0 / TILE + y0 / TILE) % 2 == 1;
        let stats = trace_paths(&ctx, paths, options.bounces, (tracing, odd), &mut sums);
        let mut all = depths.lock().unwrap_or_else(|e| e.into_inner());
        if all.len() < stats.len() {
            all.resize(stats.len(), DepthStats::default());
        }
        for (a, s) in all.iter_mut().zip(&stats) {
            a.add(s);
        }
        let scale = 1.0 / options.samples.max(1) as f32;
        sums.into_iter().map(|s| encode(s * scale)).collect()
    })?;
    Ok(PathRender {
        image: Image {
            width: options.width,
            height: options.height,
            pixels,
        },
        depths: depths.into_inner().unwrap_or_else(|e| e.into_inner()),
    })
}

/// A shadow ray planned at a diffuse hit: the ray, the light it goes to, its path's pixel and
/// what it adds there if the light is not blocked.
struct Planned {
    ray: Ray,
    light: u32,
    pixel: u32,
    adds: Vec3,
}

/// Advances `paths` a bounce at a time until none is left or `bounces` bounces are done, adding
/// each path's light into `sums` (by pixel); returns what each depth traced.
fn trace_paths(
    ctx: &Context<'_>,
    mut paths: Vec<Path>,
    bounces: u32,
    (tracing, odd): (Tracing, bool),
    sums: &mut [Vec3],
) -> Vec<DepthStats> {
    let mut depths = Vec::new();
    let (mut rays, mut hits, mut shadow, mut planned, mut blocked) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // With `Tracing::Paired`: the single rays' answers.
    let (mut alone, mut alone_blocked) = (Vec::new(), Vec::new());
    for depth in 0..=bounces {
        if paths.is_empty() {
            break;
        }
        let mut stats = DepthStats::default();
        // With `Tracing::Paired`, whether the single rays go first at this depth: the second
        // finds the first's nodes in the caches, so the order alternates from depth to depth
        // and from tile to tile.
        let single_first = odd ^ (depth % 2 == 1);
        rays.clear();
        rays.extend(paths.iter().map(|p| p.ray));
        hits.clear();
        hits.resize(rays.len(), None);
        let single = |rays: &[Ray], out: &mut Vec<Option<Hit>>| {
            ctx.tracer.intersect_all(rays, out, None);
        };
        let batch = |rays: &[Ray], out: &mut Vec<Option<Hit>>| {
            ctx.tracer.intersect_bundle_dyn(rays, out, None);
        };
        stats.trace = match tracing {
            Tracing::Single => timed(|| single(&rays, &mut hits)),
            Tracing::Batch => timed(|| batch(&rays, &mut hits)),
            Tracing::Paired => {
                let (time, single_time, differences) = paired(
                    single_first,
                    &rays,
                    &mut hits,
                    &mut alone,
                    batch,
                    single,
                    same_hit,
                );
                let p = stats.paired.get_or_insert_default();
                p.trace = single_time;
                p.differences += differences;
                time
            }
        };
        stats.rays = rays.len() as u64;
        stats.hits = hits.iter().filter(|h| h.is_some()).count() as u64;
        planned.clear();
        let last = depth == bounces;
        paths = paths
            .into_iter()
            .zip(&hits)
            .filter_map(|(path, hit)| match hit {
                Some(hit) => scatter(ctx, path, *hit, last, &mut planned),
                None => {
                    sums[path.pixel as usize] += path.throughput * ctx.sky(path.ray.dir());
                    None
                }
            })
            .collect();
        // The shadow rays toward one light after another, each light's in the order of their
        // paths: rays toward one point from nearby points make coherent runs, where rays
        // alternating between lights would not. (A stable sort keeps the sums' order of
        // additions the same whatever the tracing.)
        planned.sort_by_key(|p| p.light);
        shadow.clear();
        shadow.extend(planned.iter().map(|p| p.ray));
        blocked.clear();
        blocked.resize(shadow.len(), false);
        let single = |rays: &[Ray], out: &mut Vec<bool>| ctx.tracer.occluded_all(rays, out, None);
        let batch = |rays: &[Ray], out: &mut Vec<bool>| {
            ctx.tracer.occluded_bundle_dyn(rays, out, None);
        };
        stats.shadow_trace = match tracing {
            Tracing::Single => timed(|| single(&shadow, &mut blocked)),
            Tracing::Batch => timed(|| batch(&shadow, &mut blocked)),
            Tracing::Paired => {
                let (time, single_time, differences) = paired(
                    single_first,
                    &shadow,
                    &mut blocked,
                    &mut alone_blocked,
                    batch,
                    single,
                    |a, b| a == b,
                );
                let p = stats.paired.get_or_insert_default();
                p.shadow_trace = single_time;
                p.differences += differences;
                time
            }
        };
        stats.shadow_rays = shadow.len() as u64;
        for (p, &b) in planned.iter().zip(&blocked) {
            if b {
                stats.blocked += 1;
            } else {
                sums[p.pixel as usize] += p.adds;
            }
        }
        depths.push(stats);
    }
    depths
}

/// `rays` traced by `batch` into `out` and by `single` into `alone` (resized to match), the
/// single rays first if `single_first`: how long the batch took, how long the single rays took,
/// and how many answers differ by `same`.
fn paired<T: Clone + Default>(
    single_first: bool,
    rays: &[Ray],
    out: &mut Vec<T>,
    alone: &mut Vec<T>,
    batch: impl Fn(&[Ray], &mut Vec<T>),
    single: impl Fn(&[Ray], &mut Vec<T>),
    same: impl Fn(&T, &T) -> bool,
) -> (Duration, Duration, u64) {
    alone.clear();
    alone.resize(out.len(), T::default());
    let (batch_time, single_time) = if single_first {
        let s = timed(|| single(rays, alone));
        (timed(|| batch(rays, out)), s)
    } else {
        let b = timed(|| batch(rays, out));
        (b, timed(|| single(rays, alone)))
    };
    let differences = out
        .iter()
        .zip(alone.iter())
        .filter(|(a, b)| !same(a, b))
        .count();
    (batch_time, single_time, differences as u64)
}

/// Whether two closest-hit answers are the same in every bit.
fn same_hit(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    let bits = |h: &Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
    bits(a) == bits(b)
}

/// How long `f` took.
fn timed(f: impl FnOnce()) -> Duration {
    let start = Instant::now();
    f();
    start.elapsed()
}

/// The path after its ray hit `hit`: shadow rays toward the lights planned into `planned` at a
/// diffuse surface, and the path continued along its next ray, unless `last` or the surface
/// absorbed it.
fn scatter(
    ctx: &Context<'_>,
    mut path: Path,
    hit: Hit,
    last: bool,
    planned: &mut Vec<Planned>,
) -> Option<Path> {
    let lit = ctx.lit(&path.ray, hit);
    let material = ctx.scene.material(hit.prim as usize);
    let specular = (material.mirror + material.transmission).clamp(0.0, 1.0);
    let u = path.rng.f32();
    if u < specular {
        // A mirror or glass bounce, chosen in proportion to its weight, so its weight is the
        // material's colour alone.
        if last {
            return None;
        }
        let reflected = lit.reflected();
        let dir = if u < material.transmission {
            // Reflected or refracted in proportion to the Fresnel term.
            match lit.refracted(material.ior) {
                Some((t, fresnel)) if path.rng.f32() >= fresnel => t,
                _ => reflected,
            }
        } else {
            reflected
        };
        path.throughput *= material.color;
        path.ray = lit.at.spawn_ray(dir);
        return Some(path);
    }
    // Diffuse: the lobe's weight over the chance of choosing it.
    let weight = albedo(material, lit.at.point) * (material.diffuse / (1.0 - specular));
    for (k, light) in ctx.scene.lights.iter().enumerate() {
        if let Some((ray, lambert, _)) = ctx.shadow_ray(&lit, light) {
            planned.push(Planned {
                ray,
                light: k as u32,
                pixel: path.pixel,
                adds: path.throughput * weight * light.intensity * lambert,
            });
        }
    }
    if last {
        return None;
    }
    // Cosine-weighted about the shading normal (the normal plus a uniform unit vector); a
    // direction below the geometry leaves along the geometric normal instead.
    let n = lit.normal;
    let mut dir = (n + path.rng.unit_vector()).try_normalize().unwrap_or(n);
    if dir.dot(lit.geometric) <= 0.0 {
        dir = lit.geometric;
    }
    path.throughput *= weight;
    path.ray = lit.at.spawn_ray(dir);
    Some(path)
}

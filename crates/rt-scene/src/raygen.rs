//! The ray sets this project measures structures with: primary rays (a [`Camera`]'s image),
//! incoherent rays, shadow rays and diffuse bounces from the primary hits, points for closest-point queries, and the rays-file format that
//! replays any of them.

use crate::Camera;
use glam::Vec3;
use rt_core::{Aabb, Hit, Primitive, Ray, Rng, SurfacePoint};
use std::fmt;
use std::path::Path;

/// `count` rays with origins uniform in `bounds` and directions uniform on the sphere: the
/// worst case for coherence, like diffuse bounces.
pub fn incoherent_rays(bounds: &Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| Ray::new(rng.in_box(bounds.min, bounds.max), rng.unit_vector()))
        .collect()
}

/// `count` points for closest-point queries, drawn from `seed`: alternately a point uniform in
/// `bounds` grown by a quarter of its extent on every side (so some lie outside the scene), and
/// a point near the surface: on a random valid primitive (the nearest point of it to a random
/// point of its box), moved by up to 2% of the box's diagonal in a random direction.
///
/// ```
/// use rt_core::{Aabb, Primitive, Triangle, glam::Vec3};
/// use rt_scene::raygen::query_points;
/// let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
/// let points = query_points(&tris, &tris[0].bounds(), 100, 1);
/// assert_eq!(points.len(), 100);
/// assert_eq!(points, query_points(&tris, &tris[0].bounds(), 100, 1));
/// ```
pub fn query_points<P: Primitive>(
    prims: &[P],
    bounds: &Aabb,
    count: usize,
    seed: u64,
) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    let valid: Vec<&P> = prims.iter().filter(|p| p.is_valid()).collect();
    let grow = bounds.extent() * 0.25;
    let reach = bounds.extent().length() * 0.02;
    (0..count)
        .map(|i| {
            if i % 2 == 0 || valid.is_empty() || valid.len() > u32::MAX as usize {
                rng.in_box(bounds.min - grow, bounds.max + grow)
            } else {
                let p = valid[rng.below(valid.len() as u32) as usize];
                let b = p.bounds();
                let on = p.closest_point(rng.in_box(b.min, b.max));
                on + rng.unit_vector() * (reach * rng.f32())
            }
        })
        .collect()
}

/// A point light above and to the side of the box, at twice its radius from the centre.
pub fn default_light(bounds: &Aabb) -> Vec3 {
    bounds.center() + Vec3::new(0.6, 1.0, 0.4).normalize() * bounds.extent().length()
}

/// Occlusion rays from each primary hit to `light`, over `t` in `[0, 1]` of the way there, each
/// started at the hit's surface point moved off the surface by its error bound
/// ([`SurfacePoint::spawn_ray_to`](rt_core::SurfacePoint::spawn_ray_to)), so that no ray can hit
/// the surface it starts on. `prims` are the primitives the hits index.
pub fn shadow_rays<P: Primitive>(
    primary: &[Ray],
    hits: &[Option<Hit>],
    prims: &[P],
    light: Vec3,
) -> Vec<Ray> {
    from_hits(primary, hits, prims, |_, surface| {
        surface.spawn_ray_to(light)
    })
}

/// `spawn(primary ray, its hit's surface point)` for each primary ray that hits, the valid rays
/// it makes in order.
fn from_hits<P: Primitive>(
    primary: &[Ray],
    hits: &[Option<Hit>],
    prims: &[P],
    mut spawn: impl FnMut(&Ray, SurfacePoint) -> Ray,
) -> Vec<Ray> {
    primary
        .iter()
        .zip(hits)
        .filter_map(|(r, h)| {
            let h = (*h)?;
            Some(spawn(
                r,
                prims.get(h.prim as usize)?.surface(r, h.t, h.u, h.v),
            ))
        })
        .filter(|r| r.is_valid())
        .collect()
}

/// A path tracer's first bounce off diffuse surfaces: from each primary hit, one ray in a
/// cosine-weighted direction about the surface's normal, on the side the primary ray came
/// from, started as [`shadow_rays`] start theirs (off the surface by its error bound, so that
/// no ray can hit the surface it leaves). `prims` are the primitives the hits index; `seed`
/// draws the directions.
///
/// The direction is the normal plus a direction uniform on the sphere, normalised: the sum of
/// a unit normal and a uniform unit vector is distributed by the cosine about the normal (the
/// point is uniform on the unit sphere touching the surface, seen from where it touches).
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Triangle, glam::Vec3};
/// use rt_scene::raygen::diffuse_rays;
/// let floor = [Triangle::new(Vec3::new(-9.0, 0.0, -9.0), Vec3::new(9.0, 0.0, 9.0), Vec3::new(9.0, 0.0, -9.0))];
/// let primary = vec![Ray::new(Vec3::new(1.0, 5.0, 0.0), -Vec3::Y); 100];
/// let accel = BruteForce::build(&floor, &());
/// let hits: Vec<_> = primary.iter().map(|r| accel.intersect(r)).collect();
/// let bounces = diffuse_rays(&primary, &hits, &floor, 7);
/// assert_eq!(bounces.len(), 100);
/// // Every bounce leaves the floor upwards, towards where the primary rays came from.
/// assert!(bounces.iter().all(|r| r.dir().y > 0.0 && r.origin.y > 0.0));
/// ```
pub fn diffuse_rays<P: Primitive>(
    primary: &[Ray],
    hits: &[Option<Hit>],
    prims: &[P],
    seed: u64,
) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    from_hits(primary, hits, prims, |r, surface| {
        let n = surface.normal;
        let facing = if n.dot(r.dir()) > 0.0 { -n } else { n };
        // A sum that cancels (the uniform vector opposite the normal, almost never) leaves
        // along the normal.
        let dir = (facing + rng.unit_vector())
            .try_normalize()
            .unwrap_or(facing);
        surface.spawn_ray(dir)
    })
}

/// The ray sets every measurement in this project uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayKind {
    /// One ray per pixel of a camera's image (closest-hit queries).
    Primary,
    /// Random origins inside the scene box, random directions (closest-hit queries).
    Incoherent,
    /// Occlusion rays from the primary hits to [`default_light`] (any-hit queries).
    Shadow,
    /// One diffuse bounce from each primary hit ([`diffuse_rays`]; closest-hit queries).
    Diffuse,
}

impl RayKind {
    /// All four, in report order.
    pub const ALL: [RayKind; 4] = [
        RayKind::Primary,
        RayKind::Incoherent,
        RayKind::Shadow,
        RayKind::Diffuse,
    ];

    /// The lower-case name reports use (`primary`, `incoherent`, `shadow`, `diffuse`).
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Incoherent => "incoherent",
            RayKind::Shadow => "shadow",
            RayKind::Diffuse => "diffuse",
        }
    }

    /// Whether these rays are traced as any-hit (occlusion) queries.
    pub fn is_any_hit(self) -> bool {
        self == RayKind::Shadow
    }
}

/// The rays of one kind, exactly as `cargo xtask compare` and the benchmarks trace them:
/// `width × height` primary rays of `camera`; as many incoherent rays in `bounds` drawn with
/// `seed`; one shadow ray per primary hit towards [`default_light`] ([`shadow_rays`]); or one
/// diffuse bounce per primary hit drawn with `seed` ([`diffuse_rays`]). Shadow rays and bounces
/// need the primary rays' closest hits on `prims`, which `closest_hits` computes (with any
/// correct structure: they all give the same answers).
pub fn rays_of_kind<P: Primitive>(
    kind: RayKind,
    prims: &[P],
    camera: &Camera,
    bounds: &Aabb,
    (width, height): (u32, u32),
    seed: u64,
    closest_hits: impl FnOnce(&[Ray]) -> Vec<Option<Hit>>,
) -> Vec<Ray> {
    match kind {
        RayKind::Primary => camera.primary_rays(width, height),
        RayKind::Incoherent => incoherent_rays(bounds, width as usize * height as usize, seed),
        RayKind::Shadow => {
            let primary = camera.primary_rays(width, height);
            let hits = closest_hits(&primary);
            shadow_rays(&primary, &hits, prims, default_light(bounds))
        }
        RayKind::Diffuse => {
            let primary = camera.primary_rays(width, height);
            let hits = closest_hits(&primary);
            diffuse_rays(&primary, &hits, prims, seed)
        }
    }
}

/// An error reading a rays file.
#[derive(Clone, Debug, PartialEq)]
pub struct RaysFileError {
    /// The file.
    pub path: std::path::PathBuf,
    /// The 1-based line, when one is to blame.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for RaysFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for RaysFileError {}

/// Reads rays, one per line: `ox oy oz dx dy dz [tmin tmax]`; `#` starts a comment; blank lines
/// are skipped. Without an interval a ray covers `[0, inf]`.
///
/// # Errors
/// A [`RaysFileError`] naming the file and line for an unreadable file, a line with other than 6
/// or 8 numbers, or a ray that is not [`Ray::is_valid`] (zero or non-finite direction, ...).
pub fn read_rays_file(path: &Path) -> Result<Vec<Ray>, RaysFileError> {
    let err = |line, message| RaysFileError {
        path: path.to_owned(),
        line,
        message,
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| err(None, format!("cannot read file: {e}")))?;
    parse_rays(&text).map_err(|(line, message)| err(Some(line), message))
}

/// Parses the rays-file format from a string; errors carry the 1-based line.
///
/// # Errors
/// As [`read_rays_file`].
pub fn parse_rays(text: &str) -> Result<Vec<Ray>, (usize, String)> {
    let mut rays = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let data = line.split('#').next().unwrap_or("");
        let words: Vec<&str> = data.split_whitespace().collect();
        if words.is_empty() {
            continue;
        }
        let nums = words
            .iter()
            .map(|w| {
                w.parse::<f32>()
                    .map_err(|_| (n + 1, format!("`{w}` is not a number")))
            })
            .collect::<Result<Vec<f32>, _>>()?;
        let ray = match nums[..] {
            [ox, oy, oz, dx, dy, dz] => Ray::new(Vec3::new(ox, oy, oz), Vec3::new(dx, dy, dz)),
            [ox, oy, oz, dx, dy, dz, t0, t1] => {
                Ray::with_interval(Vec3::new(ox, oy, oz), Vec3::new(dx, dy, dz), t0, t1)
            }
            _ => {
                return Err((
                    n + 1,
                    format!(
                        "expected 6 or 8 numbers (ox oy oz dx dy dz [tmin tmax]), found {}",
                        nums.len()
                    ),
                ));
            }
        };
        if !ray.is_valid() {
            return Err((
                n + 1,
                "invalid ray: needs finite origin, non-zero finite direction and 0 <= tmin <= tmax"
                    .into(),
            ));
        }
        rays.push(ray);
    }
    Ok(rays)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_file_round_trip() {
        let r = Ray::with_interval(
            Vec3::new(0.1, -0.0, 3.0e-7),
            Vec3::new(1.0 / 3.0, 0.0, -2.0),
            0.5,
            f32::INFINITY,
        );
        let text = format!("# comment\n\n{}  # trailing\n0 0 0 0 0 1\n", r.to_line());
        let rays = parse_rays(&text).unwrap();
        assert_eq!(rays.len(), 2);
        assert_eq!(
            rays[0].origin.to_array().map(f32::to_bits),
            r.origin.to_array().map(f32::to_bits)
        );
        assert_eq!(rays[0].dir(), r.dir());
        assert_eq!((rays[0].t_min, rays[0].t_max), (0.5, f32::INFINITY));
        assert_eq!(rays[1].t_max, f32::INFINITY);
    }

    /// Bounces off a floor seen from above and from below: each leaves on the side its primary
    /// ray came from, and their directions follow the cosine about the normal (the mean cosine
    /// of a cosine-weighted hemisphere is 2/3, of a uniform one 1/2).
    #[test]
    fn diffuse_bounces_are_cosine_weighted_on_the_incoming_side() {
        use rt_core::{Accel, BruteForce, Triangle};
        let floor = [Triangle::new(
            Vec3::new(-9.0, 0.0, -9.0),
            Vec3::new(9.0, 0.0, 9.0),
            Vec3::new(9.0, 0.0, -9.0),
        )];
        let accel = BruteForce::build(&floor, &());
        for side in [1.0f32, -1.0] {
            let primary =
                vec![Ray::new(Vec3::new(0.5, 5.0 * side, 0.25), -side * Vec3::Y); 100_000];
            let hits: Vec<_> = primary.iter().map(|r| accel.intersect(r)).collect();
            let bounces = diffuse_rays(&primary, &hits, &floor, 3);
            assert_eq!(bounces.len(), primary.len());
            assert!(bounces.iter().all(|r| r.dir().y * side > 0.0
                && r.origin.y * side > 0.0
                && accel.intersect(r).is_none()));
            let mean_cos = bounces
                .iter()
                .map(|r| (r.dir().y * side) as f64)
                .sum::<f64>()
                / bounces.len() as f64;
            assert!((mean_cos - 2.0 / 3.0).abs() < 0.005, "{mean_cos}");
            assert_eq!(bounces, diffuse_rays(&primary, &hits, &floor, 3));
        }
        // A miss makes no bounce.
        assert!(diffuse_rays(&[Ray::new(Vec3::Y, Vec3::Y)], &[None], &floor, 3).is_empty());
    }

    #[test]
    fn rays_file_errors_name_the_line() {
        assert_eq!(parse_rays("0 0 0 1 0 0\n1 2 3\n").unwrap_err().0, 2);
        assert_eq!(parse_rays("0 0 0 x 0 0\n").unwrap_err().0, 1);
        assert_eq!(parse_rays("0 0 0 0 0 0\n").unwrap_err().0, 1);
        assert_eq!(parse_rays("0 0 nan 1 0 0\n").unwrap_err().0, 1);
        assert_eq!(parse_rays("0 0 0 1 0 0 2 1\n").unwrap_err().0, 1);
    }
}

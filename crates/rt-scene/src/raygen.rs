//! The ray sets this project measures structures with: primary rays (a [`Camera`]'s image),
//! incoherent and shadow rays, points for closest-point queries, and the rays-file format that
//! replays any of them.

use crate::Camera;
use glam::Vec3;
use rt_core::{Aabb, Hit, Primitive, Ray, Rng};
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
    primary
        .iter()
        .zip(hits)
        .filter_map(|(r, h)| {
            let h = (*h)?;
            let surface = prims.get(h.prim as usize)?.surface(r, h.t, h.u, h.v);
            Some(surface.spawn_ray_to(light))
        })
        .filter(|r| r.is_valid())
        .collect()
}

/// The three ray sets every measurement in this project uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayKind {
    /// One ray per pixel of a camera's image (closest-hit queries).
    Primary,
    /// Random origins inside the scene box, random directions (closest-hit queries).
    Incoherent,
    /// Occlusion rays from the primary hits to [`default_light`] (any-hit queries).
    Shadow,
}

impl RayKind {
    /// All three, in report order.
    pub const ALL: [RayKind; 3] = [RayKind::Primary, RayKind::Incoherent, RayKind::Shadow];

    /// The lower-case name reports use (`primary`, `incoherent`, `shadow`).
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Incoherent => "incoherent",
            RayKind::Shadow => "shadow",
        }
    }

    /// Whether these rays are traced as any-hit (occlusion) queries.
    pub fn is_any_hit(self) -> bool {
        self == RayKind::Shadow
    }
}

/// The rays of one kind, exactly as `cargo xtask compare` and the benchmarks trace them:
/// `width × height` primary rays of `camera`; as many incoherent rays in `bounds` drawn with
/// `seed`; or one shadow ray per primary hit towards [`default_light`] ([`shadow_rays`]). Shadow
/// rays need the primary rays' closest hits on `prims`, which `closest_hits` computes (with any
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

    #[test]
    fn rays_file_errors_name_the_line() {
        assert_eq!(parse_rays("0 0 0 1 0 0\n1 2 3\n").unwrap_err().0, 2);
        assert_eq!(parse_rays("0 0 0 x 0 0\n").unwrap_err().0, 1);
        assert_eq!(parse_rays("0 0 0 0 0 0\n").unwrap_err().0, 1);
        assert_eq!(parse_rays("0 0 nan 1 0 0\n").unwrap_err().0, 1);
        assert_eq!(parse_rays("0 0 0 1 0 0 2 1\n").unwrap_err().0, 1);
    }
}

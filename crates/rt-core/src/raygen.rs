//! Ray sets for measuring structures: primary (camera), incoherent and shadow rays, and the
//! rays-file format used to replay them.

use crate::{Aabb, Hit, Primitive, Ray, Rng};
use glam::Vec3;
use std::fmt;
use std::path::Path;

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point the camera looks at.
    pub target: Vec3,
    /// Approximate up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

impl Camera {
    /// A camera that looks at the box from the front (+z), slightly from above, with a 40°
    /// vertical field of view, as close as it can while every corner of the box stays in a
    /// `width × height` image.
    pub fn framing(bounds: &Aabb, width: u32, height: u32) -> Self {
        Self::framing_from(bounds, Vec3::new(0.15, 0.3, 1.0), width, height)
    }

    /// [`Camera::framing`] from the direction `back` (from the box's centre towards the eye;
    /// need not be unit length): a field of instances on the ground, say, seen from above.
    pub fn framing_from(bounds: &Aabb, back: Vec3, width: u32, height: u32) -> Self {
        let vfov_deg = 40.0f32;
        let center = bounds.center();
        let back = back.try_normalize().unwrap_or(Vec3::Z);
        let forward = -back;
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let tan_v = (0.5 * vfov_deg.to_radians()).tan();
        let tan_h = tan_v * width as f32 / height.max(1) as f32;
        // A corner at offset c from the centre is at depth d + c·forward; it is in view when its
        // sideways offsets are within depth · tan of the half angles.
        let mut dist = 1e-6f32;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 {
                    bounds.min.x
                } else {
                    bounds.max.x
                },
                if i & 2 == 0 {
                    bounds.min.y
                } else {
                    bounds.max.y
                },
                if i & 4 == 0 {
                    bounds.min.z
                } else {
                    bounds.max.z
                },
            ) - center;
            let depth = corner.dot(forward);
            dist = dist
                .max(corner.dot(up).abs() / tan_v - depth)
                .max(corner.dot(right).abs() / tan_h - depth);
        }
        // A small margin so the silhouette does not touch the image border.
        let eye = center + back * dist * 1.05;
        Self {
            eye,
            target: center,
            up: Vec3::Y,
            vfov_deg,
        }
    }

    /// The camera set up for a `width × height` image: it gives the ray through any point of the
    /// image plane ([`Raster::ray`]), for renderers that sample pixels one at a time, several
    /// times, or in tiles.
    pub fn raster(&self, width: u32, height: u32) -> Raster {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan = (0.5 * self.vfov_deg.to_radians()).tan();
        Raster {
            eye: self.eye,
            forward,
            right,
            up,
            tan,
            aspect: width as f32 / height.max(1) as f32,
            width: width as f32,
            height: height as f32,
        }
    }

    /// One ray through the centre of each pixel of a `width × height` image, row by row from the
    /// top left.
    pub fn primary_rays(&self, width: u32, height: u32) -> Vec<Ray> {
        let raster = self.raster(width, height);
        let mut rays = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                rays.push(raster.ray(x as f32 + 0.5, y as f32 + 0.5));
            }
        }
        rays
    }
}

/// A [`Camera`] set up for one image size (see [`Camera::raster`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Raster {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan: f32,
    aspect: f32,
    width: f32,
    height: f32,
}

impl Raster {
    /// The ray through the point `(x, y)` of the image, in pixels from its top left corner: the
    /// centre of pixel `(i, j)` is `(i + 0.5, j + 0.5)`, and any other point of the pixel gives
    /// a sub-pixel sample. The direction is unit length; the interval is `[0, inf]`.
    ///
    /// ```
    /// use rt_core::{Aabb, raygen::Camera, glam::Vec3};
    /// let camera = Camera::framing(&Aabb::new(Vec3::ZERO, Vec3::ONE), 64, 48);
    /// let raster = camera.raster(64, 48);
    /// assert_eq!(raster.ray(3.5, 7.5), camera.primary_rays(64, 48)[7 * 64 + 3]);
    /// // The top left corner of the image looks up and to the left of its centre.
    /// let (corner, centre) = (raster.ray(0.0, 0.0), raster.ray(32.0, 24.0));
    /// assert!(corner.dir().y > centre.dir().y);
    /// ```
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.tan * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height) * self.tan;
        Ray::new(
            self.eye,
            (self.forward + sx * self.right + sy * self.up).normalize(),
        )
    }
}

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
/// use rt_core::{Aabb, Primitive, Triangle, glam::Vec3, raygen::query_points};
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
/// ([`SurfacePoint::spawn_ray_to`](crate::SurfacePoint::spawn_ray_to)), so that no ray can hit
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

    #[test]
    fn primary_rays_cover_the_image() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let cam = Camera::framing(&b, 8, 6);
        let rays = cam.primary_rays(8, 6);
        assert_eq!(rays.len(), 48);
        // The centre pixels look at (nearly) the box centre.
        let to_center = (b.center() - cam.eye).normalize();
        assert!(rays[3 * 8 + 4].dir().dot(to_center) > 0.99);
    }
}

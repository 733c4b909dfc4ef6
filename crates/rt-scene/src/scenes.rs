//! Procedural scenes built into the library, so that tests and `cargo xtask compare` need no files.

use crate::Camera;
use glam::Vec3;
use rt_core::{Aabb, Mesh, Rng};

/// A built-in scene: its name (what `--scene` takes), a one-line description, and how it is
/// made at any size.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// Name accepted by [`builtin`], alone or with a size: `random-soup:10M`.
    pub name: &'static str,
    /// What the scene is and why it is interesting.
    pub description: &'static str,
    /// About how many triangles the bare name gives.
    pub default_size: usize,
    /// Makes the scene with about this many triangles.
    make: fn(usize) -> Mesh,
    /// Where primary rays look from, when the scene has a subject to look at; `None` frames the
    /// whole scene ([`Camera::framing`]).
    pub camera: Option<Camera>,
}

impl BuiltinScene {
    /// The scene's camera for a `width × height` image: its own viewpoint, or one framing
    /// `bounds`.
    pub fn camera(&self, bounds: &Aabb, width: u32, height: u32) -> Camera {
        self.camera
            .unwrap_or_else(|| Camera::framing(bounds, width, height))
    }

    /// The scene with about `triangles` triangles (its own default at [`Self::default_size`]).
    pub fn make(&self, triangles: usize) -> Mesh {
        (self.make)(triangles)
    }
}

/// The most triangles a sized built-in scene may ask for (`random-soup:100M`): beyond it the
/// mesh alone would take several GiB.
pub const MAX_SIZE: usize = 100_000_000;

/// The built-in scene `spec` names (`name` or `name:size`), if there is one; the size is not
/// checked here (see [`resolve`]).
pub fn find(spec: &str) -> Option<&'static BuiltinScene> {
    let name = spec.split_once(':').map_or(spec, |(name, _)| name);
    BUILTIN_SCENES.iter().find(|s| s.name == name)
}

/// A triangle count as scenes and `scale` take it: digits with an optional `k` (thousand) or `M`
/// (million) suffix, such as `20000`, `500k` or `2.5M`, from 1 to [`MAX_SIZE`]; `None` otherwise.
///
/// ```
/// use rt_scene::scenes::parse_size;
/// assert_eq!(parse_size("2.5M"), Some(2_500_000));
/// assert_eq!(parse_size("0"), None);
/// ```
pub fn parse_size(text: &str) -> Option<usize> {
    let (digits, unit) = match text.strip_suffix(['k', 'K']) {
        Some(d) => (d, 1e3),
        None => match text.strip_suffix(['m', 'M']) {
            Some(d) => (d, 1e6),
            None => (text, 1.0),
        },
    };
    let n = (digits.parse::<f64>().ok()? * unit).round();
    (n.is_finite() && (1.0..=MAX_SIZE as f64).contains(&n)).then_some(n as usize)
}

/// The built-in scene and triangle count `spec` asks for: `name` (the scene's default size) or
/// `name:size`, where size is a count with an optional `k` (thousand) or `M` (million) suffix,
/// such as `20000`, `500k` or `2.5M`, from 1 to [`MAX_SIZE`]. `Ok(None)` when `spec` names no
/// built-in scene (it may be a file).
///
/// # Errors
/// A one-line message when the name is built in but the size is not a valid count.
///
/// ```
/// use rt_scene::scenes::resolve;
/// let (scene, size) = resolve("random-soup:10M").unwrap().unwrap();
/// assert_eq!((scene.name, size), ("random-soup", 10_000_000));
/// assert_eq!(resolve("terrain").unwrap().unwrap().1, 100_000);
/// assert!(resolve("random-soup:lots").is_err());
/// assert!(resolve("bunny.obj").unwrap().is_none());
/// ```
pub fn resolve(spec: &str) -> Result<Option<(&'static BuiltinScene, usize)>, String> {
    let Some(scene) = find(spec) else {
        return Ok(None);
    };
    let Some((_, size)) = spec.split_once(':') else {
        return Ok(Some((scene, scene.default_size)));
    };
    match parse_size(size) {
        Some(n) => Ok(Some((scene, n))),
        None => Err(format!(
            "scene `{spec}`: the size must be a triangle count from 1 to 100M, such as 20000, \
             500k or 2.5M"
        )),
    }
}

/// Every built-in scene; the first is the default of `compare`.
pub const BUILTIN_SCENES: &[BuiltinScene] = &[
    BuiltinScene {
        name: "sphereflake",
        description: "Haines' sphereflake (820 tessellated spheres over four orders of size, 82k triangles) on a ground quad; sized: more levels and finer spheres",
        default_size: 82_002,
        make: sphereflake_sized,
        camera: None,
    },
    BuiltinScene {
        name: "random-soup",
        description: "20k random triangles of random size, uniformly spread in a cube: no structure to exploit",
        default_size: 20_000,
        make: |n| random_soup_sized(n, 7),
        camera: None,
    },
    BuiltinScene {
        name: "teapot-in-stadium",
        description: "a 44k-triangle procedural teapot, 5 units wide, in the middle of a stadium 40 times its size (2.6k large triangles), seen from the stands; sized: a finer teapot",
        default_size: 46_722,
        make: teapot_in_stadium_sized,
        // A spectator's view: the teapot in the middle of the picture, the far stands behind.
        camera: Some(Camera {
            eye: Vec3::new(0.0, 9.0, 26.0),
            target: Vec3::new(0.2, 1.0, 0.0),
            up: Vec3::Y,
            vfov_deg: 40.0,
        }),
    },
    BuiltinScene {
        name: "teapot",
        description: "the 44k-triangle procedural teapot alone, 5 units wide: the mesh `compare --instances` fields; sized: finer or coarser",
        default_size: 44_160,
        make: |n| teapot_with_detail(0.0, (n.max(1_000) as f64 / 44_160.0).sqrt() as f32),
        camera: None,
    },
    BuiltinScene {
        name: "terrain",
        description: "a 100k-triangle height field of rolling hills over a unit square: large, even, realistic input for build time and memory",
        default_size: 100_000,
        make: height_field,
        camera: None,
    },
];

/// The camera of the sparse view ([`View::Sparse`]) of the scene `spec` (a built-in name or a
/// file): a built-in scene's own viewpoint when it has one, else one framing `bounds`, the
/// whole box in the image. `render` draws from it; timings use [`camera_for_view`].
pub fn camera_for(spec: &str, bounds: &Aabb, width: u32, height: u32) -> Camera {
    match find(spec) {
        Some(scene) => scene.camera(bounds, width, height),
        None => Camera::framing(bounds, width, height),
    }
}

/// Which view of a scene a benchmark's primary rays come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum View {
    /// A view the scene fills: a built-in scene's own camera where it has one (the teapot in a
    /// stadium, seen from the stands), else [`Camera::filled`]. Most primary rays enter the
    /// scene's box, so their speed is the speed of traversal.
    #[default]
    Filled,
    /// The whole scene box in the image ([`camera_for`]): most rays of a compact mesh miss its
    /// box and leave after one test.
    Sparse,
}

/// The camera of `view` for the scene `spec` with box `bounds` (see [`View`]).
pub fn camera_for_view(spec: &str, bounds: &Aabb, width: u32, height: u32, view: View) -> Camera {
    match (view, find(spec).and_then(|s| s.camera)) {
        (View::Sparse, _) => camera_for(spec, bounds, width, height),
        (View::Filled, Some(own)) => own,
        (View::Filled, None) => Camera::filled(bounds),
    }
}

/// The built-in scene `spec` asks for (`name` or `name:size`, see [`resolve`]), if it names one
/// with a valid size.
pub fn builtin(spec: &str) -> Option<Mesh> {
    resolve(spec).ok().flatten().map(|(s, n)| s.make(n))
}

/// A UV sphere with `stacks` bands of latitude and `slices` of longitude
/// (`2·slices·(stacks - 1)` triangles).
pub fn uv_sphere(center: Vec3, radius: f32, stacks: u32, slices: u32) -> Mesh {
    let stacks = stacks.max(2);
    let slices = slices.max(3);
    let mut positions = vec![center + Vec3::Y * radius];
    for i in 1..stacks {
        let theta = std::f32::consts::PI * i as f32 / stacks as f32;
        for j in 0..slices {
            let phi = std::f32::consts::TAU * j as f32 / slices as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            positions.push(center + d * radius);
        }
    }
    positions.push(center - Vec3::Y * radius);
    let ring = |i: u32, j: u32| 1 + (i - 1) * slices + j % slices;
    let bottom = positions.len() as u32 - 1;
    let mut indices = Vec::new();
    for j in 0..slices {
        indices.push([0, ring(1, j + 1), ring(1, j)]);
        indices.push([bottom, ring(stacks - 1, j), ring(stacks - 1, j + 1)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            indices.push([a, b, d]);
            indices.push([a, d, c]);
        }
    }
    Mesh::new(positions, indices).expect("uv_sphere indices are in range by construction")
}

/// Haines' sphereflake (Standard Procedural Databases, 1987): a sphere carrying nine spheres of
/// a third of its radius, recursively, `levels` times; each tessellated as a [`uv_sphere`], on a
/// large ground quad. Sizes span four orders of magnitude at level 3, which rewards builders
/// that adapt to the geometry.
pub fn sphereflake(levels: u32, stacks: u32, slices: u32) -> Mesh {
    fn recurse(mesh: &mut Mesh, c: Vec3, r: f32, up: Vec3, level: u32, stacks: u32, slices: u32) {
        mesh.append(&uv_sphere(c, r, stacks, slices));
        if level == 0 {
            return;
        }
        // Nine children: six around the equator, three on the upper cap (the SPD layout).
        let side = if up.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
        let u = up.cross(side).normalize();
        let v = up.cross(u);
        for k in 0..9 {
            let (elev, azim) = if k < 6 {
                (0.0f32, k as f32 * std::f32::consts::TAU / 6.0)
            } else {
                (0.9f32, (k - 6) as f32 * std::f32::consts::TAU / 3.0 + 0.5)
            };
            let dir =
                (elev.cos() * (azim.cos() * u + azim.sin() * v) + elev.sin() * up).normalize();
            let cr = r / 3.0;
            recurse(mesh, c + dir * (r + cr), cr, dir, level - 1, stacks, slices);
        }
    }
    let mut mesh = Mesh::default();
    recurse(&mut mesh, Vec3::ZERO, 1.0, Vec3::Y, levels, stacks, slices);
    let g = 2.5;
    let y = -1.0;
    let ground = Mesh::new(
        vec![
            Vec3::new(-g, y, -g),
            Vec3::new(g, y, -g),
            Vec3::new(g, y, g),
            Vec3::new(-g, y, g),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    )
    .expect("ground indices are in range");
    mesh.append(&ground);
    mesh
}

/// A sphereflake of about `triangles` triangles: the most levels (up to 6) whose spheres can
/// have 40 triangles each, then each sphere's tessellation chosen to reach the count. At 82,002
/// triangles this is `sphereflake(3, 6, 10)`, the built-in default.
pub fn sphereflake_sized(triangles: usize) -> Mesh {
    let spheres = |levels: u32| (9usize.pow(levels + 1) - 1) / 8;
    let levels = (0..=6)
        .rev()
        .find(|&l| spheres(l) * 40 <= triangles)
        .unwrap_or(0);
    let per_sphere = (triangles as f64 / spheres(levels) as f64).max(8.0);
    // 2 · slices · (stacks - 1) triangles per sphere, with slices = 2 (stacks - 1).
    let bands = ((per_sphere / 4.0).sqrt().round() as u32).max(1);
    let slices = ((per_sphere / (2.0 * bands as f64)).round() as u32).max(3);
    sphereflake(levels, bands + 1, slices)
}

/// A surface of `along + 1` rings of `around` points, point `f(u, v)` for `u` in `[0, 1]` along
/// the surface and `v` in `[0, 1)` around it, stitched into quads of two triangles; the rings
/// close on themselves. `start` and `end` close the first and last ring with a fan to that point.
fn swept(
    along: u32,
    around: u32,
    f: impl Fn(f32, f32) -> Vec3,
    start: Option<Vec3>,
    end: Option<Vec3>,
) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..=along {
        for j in 0..around {
            positions.push(f(i as f32 / along as f32, j as f32 / around as f32));
        }
    }
    let at = |i: u32, j: u32| i * around + j % around;
    let mut indices = Vec::new();
    for i in 0..along {
        for j in 0..around {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            indices.push([a, c, d]);
            indices.push([a, d, b]);
        }
    }
    for (apex, ring, flip) in [(start, 0, true), (end, along, false)] {
        if let Some(p) = apex {
            let k = positions.len() as u32;
            positions.push(p);
            for j in 0..around {
                let (a, b) = (at(ring, j), at(ring, j + 1));
                indices.push(if flip { [k, b, a] } else { [k, a, b] });
            }
        }
    }
    Mesh::new(positions, indices).expect("swept indices are in range by construction")
}

/// The point at `u` in `[0, 1]` on the Catmull–Rom spline through `points` (at least two).
fn spline(points: &[(f32, f32)], u: f32) -> (f32, f32) {
    let n = points.len() - 1;
    let x = (u.clamp(0.0, 1.0) * n as f32).min(n as f32 - 1e-6);
    let i = x as usize;
    let t = x - i as f32;
    let p = |k: isize| points[k.clamp(0, n as isize) as usize];
    let (p0, p1, p2, p3) = (
        p(i as isize - 1),
        p(i as isize),
        p(i as isize + 1),
        p(i as isize + 2),
    );
    let c = |a: f32, b: f32, c: f32, d: f32| {
        0.5 * (2.0 * b
            + (c - a) * t
            + (2.0 * a - 5.0 * b + 4.0 * c - d) * t * t
            + (3.0 * b - a - 3.0 * c + d) * t * t * t)
    };
    (c(p0.0, p1.0, p2.0, p3.0), c(p0.1, p1.1, p2.1, p3.1))
}

/// A tube of radius `radius(u)` around the curve `path(u)` in the plane z = 0, `u` in `[0, 1]`.
fn tube(along: u32, around: u32, path: impl Fn(f32) -> Vec3, radius: impl Fn(f32) -> f32) -> Mesh {
    swept(
        along,
        around,
        |u, v| {
            let du = 1e-3;
            let tangent = (path((u + du).min(1.0)) - path((u - du).max(0.0))).normalize();
            // The curve lies in z = 0: its normal in that plane, and the z axis, frame the ring.
            let normal = Vec3::new(-tangent.y, tangent.x, 0.0);
            let angle = std::f32::consts::TAU * v;
            path(u) + radius(u) * (angle.cos() * normal + angle.sin() * Vec3::Z)
        },
        None,
        None,
    )
}

/// A procedural teapot, about 5 units wide and 2 tall, standing on y = `base`: body and lid as
/// one surface of revolution (closed at both poles), a tapering spout and a handle as tubes;
/// 44k triangles.
pub fn teapot(base: f32) -> Mesh {
    teapot_with_detail(base, 1.0)
}

/// [`teapot`] with every tessellation count multiplied by `detail` (1 is the default, about
/// 44k triangles; the count grows as `detail²`).
pub fn teapot_with_detail(base: f32, detail: f32) -> Mesh {
    let n = |count: u32| ((count as f32 * detail).round() as u32).max(3);
    // (radius, height) from the bottom centre to the knob.
    let profile = [
        (0.9, 0.0),
        (1.25, 0.12),
        (1.45, 0.4),
        (1.52, 0.75),
        (1.42, 1.1),
        (1.2, 1.38),
        (1.02, 1.5),
        (0.92, 1.58),
        (0.62, 1.7),
        (0.3, 1.77),
        (0.13, 1.81),
        (0.17, 1.9),
        (0.14, 1.99),
        (0.05, 2.03),
    ];
    let mut mesh = swept(
        n(96),
        n(192),
        |u, v| {
            let (r, y) = spline(&profile, u);
            let a = std::f32::consts::TAU * v;
            Vec3::new(r * a.cos(), base + y, r * a.sin())
        },
        Some(Vec3::new(0.0, base, 0.0)),
        Some(Vec3::new(0.0, base + 2.05, 0.0)),
    );
    let spout = |u: f32| {
        let (a, b, c) = (
            Vec3::new(1.25, 0.55, 0.0),
            Vec3::new(2.15, 0.6, 0.0),
            Vec3::new(2.55, 1.45, 0.0),
        );
        let p = a * (1.0 - u) * (1.0 - u) + b * 2.0 * u * (1.0 - u) + c * u * u;
        p + Vec3::Y * base
    };
    mesh.append(&tube(n(48), n(48), spout, |u| 0.28 - 0.18 * u));
    let handle = |u: f32| {
        let a = std::f32::consts::PI * u;
        Vec3::new(-1.4 - 0.65 * a.sin(), base + 0.85 + 0.5 * a.cos(), 0.0)
    };
    mesh.append(&tube(n(48), n(24), handle, |_| 0.09));
    mesh
}

/// Haines' "teapot in a stadium": [`teapot`] at the centre of a stadium 40 times its size, a
/// ground square 240 units wide ringed by ten tiers of stands (seats and risers, 64 segments
/// around, from radius 60 to 100 and up to 40 units high). A uniform grid fine enough for the
/// stands puts the whole teapot into a few cells.
pub fn teapot_in_stadium() -> Mesh {
    stadium_with_teapot(true)
}

/// [`teapot_in_stadium`] with about `triangles` triangles: the stadium as it is, and a teapot
/// tessellated finer or coarser to make up the rest (at least a coarse teapot of about 1k).
pub fn teapot_in_stadium_sized(triangles: usize) -> Mesh {
    // The default scene's counts: the stadium alone, and the teapot at detail 1.
    const STADIUM: usize = 2_562;
    const TEAPOT: usize = 44_160;
    // At the default count this is exactly 1.0: the default scene, triangle for triangle.
    let detail =
        (triangles.saturating_sub(STADIUM).max(1_000) as f64 / TEAPOT as f64).sqrt() as f32;
    let mut mesh = teapot_with_detail(0.02, detail);
    mesh.append(&stadium_with_teapot(false));
    mesh
}

/// The stadium of [`teapot_in_stadium`], with or without its teapot.
pub fn stadium_with_teapot(with_teapot: bool) -> Mesh {
    let (inner, step, rise, tiers, segments) = (60.0, 4.0, 4.0, 10, 64);
    let mut mesh = if with_teapot {
        teapot(0.02)
    } else {
        Mesh::default()
    };
    let g = inner + step * tiers as f32 + 20.0;
    mesh.append(
        &Mesh::new(
            vec![
                Vec3::new(-g, 0.0, -g),
                Vec3::new(g, 0.0, -g),
                Vec3::new(g, 0.0, g),
                Vec3::new(-g, 0.0, g),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        )
        .expect("ground indices are in range"),
    );
    for k in 0..tiers {
        let (r, h) = (inner + step * k as f32, rise * k as f32);
        let ring = |radius: f32, y: f32, v: f32| {
            let a = std::f32::consts::TAU * v;
            Vec3::new(radius * a.cos(), y, radius * a.sin())
        };
        // The riser at radius r from h to h + rise, then the seat from r to r + step at
        // h + rise; each a band of one quad per segment.
        let riser = swept(1, segments, |u, v| ring(r, h + rise * u, v), None, None);
        let seat = swept(
            1,
            segments,
            |u, v| ring(r + step * u, h + rise, v),
            None,
            None,
        );
        mesh.append(&riser);
        mesh.append(&seat);
    }
    mesh
}

/// A terrain of about `triangles` triangles: a square grid of `k × k` cells over `[0, 1]²`, two
/// triangles per cell (`k = sqrt(triangles / 2)`), with heights from a sum of sines (hills of
/// several sizes, up to 0.1 high). Shared vertices, no degenerate triangles: a large, realistic
/// input for build times and memory.
pub fn height_field(triangles: usize) -> Mesh {
    let k = ((triangles as f64 / 2.0).sqrt().round() as u32).max(1);
    let n = k + 1;
    let h = |x: f32, y: f32| {
        0.05 * (6.1 * x).sin() * (5.3 * y).cos()
            + 0.03 * (23.0 * x + 1.3).sin() * (19.0 * y + 0.7).sin()
            + 0.02 * (71.0 * (x + y)).sin()
    };
    let mut positions = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f32 / k as f32, j as f32 / k as f32);
            positions.push(Vec3::new(x, h(x, y), y));
        }
    }
    let mut indices = Vec::with_capacity(2 * (k * k) as usize);
    for j in 0..k {
        for i in 0..k {
            let v = j * n + i;
            indices.push([v, v + n, v + 1]);
            indices.push([v + 1, v + n, v + n + 1]);
        }
    }
    Mesh::new(positions, indices).expect("height_field indices are in range by construction")
}

/// `count` random triangles with random orientation, edge lengths up to a tenth of the unit
/// cube they fill.
pub fn random_soup(count: usize, seed: u64) -> Mesh {
    soup(count, seed, 1.0)
}

/// The `random-soup` scene at `count` triangles: [`random_soup`] at 20,000 (the scene's default),
/// and at other counts triangles scaled by `(20000 / count)^(1/3)`, so that a triangle overlaps
/// about as many others at every count (the number of centres in a triangle-sized box stays the
/// same). With a fixed size, ten million triangles would overlap each other hundreds of times
/// over, and a scale ladder would measure that crowding rather than the structures.
pub fn random_soup_sized(count: usize, seed: u64) -> Mesh {
    soup(count, seed, (20_000.0 / count.max(1) as f64).cbrt() as f32)
}

fn soup(count: usize, seed: u64, scale: f32) -> Mesh {
    let mut rng = Rng::new(seed);
    let mut positions = Vec::with_capacity(3 * count);
    for _ in 0..count {
        let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
        let size = rng.range(0.005, 0.1) * scale;
        for _ in 0..3 {
            positions.push(c + rng.unit_vector() * size);
        }
    }
    let indices = (0..count as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    Mesh::new(positions, indices).expect("random_soup indices are in range by construction")
}

/// Where a field of `count` instances of an object with bounds `object` stands: transforms
/// (object space to world) on a square grid in the x-z plane, 1.2 object sizes apart, each
/// turned about y by a random angle and tilted by up to 0.2 radians, scaled by 0.75 to 1.25 on
/// each axis independently, and every seventh mirrored (x scaled by a negative factor); drawn
/// from `seed`. What `cargo xtask compare --instances` traces.
pub fn instance_field(object: &Aabb, count: usize, seed: u64) -> Vec<glam::Affine3A> {
    use glam::{Affine3A, Quat};
    let mut rng = Rng::new(seed ^ 0xf1e1d);
    let size = if object.is_empty() {
        1.0
    } else {
        object.extent().max_element().max(f32::MIN_POSITIVE)
    };
    let center = if object.is_empty() {
        Vec3::ZERO
    } else {
        object.center()
    };
    let side = (count as f64).sqrt().ceil().max(1.0) as usize;
    (0..count)
        .map(|k| {
            let at = Vec3::new((k % side) as f32, 0.0, (k / side) as f32) * (1.2 * size);
            let mut scale = Vec3::new(
                rng.range(0.75, 1.25),
                rng.range(0.75, 1.25),
                rng.range(0.75, 1.25),
            );
            if k % 7 == 6 {
                scale.x = -scale.x;
            }
            let tilt_axis = Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0))
                .try_normalize()
                .unwrap_or(Vec3::X);
            let turn = Quat::from_axis_angle(tilt_axis, rng.range(-0.2, 0.2))
                * Quat::from_rotation_y(rng.range(0.0, std::f32::consts::TAU));
            Affine3A::from_translation(at)
                * Affine3A::from_scale_rotation_translation(scale, turn, Vec3::ZERO)
                * Affine3A::from_translation(-center)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::Primitive;

    #[test]
    fn builtins_are_valid() {
        for s in BUILTIN_SCENES {
            let m = builtin(s.name).unwrap();
            assert!(m.triangle_count() > 1000, "{}", s.name);
            assert!(m.triangles().len() == m.triangle_count(), "{}", s.name);
            assert!(m.triangles().iter().all(|t| t.is_valid()), "{}", s.name);
        }
        assert!(builtin("nope").is_none());
    }

    #[test]
    fn sized_scenes_come_close_to_their_size() {
        for s in BUILTIN_SCENES {
            // The default size is the bare name's scene, exactly.
            assert_eq!(
                s.make(s.default_size).triangles(),
                builtin(s.name).unwrap().triangles(),
                "{}",
                s.name
            );
            let count = builtin(s.name).unwrap().triangle_count() as f64;
            assert!(
                (count / s.default_size as f64 - 1.0).abs() < 0.01,
                "{}: {count} triangles",
                s.name
            );
            for n in [5_000, 300_000] {
                let got = s.make(n).triangle_count() as f64;
                assert!(
                    (0.7..1.4).contains(&(got / n as f64)),
                    "{}:{n} has {got} triangles",
                    s.name
                );
            }
        }
        assert_eq!(
            sphereflake_sized(82_002).triangles(),
            sphereflake(3, 6, 10).triangles()
        );
        assert_eq!(
            teapot_in_stadium_sized(46_722).triangles(),
            teapot_in_stadium().triangles()
        );
    }

    #[test]
    fn sizes_parse_or_fail_in_one_line() {
        let size = |spec: &str| resolve(spec).map(|r| r.map(|(s, n)| (s.name, n)));
        assert_eq!(
            size("random-soup:2.5M"),
            Ok(Some(("random-soup", 2_500_000)))
        );
        assert_eq!(size("sphereflake:500k"), Ok(Some(("sphereflake", 500_000))));
        assert_eq!(size("terrain:1234"), Ok(Some(("terrain", 1234))));
        assert_eq!(
            size("teapot-in-stadium"),
            Ok(Some(("teapot-in-stadium", 46_722)))
        );
        assert_eq!(size("nope:10k"), Ok(None));
        for bad in [
            "random-soup:",
            "random-soup:0",
            "random-soup:-5",
            "random-soup:1G",
            "random-soup:101M",
            "random-soup:NaN",
            "random-soup:inf",
            "random-soup:1e400",
        ] {
            let err = resolve(bad).unwrap_err();
            assert!(err.contains(bad) && !err.contains('\n'), "{err}");
        }
        assert!(builtin("random-soup:0").is_none());
    }

    #[test]
    fn sphereflake_size() {
        let m = sphereflake(3, 6, 10);
        // 1 + 9 + 81 + 729 spheres of 2·10·5 triangles, plus the ground quad.
        assert_eq!(m.triangle_count(), 820 * 100 + 2);
    }
}

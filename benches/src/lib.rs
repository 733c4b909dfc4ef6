//! Shared set-up for the benchmarks: scenes and ray sets, identical for every contender.

#[cfg(feature = "embree")]
pub mod embree;

use rt_conformance::shared_meshes_dir;
use rt_core::{Aabb, Hit, Primitive, Ray, Triangle};
use rt_scene::Camera;
use rt_scene::raygen::{self, RayKind};
use rt_scene::scenes::{self, View};

/// A named triangle scene.
#[derive(Debug)]
pub struct BenchScene {
    /// Short name for benchmark ids.
    pub name: &'static str,
    /// What `--scene` would take for it in `cargo xtask compare`: a built-in name or a path. It
    /// picks the camera ([`scenes::camera_for`]).
    pub spec: String,
    /// The triangles.
    pub triangles: Vec<Triangle>,
}

impl BenchScene {
    /// Box around the valid triangles.
    pub fn bounds(&self) -> Aabb {
        self.triangles
            .iter()
            .filter(|t| t.is_valid())
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
    }

    /// The scene's camera of `view` for a `width × height` image, as `compare --view` makes it.
    pub fn camera(&self, view: View, width: u32, height: u32) -> Camera {
        scenes::camera_for_view(&self.spec, &self.bounds(), width, height, view)
    }

    /// Primary rays of the view `compare` uses by default, one the scene fills
    /// ([`View::Filled`]).
    pub fn primary_rays(&self, width: u32, height: u32) -> Vec<Ray> {
        self.camera(View::Filled, width, height)
            .primary_rays(width, height)
    }

    /// The rays of one kind from `view`'s camera, exactly as `cargo xtask compare --rays KIND
    /// --view VIEW` makes them (seed 1); `closest_hits` answers the primary rays that shadow
    /// rays start from.
    pub fn rays(
        &self,
        kind: RayKind,
        view: View,
        (width, height): (u32, u32),
        closest_hits: impl FnOnce(&[Ray]) -> Vec<Option<Hit>>,
    ) -> Vec<Ray> {
        raygen::rays_of_kind(
            kind,
            &self.triangles,
            &self.camera(view, width, height),
            &self.bounds(),
            (width, height),
            1,
            closest_hits,
        )
    }
}

fn builtin(name: &'static str) -> BenchScene {
    BenchScene {
        name,
        spec: name.to_string(),
        triangles: scenes::builtin(name).expect("built-in scene").triangles(),
    }
}

/// The shared mesh `file` under the name `name`, when `../shared/meshes` is present.
///
/// # Panics
/// If the shared meshes are missing under `CI=true`, or the file does not load.
pub fn shared(name: &'static str, file: &str) -> Option<BenchScene> {
    let path = shared_meshes_dir()?.join(file);
    let mesh = rt_scene::load_obj(&path).unwrap_or_else(|e| panic!("{e}"));
    Some(BenchScene {
        name,
        spec: path.display().to_string(),
        triangles: mesh.triangles(),
    })
}

/// The built-in default scene and, when `../shared/meshes` is present, the Stanford bunny.
///
/// # Panics
/// If the shared meshes are missing under `CI=true`, or the bunny does not load.
pub fn scenes() -> Vec<BenchScene> {
    let mut out = vec![builtin("sphereflake")];
    out.extend(shared("bunny", "stanford-bunny.obj"));
    out
}

/// The four scenes of the Embree comparison: the Stanford bunny and the Utah teapot (when
/// `../shared/meshes` is present), the sphereflake and the teapot in a stadium.
///
/// # Panics
/// If the shared meshes are missing under `CI=true`, or a mesh does not load.
pub fn peer_scenes() -> Vec<BenchScene> {
    let mut out = Vec::new();
    out.extend(shared("bunny", "stanford-bunny.obj"));
    out.extend(shared("teapot", "teapot.obj"));
    out.push(builtin("sphereflake"));
    out.push(builtin("teapot-in-stadium"));
    out
}

/// Every built-in scene and, when `../shared/meshes` is present, every mesh there (its `.obj`
/// files): what the kernel table and the peers benchmark measure by default, so that
/// no figure rests on the scenes a kernel was tuned on. A shared mesh's name is its file
/// name (`teapot.obj`, beside the built-in `teapot`).
///
/// # Panics
/// If the shared meshes are missing under `CI=true`, or a mesh does not load.
pub fn every_scene() -> Vec<BenchScene> {
    let mut out: Vec<BenchScene> = scenes::BUILTIN_SCENES
        .iter()
        .map(|s| builtin(s.name))
        .collect();
    let Some(dir) = shared_meshes_dir() else {
        return out;
    };
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|f| f.ends_with(".obj"))
        .collect();
    files.sort();
    for file in files {
        // A benchmark names its scenes for the whole run: the few names are leaked once.
        let name: &'static str = Box::leak(file.as_str().into());
        out.extend(shared(name, &file));
    }
    out
}

/// The scenes named by `--scenes` (`all` or nothing: [`every_scene`]; `peers`:
/// [`peer_scenes`]; else a comma-separated list of names from [`every_scene`]).
///
/// # Panics
/// If a name is none of those scenes.
pub fn chosen_scenes(list: Option<&str>) -> Vec<BenchScene> {
    match list {
        None | Some("all") => every_scene(),
        Some("peers") => peer_scenes(),
        Some(list) => {
            let names: Vec<&str> = list.split(',').collect();
            let all = every_scene();
            for n in &names {
                assert!(
                    all.iter().any(|s| s.name == *n),
                    "no scene {n}: the scenes are {}",
                    all.iter().map(|s| s.name).collect::<Vec<_>>().join(", ")
                );
            }
            all.into_iter()
                .filter(|s| names.contains(&s.name))
                .collect()
        }
    }
}

/// The flags of the benchmarks with their own harness that trace scenes (`peers`, `kernels`):
/// `--passes N` (5), `--width W` and `--height H` (1024×768), `--scenes LIST` (see
/// [`chosen_scenes`]) and `--json FILE`.
#[derive(Debug)]
pub struct RunOptions {
    /// Timed passes per contender (at least 1).
    pub passes: usize,
    /// Image width of the camera rays.
    pub width: u32,
    /// Image height of the camera rays.
    pub height: u32,
    /// `--scenes`: every scene when absent.
    pub scenes: Option<String>,
    /// Where to write the results as JSON.
    pub json: Option<String>,
}

impl RunOptions {
    /// The flags on the command line.
    ///
    /// # Panics
    /// On an unknown flag or a value that is not a number where one is needed.
    pub fn from_args() -> Self {
        let mut o = Self {
            passes: 5,
            width: 1024,
            height: 768,
            scenes: None,
            json: None,
        };
        for (flag, value) in flag_values() {
            let number =
                |what: &str| -> u32 { value.parse().unwrap_or_else(|_| panic!("{what} N")) };
            match flag.as_str() {
                "--passes" => o.passes = number("--passes").max(1) as usize,
                "--width" => o.width = number("--width"),
                "--height" => o.height = number("--height"),
                "--scenes" => o.scenes = Some(value),
                "--json" => o.json = Some(value),
                _ => panic!("unknown flag {flag}"),
            }
        }
        o
    }

    /// The scenes `--scenes` names ([`chosen_scenes`]).
    pub fn scenes(&self) -> Vec<BenchScene> {
        chosen_scenes(self.scenes.as_deref())
    }
}

/// The median of `v` (the mean of the two middle values of an even count).
///
/// # Panics
/// If `v` is empty.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The geometric mean of `v`: how the benchmarks average ratios.
pub fn geomean(v: &[f64]) -> f64 {
    (v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp()
}

/// The `--name value` pairs on the command line of a benchmark with its own harness, in order.
/// `cargo bench` adds `--bench`, which takes no value and is skipped, as is anything else that
/// does not start with `--`.
///
/// # Panics
/// If a flag other than `--bench` has no value after it.
pub fn flag_values() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--bench" || !a.starts_with("--") {
            continue;
        }
        let value = args.next().unwrap_or_else(|| panic!("{a} needs a value"));
        out.push((a, value));
    }
    out
}

/// The `--passes N` of a benchmark with its own harness (`default` without it).
///
/// # Panics
/// If `N` is not a positive number.
pub fn passes_flag(default: usize) -> usize {
    flag_values()
        .into_iter()
        .rev()
        .find(|(flag, _)| flag == "--passes")
        .map(|(_, v)| {
            v.parse()
                .ok()
                .filter(|&p: &usize| p > 0)
                .expect("--passes takes a positive number")
        })
        .unwrap_or(default)
}

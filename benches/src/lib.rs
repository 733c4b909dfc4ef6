//! Shared set-up for the benchmarks: scenes and ray sets, identical for every contender.

use rt_core::raygen::Camera;
use rt_core::{Aabb, Primitive, Ray, Triangle, conformance::shared_meshes_dir, scenes};

/// A named triangle scene.
#[derive(Debug)]
pub struct BenchScene {
    /// Short name for benchmark ids.
    pub name: &'static str,
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

    /// Primary rays of the framing camera `compare` uses.
    pub fn primary_rays(&self, width: u32, height: u32) -> Vec<Ray> {
        Camera::framing(&self.bounds(), width, height).primary_rays(width, height)
    }
}

/// The built-in default scene and, when `../shared/meshes` is present, the Stanford bunny.
///
/// # Panics
/// If the shared meshes are missing under `CI=true`, or the bunny does not load.
pub fn scenes() -> Vec<BenchScene> {
    let mut out = vec![BenchScene {
        name: "sphereflake",
        triangles: scenes::builtin("sphereflake")
            .expect("built-in scene")
            .triangles(),
    }];
    if let Some(dir) = shared_meshes_dir() {
        let mesh = rt_core::load_obj(dir.join("stanford-bunny.obj")).expect("the bunny loads");
        out.push(BenchScene {
            name: "bunny",
            triangles: mesh.triangles(),
        });
    }
    out
}

//! What a render needs besides geometry: materials, lights, a camera, a sky; and the built-in
//! scenes.

use rt_core::{Aabb, Mesh, Primitive, Shape, Sphere, glam::Vec3};
use rt_scene::Camera;
use rt_scene::scenes;

/// How a surface reflects and transmits light, in the Whitted model: a Lambert term plus a
/// Phong highlight for each light, then a mirror and a refracted ray where the surface asks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Diffuse colour (linear RGB, each in `[0, 1]`).
    pub color: Vec3,
    /// A second colour for a checkerboard of squares `checker_size` wide in world x and z
    /// (a floor's pattern); `None` for a plain colour.
    pub checker: Option<Vec3>,
    /// Side of a checker square, in scene units.
    pub checker_size: f32,
    /// Weight of the Lambert term.
    pub diffuse: f32,
    /// Weight of the Phong highlight.
    pub specular: f32,
    /// Phong exponent of the highlight.
    pub shininess: f32,
    /// Weight of the mirror reflection.
    pub mirror: f32,
    /// Weight of the Fresnel-split pair of refracted and reflected rays (glass is 1); the
    /// diffuse and mirror terms are scaled by `1 - transmission`.
    pub transmission: f32,
    /// Index of refraction inside the surface (outside is 1).
    pub ior: f32,
}

impl Material {
    /// A matte surface of this colour with a faint highlight.
    pub const fn matte(color: Vec3) -> Self {
        Self {
            color,
            checker: None,
            checker_size: 1.0,
            diffuse: 0.9,
            specular: 0.1,
            shininess: 20.0,
            mirror: 0.0,
            transmission: 0.0,
            ior: 1.0,
        }
    }

    /// A plastic: diffuse colour and a white highlight.
    pub const fn plastic(color: Vec3) -> Self {
        Self {
            specular: 0.5,
            shininess: 60.0,
            diffuse: 0.8,
            ..Self::matte(color)
        }
    }

    /// A mirror reflecting `reflectance` of the light, tinted by `color`.
    pub const fn mirror(color: Vec3, reflectance: f32) -> Self {
        Self {
            diffuse: 0.05,
            specular: 0.8,
            shininess: 200.0,
            mirror: reflectance,
            ..Self::matte(color)
        }
    }

    /// Clear glass with index of refraction `ior`.
    pub const fn glass(ior: f32) -> Self {
        Self {
            color: Vec3::ONE,
            diffuse: 0.0,
            specular: 0.8,
            shininess: 200.0,
            transmission: 1.0,
            ior,
            ..Self::matte(Vec3::ONE)
        }
    }
}

/// A point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Where it is.
    pub position: Vec3,
    /// Its colour and strength (linear RGB); no fall-off with distance, as in Whitted's model.
    pub intensity: Vec3,
}

/// A scene to render: a triangle mesh (its normals and texture coordinates included) and
/// analytic spheres, each with a material, point lights, an ambient term, a camera and a sky.
///
/// Primitive `i` of [`RenderScene::shapes`] is triangle `i` of the mesh for
/// `i < mesh.triangle_count()`, then the spheres in order, so a structure built over the shapes
/// reports hits that index both.
#[derive(Clone, Debug)]
pub struct RenderScene {
    /// The triangles.
    pub mesh: Mesh,
    /// Material index of each triangle (into [`RenderScene::materials`]).
    pub mesh_materials: Vec<u32>,
    /// The spheres.
    pub spheres: Vec<Sphere>,
    /// Material index of each sphere.
    pub sphere_materials: Vec<u32>,
    /// The materials; a missing index falls back to the first, or to a grey matte.
    pub materials: Vec<Material>,
    /// The lights.
    pub lights: Vec<PointLight>,
    /// Light that reaches every surface, shadowed or not.
    pub ambient: Vec3,
    /// The viewpoint.
    pub camera: Camera,
    /// Sky colour at the horizon and straight up (rays that hit nothing see the sky).
    pub sky: (Vec3, Vec3),
}

impl RenderScene {
    /// The primitives, triangles first, for building a structure.
    pub fn shapes(&self) -> Vec<Shape> {
        let mut shapes: Vec<Shape> = (0..self.mesh.triangle_count())
            .map(|i| Shape::Triangle(self.mesh.triangle(i)))
            .collect();
        shapes.extend(self.spheres.iter().map(|&s| Shape::Sphere(s)));
        shapes
    }

    /// The box around every valid primitive.
    pub fn bounds(&self) -> Aabb {
        self.shapes()
            .iter()
            .filter(|s| s.is_valid())
            .fold(Aabb::EMPTY, |b, s| b.union(s.bounds()))
    }

    /// The material of primitive `prim` (as [`RenderScene::shapes`] numbers them).
    pub fn material(&self, prim: usize) -> &Material {
        const GREY: Material = Material::matte(Vec3::splat(0.7));
        let n = self.mesh.triangle_count();
        let index = if prim < n {
            self.mesh_materials.get(prim)
        } else {
            self.sphere_materials.get(prim - n)
        };
        index
            .and_then(|&m| self.materials.get(m as usize))
            .or(self.materials.first())
            .unwrap_or(&GREY)
    }

    /// A mesh as a scene: one plastic material, a white light above and to the side at twice
    /// the mesh's radius ([`rt_scene::raygen::default_light`]), a dim fill light from the camera's
    /// side, and `camera` (for example [`Camera::framing`] the mesh).
    pub fn from_mesh(mesh: Mesh, camera: Camera) -> Self {
        let bounds = mesh.bounds();
        let key = rt_scene::raygen::default_light(&bounds);
        let fill = camera.eye + (camera.eye - bounds.center()) * 0.5 + Vec3::Y * 0.1;
        Self {
            mesh_materials: vec![0; mesh.triangle_count()],
            mesh,
            spheres: Vec::new(),
            sphere_materials: Vec::new(),
            materials: vec![Material::plastic(Vec3::new(0.75, 0.72, 0.65))],
            lights: vec![
                PointLight {
                    position: key,
                    intensity: Vec3::splat(0.85),
                },
                PointLight {
                    position: fill,
                    intensity: Vec3::splat(0.2),
                },
            ],
            ambient: Vec3::splat(0.08),
            camera,
            sky: (Vec3::new(0.85, 0.87, 0.9), Vec3::new(0.45, 0.58, 0.8)),
        }
    }

    /// The built-in Whitted scene: a checkerboard floor, a glass sphere, a mirror sphere and the
    /// procedural teapot ([`rt_scene::scenes::teapot`], 44k triangles), two lights and its own
    /// camera. Named `whitted` in [`scene`].
    pub fn whitted() -> Self {
        let mut mesh = Mesh::new(
            vec![
                Vec3::new(-30.0, 0.0, -30.0),
                Vec3::new(30.0, 0.0, -30.0),
                Vec3::new(30.0, 0.0, 30.0),
                Vec3::new(-30.0, 0.0, 30.0),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        )
        .expect("floor indices are in range");
        let floor = Material {
            checker: Some(Vec3::new(0.75, 0.12, 0.1)),
            checker_size: 1.5,
            diffuse: 0.9,
            specular: 0.0,
            ..Material::matte(Vec3::new(0.9, 0.88, 0.8))
        };
        let mut mesh_materials = vec![0; 2];
        // The procedural teapot has no normals of its own: smooth ones hide its facets.
        let teapot = scenes::teapot(0.0).with_smooth_normals();
        mesh_materials.resize(2 + teapot.triangle_count(), 1);
        mesh.append(&teapot);
        Self {
            mesh,
            mesh_materials,
            spheres: vec![
                Sphere::new(Vec3::new(-1.6, 1.1, 3.4), 1.1),
                Sphere::new(Vec3::new(3.3, 1.6, -1.6), 1.6),
            ],
            sphere_materials: vec![2, 3],
            materials: vec![
                floor,
                Material::plastic(Vec3::new(0.25, 0.45, 0.8)),
                Material::glass(1.5),
                Material::mirror(Vec3::new(0.95, 0.95, 0.9), 0.9),
            ],
            lights: vec![
                PointLight {
                    position: Vec3::new(-6.0, 11.0, 9.0),
                    intensity: Vec3::splat(0.75),
                },
                PointLight {
                    position: Vec3::new(9.0, 7.0, 6.0),
                    intensity: Vec3::splat(0.35),
                },
            ],
            ambient: Vec3::splat(0.1),
            camera: Camera {
                eye: Vec3::new(1.0, 4.2, 11.5),
                target: Vec3::new(0.3, 1.0, 0.0),
                up: Vec3::Y,
                vfov_deg: 42.0,
            },
            sky: (Vec3::new(0.85, 0.88, 0.95), Vec3::new(0.3, 0.45, 0.8)),
        }
    }

    /// The same scene with every coordinate (geometry, lights, camera, checker squares)
    /// multiplied by `factor > 0`: it must render the same picture, which is how the tests
    /// check that secondary rays never hit their own surface at any scale.
    pub fn scaled(mut self, factor: f32) -> Self {
        self.mesh = self.mesh.scaled(factor);
        for s in &mut self.spheres {
            *s = Sphere::new(s.center * factor, s.radius * factor);
        }
        for l in &mut self.lights {
            l.position *= factor;
        }
        for m in &mut self.materials {
            m.checker_size *= factor;
        }
        self.camera.eye *= factor;
        self.camera.target *= factor;
        self
    }
}

/// The names [`scene`] accepts besides files: `whitted` and every built-in mesh scene of
/// [`rt_scene::scenes`].
pub fn builtin_names() -> Vec<&'static str> {
    let mut names = vec!["whitted"];
    names.extend(scenes::BUILTIN_SCENES.iter().map(|s| s.name));
    names
}

/// The scene called `spec` for a `width × height` image: `whitted`, a built-in mesh scene
/// (`sphereflake`, `teapot-in-stadium`, ...) with its own camera when it has one, or, for
/// anything else, an OBJ file with [`RenderScene::from_mesh`]'s defaults and a camera framing it.
///
/// # Errors
/// The loader's error (naming the file and line) for a file that cannot be read or parsed.
pub fn scene(spec: &str, width: u32, height: u32) -> Result<RenderScene, rt_scene::LoadError> {
    if spec == "whitted" {
        return Ok(RenderScene::whitted());
    }
    let mesh = match scenes::builtin(spec) {
        Some(mesh) => mesh,
        None => rt_scene::load_mesh(spec)?,
    };
    let bounds = mesh.bounds();
    let camera = scenes::camera_for(spec, &bounds, width, height);
    Ok(RenderScene::from_mesh(mesh, camera))
}

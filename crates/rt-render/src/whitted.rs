//! Whitted-style recursive ray tracing (Whitted, "An Improved Illumination Model for Shaded
//! Display", 1980): at each hit, a Lambert term and a Phong highlight for every light that a
//! shadow ray sees, then a mirror ray and a refracted ray (Snell's law, Schlick's Fresnel
//! weights, total internal reflection) where the material asks, to a fixed depth.

use crate::{Material, PointLight, RenderScene};
use rt_core::DynAccel;
use rt_core::{Hit, Primitive, Ray, Shape, SurfacePoint, glam::Vec3};

/// Everything one pixel's rays need, borrowed once per render.
pub(crate) struct Context<'a> {
    pub scene: &'a RenderScene,
    pub shapes: &'a [Shape],
    pub tracer: &'a dyn DynAccel<Shape>,
    pub max_depth: u32,
}

/// A hit ready to shade: the surface, its normals turned towards the viewer, and the viewing
/// direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lit {
    prim: usize,
    pub at: SurfacePoint,
    /// Unit shading normal, facing the viewer.
    pub normal: Vec3,
    /// Geometric normal, facing the viewer.
    pub geometric: Vec3,
    /// The ray's unit direction.
    d: Vec3,
    /// Whether the ray arrives at the front of the surface.
    entering: bool,
}

/// What the renderer knows of a hit after re-deriving it from the primitive itself.
struct Surface {
    /// Point, geometric normal and error bound (for spawning rays).
    at: SurfacePoint,
    /// Unit shading normal, on the same side as `at.normal`.
    normal: Vec3,
}

impl Context<'_> {
    /// The colour (linear RGB) seen along `ray`, which has `depth` bounces behind it.
    pub fn radiance(&self, ray: &Ray, depth: u32) -> Vec3 {
        match self.tracer.intersect_dyn(ray, None) {
            Some(hit) => self.shade(ray, hit, depth),
            None => self.sky(ray.dir()),
        }
    }

    /// The colours seen along `rays`, the primary rays and the first shadow rays traced as
    /// bundles ([`DynAccel::intersect_bundle_dyn`], [`DynAccel::occluded_bundle_dyn`]): the
    /// shadow rays towards each light, in the order of their pixels, make one batch. Deeper
    /// rays go one by one. Each answer is the single ray's, so the colours are
    /// [`Context::radiance`]'s to the bit.
    pub fn radiance_bundle(&self, rays: &[Ray]) -> Vec<Vec3> {
        let mut hits = vec![None; rays.len()];
        self.tracer.intersect_bundle_dyn(rays, &mut hits, None);
        let lits: Vec<Option<Lit>> = rays
            .iter()
            .zip(&hits)
            .map(|(ray, hit)| hit.map(|hit| self.lit(ray, hit)))
            .collect();
        // Each pixel's shadow ray towards each light, if any: its index in `shadow`.
        let lights = &self.scene.lights;
        let mut slot = vec![u32::MAX; rays.len() * lights.len()];
        let mut shadow = Vec::new();
        for (k, light) in lights.iter().enumerate() {
            for (i, lit) in lits.iter().enumerate() {
                if let Some((ray, ..)) = lit.as_ref().and_then(|l| self.shadow_ray(l, light)) {
                    slot[i * lights.len() + k] = shadow.len() as u32;
                    shadow.push(ray);
                }
            }
        }
        let mut blocked = vec![false; shadow.len()];
        self.tracer.occluded_bundle_dyn(&shadow, &mut blocked, None);
        rays.iter()
            .zip(&lits)
            .enumerate()
            .map(|(i, (ray, lit))| match lit {
                Some(lit) => self.shade_lit(lit, 0, |k, ray| {
                    match blocked.get(slot[i * lights.len() + k] as usize) {
                        Some(&b) => b,
                        // Not planned above (it always is): trace it now.
                        None => self.tracer.occluded_dyn(ray, None),
                    }
                }),
                None => self.sky(ray.dir()),
            })
            .collect()
    }

    /// The sky's colour seen in direction `dir`.
    pub fn sky(&self, dir: Vec3) -> Vec3 {
        let (horizon, zenith) = self.scene.sky;
        let up = dir.normalize_or_zero().y.max(0.0);
        horizon.lerp(zenith, up.sqrt())
    }

    /// The surface the structure reported. The hit's `t`, `u`, `v` are recomputed by the
    /// primitive's own test on the same ray: structures must agree on the primitive exactly
    /// but on `t` only within a tolerance, and re-deriving it makes the picture depend on the
    /// primitive alone, so every correct structure renders the same bytes.
    fn surface(&self, ray: &Ray, hit: Hit) -> Surface {
        let prim = hit.prim as usize;
        let shape = &self.shapes[prim];
        let (t, u, v) = match shape.intersect(ray, ray.t_max) {
            Some(h) => (h.t, h.u, h.v),
            None => (hit.t, hit.u, hit.v),
        };
        match shape {
            Shape::Triangle(_) if prim < self.scene.mesh.triangle_count() => {
                let s = self.scene.mesh.shading(prim, u, v);
                Surface {
                    at: s.surface,
                    normal: s.normal,
                }
            }
            _ => {
                let at = shape.surface(ray, t, u, v);
                Surface {
                    at,
                    normal: at.normal,
                }
            }
        }
    }

    fn shade(&self, ray: &Ray, hit: Hit, depth: u32) -> Vec3 {
        let lit = self.lit(ray, hit);
        self.shade_lit(&lit, depth, |_, shadow| {
            self.tracer.occluded_dyn(shadow, None)
        })
    }

    /// The surface at `hit` seen along `ray`, its normals turned to face the viewer.
    pub fn lit(&self, ray: &Ray, hit: Hit) -> Lit {
        let Surface { at, mut normal } = self.surface(ray, hit);
        let d = ray.dir().normalize();
        // Face the viewer: flip both normals when the ray arrives from the back (or from inside
        // a glass sphere); `entering` says which side of a refracting surface we are on.
        let entering = d.dot(at.normal) < 0.0;
        let geometric = if entering { at.normal } else { -at.normal };
        if normal.dot(geometric) < 0.0 {
            normal = -normal;
        }
        // An interpolated normal can face away from the viewer near silhouettes; the geometric
        // one cannot.
        if normal.dot(d) >= 0.0 {
            normal = geometric;
        }
        Lit {
            prim: hit.prim as usize,
            at,
            normal,
            geometric,
            d,
            entering,
        }
    }

    /// The shadow ray from `lit` to `light`, and the cosine at the surface, if the light is in
    /// front of it (lights behind the surface, as the geometry faces, cannot reach it).
    pub fn shadow_ray(&self, lit: &Lit, light: &PointLight) -> Option<(Ray, f32, Vec3)> {
        let to_light = light.position - lit.at.point;
        let l = to_light.normalize_or_zero();
        let lambert = lit.normal.dot(l);
        if lambert <= 0.0 || lit.geometric.dot(l) <= 0.0 {
            return None;
        }
        Some((lit.at.spawn_ray_to(light.position), lambert, l))
    }

    /// The colour of `lit`, which has `depth` bounces behind it; `occluded(k, shadow)` answers
    /// whether the shadow ray towards light `k` is blocked (a renderer tracing bundles has
    /// traced it already).
    pub fn shade_lit(
        &self,
        lit: &Lit,
        depth: u32,
        mut occluded: impl FnMut(usize, &Ray) -> bool,
    ) -> Vec3 {
        let material = self.scene.material(lit.prim);
        let &Lit { at, normal, d, .. } = lit;
        let albedo = albedo(material, at.point);
        let opaque = 1.0 - material.transmission;
        let mut color = self.scene.ambient * albedo * material.diffuse * opaque;
        for (k, light) in self.scene.lights.iter().enumerate() {
            let Some((shadow, lambert, l)) = self.shadow_ray(lit, light) else {
                continue;
            };
            if occluded(k, &shadow) {
                continue;
            }
            let diffuse = albedo * (material.diffuse * opaque * lambert);
            let half = (l - d).normalize_or_zero();
            let highlight = material.specular * normal.dot(half).max(0.0).powf(material.shininess);
            color += light.intensity * (diffuse + Vec3::splat(highlight));
        }
        if depth + 1 >= self.max_depth {
            return color;
        }
        let r = lit.reflected();
        if material.mirror > 0.0 {
            color += material.mirror
                * opaque
                * material.color
                * self.radiance(&at.spawn_ray(r), depth + 1);
        }
        if material.transmission > 0.0 {
            let reflected = self.radiance(&at.spawn_ray(r), depth + 1);
            let light = match lit.refracted(material.ior) {
                Some((t, fresnel)) => {
                    fresnel * reflected
                        + (1.0 - fresnel) * self.radiance(&at.spawn_ray(t), depth + 1)
                }
                // Total internal reflection.
                None => reflected,
            };
            color += material.transmission * material.color * light;
        }
        color
    }
}

impl Lit {
    /// The mirror direction of the view direction. It leaves on the viewer's side of the
    /// geometry: where the shading normal would bend it below, the geometric normal reflects.
    pub fn reflected(&self) -> Vec3 {
        let d = self.d;
        let reflect = |n: Vec3| d - 2.0 * d.dot(n) * n;
        let r = reflect(self.normal);
        if r.dot(self.geometric) <= 0.0 {
            reflect(self.geometric)
        } else {
            r
        }
    }

    /// The refracted direction into (or out of) a surface of index of refraction `ior`, with
    /// the share of the light reflected instead (Schlick's approximation of the Fresnel term);
    /// `None` at total internal reflection.
    pub fn refracted(&self, ior: f32) -> Option<(Vec3, f32)> {
        let (d, normal) = (self.d, self.normal);
        let eta = if self.entering { 1.0 / ior } else { ior };
        let cos_i = -d.dot(normal);
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        if sin2_t >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        let t = (eta * d + (eta * cos_i - cos_t) * normal).normalize();
        // Schlick's approximation, with the cosine on the optically thinner side.
        let r0 = ((1.0 - ior) / (1.0 + ior)).powi(2);
        let c = if self.entering { cos_i } else { cos_t };
        Some((t, r0 + (1.0 - r0) * (1.0 - c).powi(5)))
    }
}

/// The diffuse colour of `material` at `point`: its colour, or its checkerboard's square there.
pub(crate) fn albedo(material: &Material, point: Vec3) -> Vec3 {
    match material.checker {
        Some(other) => {
            let s = material.checker_size;
            let (i, k) = ((point.x / s).floor() as i64, (point.z / s).floor() as i64);
            if (i + k).rem_euclid(2) == 0 {
                material.color
            } else {
                other
            }
        }
        None => material.color,
    }
}

//! Procedural scenes built into the library, so that tests and `cargo xtask compare` need no files.

use crate::{Mesh, Rng};
use glam::Vec3;

/// A built-in scene: its name (what `--scene` takes) and a one-line description.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// Name accepted by [`builtin`].
    pub name: &'static str,
    /// What the scene is and why it is interesting.
    pub description: &'static str,
    make: fn() -> Mesh,
}

/// Every built-in scene; the first is the default of `compare`.
pub const BUILTIN_SCENES: &[BuiltinScene] = &[
    BuiltinScene {
        name: "sphereflake",
        description: "Haines' sphereflake (820 tessellated spheres over four orders of size, 82k triangles) on a ground quad",
        make: || sphereflake(3, 6, 10),
    },
    BuiltinScene {
        name: "random-soup",
        description: "20k random triangles of random size in a cube: no structure to exploit",
        make: || random_soup(20_000, 7),
    },
];

/// The built-in scene called `name`, if there is one.
pub fn builtin(name: &str) -> Option<Mesh> {
    BUILTIN_SCENES
        .iter()
        .find(|s| s.name == name)
        .map(|s| (s.make)())
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

/// `count` random triangles with random orientation, edge lengths up to a tenth of the unit
/// cube they fill.
pub fn random_soup(count: usize, seed: u64) -> Mesh {
    let mut rng = Rng::new(seed);
    let mut positions = Vec::with_capacity(3 * count);
    for _ in 0..count {
        let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
        let size = rng.range(0.005, 0.1);
        for _ in 0..3 {
            positions.push(c + rng.unit_vector() * size);
        }
    }
    let indices = (0..count as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    Mesh::new(positions, indices).expect("random_soup indices are in range by construction")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Primitive;

    #[test]
    fn builtins_are_valid() {
        for s in BUILTIN_SCENES {
            let m = builtin(s.name).unwrap();
            assert!(m.triangle_count() > 1000, "{}", s.name);
            assert!(m.triangles().iter().all(|t| t.is_valid()), "{}", s.name);
        }
        assert!(builtin("nope").is_none());
    }

    #[test]
    fn sphereflake_size() {
        let m = sphereflake(3, 6, 10);
        // 1 + 9 + 81 + 729 spheres of 2·10·5 triangles, plus the ground quad.
        assert_eq!(m.triangle_count(), 820 * 100 + 2);
    }
}

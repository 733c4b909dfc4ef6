//! Meshes the unit tests share.

use glam::Vec3;
use rt_core::Triangle;

/// A closed UV sphere of radius `r` around `c`, faces outwards.
pub(crate) fn sphere(c: Vec3, r: f32, rings: usize, segments: usize) -> Vec<Triangle> {
    let at = |i: usize, j: usize| {
        // The poles exactly, so that the sphere is closed: `sin(π)` is not 0 in `f32`.
        if i == 0 || i == rings {
            return c + Vec3::new(0.0, 0.0, if i == 0 { r } else { -r });
        }
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::TAU * (j % segments) as f32 / segments as f32;
        c + r * Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    };
    let mut tris = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, cc, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            tris.push(Triangle::new(a, b, cc));
            tris.push(Triangle::new(a, cc, d));
        }
    }
    tris
}

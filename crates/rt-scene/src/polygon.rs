//! Polygons to triangles, shared by the OBJ and PLY loaders (both allow faces of any size).

use glam::{Vec2, Vec3};

/// Splits one polygon (its corners' position indices) into triangles by ear clipping in the
/// plane of its Newell normal, emitting each triangle as three corner numbers (`0..face.len()`),
/// so the caller can pick each corner's position, normal and texture coordinate.
///
/// Degenerate polygons (no normal) and very large ones, where ear clipping's quadratic passes
/// would cost too much, fall back to a fan. When no ear is found (self-intersecting input), a
/// convex corner (or else the first one) is clipped anyway, so the loop always ends after
/// `n - 2` triangles.
pub(crate) fn triangulate(face: &[u32], pos: &[Vec3], mut emit: impl FnMut([usize; 3])) {
    const EAR_CLIPPING_LIMIT: usize = 256;
    let n = face.len();
    if n == 3 {
        emit([0, 1, 2]);
        return;
    }
    let p = |i: u32| pos[i as usize];
    let mut normal = Vec3::ZERO;
    for k in 0..n {
        let (a, b) = (p(face[k]), p(face[(k + 1) % n]));
        normal += Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    if normal == Vec3::ZERO || !normal.is_finite() || n > EAR_CLIPPING_LIMIT {
        for k in 1..n - 1 {
            emit([0, k, k + 1]);
        }
        return;
    }
    // Drop the dominant axis; flip one kept axis if needed so the polygon winds counter-clockwise.
    let a = normal.abs();
    let (ax, ay, sign) = if a.x >= a.y && a.x >= a.z {
        (1, 2, normal.x)
    } else if a.y >= a.z {
        (2, 0, normal.y)
    } else {
        (0, 1, normal.z)
    };
    let flat: Vec<Vec2> = face
        .iter()
        .map(|&i| Vec2::new(p(i)[ax], if sign < 0.0 { -p(i)[ay] } else { p(i)[ay] }))
        .collect();
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut ring: Vec<usize> = (0..n).collect();
    while ring.len() > 3 {
        let m = ring.len();
        let is_ear = |k: usize| {
            let (i0, i1, i2) = (ring[(k + m - 1) % m], ring[k], ring[(k + 1) % m]);
            let (a, b, c) = (flat[i0], flat[i1], flat[i2]);
            if cross(a, b, c) <= 0.0 {
                return false;
            }
            // A corner blocks the ear if it lies inside or on it, unless it sits exactly on one
            // of the ear's corners: keyhole polygons (holes bridged into the outline) repeat
            // positions, and such a twin must not block the ear it belongs to.
            ring.iter().all(|&j| {
                let q = flat[j];
                j == i0
                    || j == i1
                    || j == i2
                    || q == a
                    || q == b
                    || q == c
                    || !(cross(a, b, q) >= 0.0 && cross(b, c, q) >= 0.0 && cross(c, a, q) >= 0.0)
            })
        };
        let convex = |k: usize| {
            let (i0, i1, i2) = (ring[(k + m - 1) % m], ring[k], ring[(k + 1) % m]);
            cross(flat[i0], flat[i1], flat[i2]) > 0.0
        };
        let k = (0..m)
            .find(|&k| is_ear(k))
            .or_else(|| (0..m).find(|&k| convex(k)))
            .unwrap_or(0);
        emit([ring[(k + m - 1) % m], ring[k], ring[(k + 1) % m]]);
        ring.remove(k);
    }
    emit([ring[0], ring[1], ring[2]]);
}

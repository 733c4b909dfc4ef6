//! The winding number by counting crossings, exact and cheap.
//!
//! # The idea
//! Around a point off a *closed* surface, the winding number is an integer: the number of
//! times any ray from the point crosses the surface outwards, minus the times it crosses
//! inwards. A mesh with holes is not closed, but it becomes closed once each hole is capped:
//! for every boundary loop, triangles between the loop's own vertices, turned so that each cap
//! edge cancels its mesh edge. The winding number is additive over triangles,
//! so for the mesh `M` and its caps `C`:
//!
//! ```text
//! w_M(q) = w_{M+C}(q) − w_C(q) = (signed crossings of one ray with M and C) − w_C(q)
//! ```
//!
//! The first term is an integer found by tracing one ray; the second is the winding number
//! of the caps alone, a few triangles where a mesh has a few holes, evaluated by its own
//! [`WindingTree`] with an error bound. A closed mesh has no caps, and its winding number is
//! the crossing count. This holds for any mesh: self-intersecting, non-manifold, inside out,
//! nested; the caps close exactly the chain of triangles the tree holds, whatever their shape.
//!
//! # Why the count is exact
//! The ray runs along a coordinate axis, so whether it crosses a triangle is the sign of
//! three 2D orientations (which side of each edge the point's projection lies on) and one 3D
//! orientation (which side of the triangle's plane the point lies on, which says whether the
//! crossing is ahead of it). Each is computed in `f64` from the `f32` coordinates and kept
//! only when its magnitude exceeds Shewchuk's error bound for that expression ("Adaptive
//! precision floating-point arithmetic and fast robust geometric predicates", 1997), which
//! makes its sign the exact one. A ray through an edge or a vertex, or from a point on a
//! triangle, has an orientation of exactly 0, which no bound certifies: that ray is given up
//! and the next axis tried, and when all six are given up the winding number is evaluated by
//! the tree ([`WindingTree::winding_number`] says how). So every counted crossing is a true
//! transversal crossing, and the count is the exact integer.
//!
//! The ray walks the tree's clusters, visiting those whose bounding sphere it meets, along the
//! axis on which it leaves the mesh's bounding box soonest.
//!
//! Caps are worth it while they are few: a triangle soup has three boundary edges per
//! triangle, and its caps would cost more than the mesh. Past 256 cap triangles (or
//! a quarter of the mesh's, whichever is more), the tree keeps none and always evaluates.
//! Caps of an open sheet are as large as the sheet, but even then they usually pay: points
//! near a sheet have winding numbers near ½, which the tree alone must evaluate closely.

use crate::winding::WindingTree;
use glam::{DVec3, Vec3};
use std::collections::HashMap;

// PERF: `is_inside` at 10,000 points (half in the box grown by a quarter, half near the
// surface; AMD Zen 3, one thread), the tree's evaluation alone ÷ crossings with caps, best
// of two alternated runs: closed meshes (no caps) 12–22×; bunny (223 caps) 9.7×; suzanne
// (42) 6.6×; the shared teapot (160) 4.5×; the built-in teapot (912) 3.1×; terrain (896)
// 9.0×; woody (119) 1.3×; beetle (1,136) 1.3×; alligator (433, an open sheet) 0.99×. A
// soup of 20,000 triangles (60,000 caps) with caps: 0.43×.
/// Cap triangles a tree keeps at least: see the [module documentation](self). Above this,
/// it keeps caps while they are at most a quarter as many as the mesh's triangles.
pub(crate) const MAX_CAPS: usize = 256;

/// Shewchuk's `ε`: half an ulp of 1 in `f64`.
const EPS: f64 = f64::EPSILON / 2.0;
/// Shewchuk's bound on the error of the 2D orientation, relative to its permanent.
const ORIENT2_BOUND: f64 = (3.0 + 16.0 * EPS) * EPS;
/// Shewchuk's bound on the error of the 3D orientation, relative to its permanent.
const ORIENT3_BOUND: f64 = (7.0 + 56.0 * EPS) * EPS;

/// A ray from the query point along a coordinate axis: the axis `k`, the two others `(i, j)`
/// in cyclic order, and the direction along `k` (`+1.0` or `-1.0`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct AxisRay {
    pub(crate) origin: DVec3,
    pub(crate) k: usize,
    pub(crate) i: usize,
    pub(crate) j: usize,
    pub(crate) dir: f64,
}

impl AxisRay {
    /// The six axis rays from `q`, the one that leaves the box `[lo, hi]` soonest first.
    pub(crate) fn from_point(q: DVec3, lo: Vec3, hi: Vec3) -> [AxisRay; 6] {
        let mut rays = [0, 1, 2, 3, 4, 5].map(|n| {
            let k = n % 3;
            AxisRay {
                origin: q,
                k,
                i: (k + 1) % 3,
                j: (k + 2) % 3,
                dir: if n < 3 { 1.0 } else { -1.0 },
            }
        });
        let exit = |r: &AxisRay| {
            if r.dir > 0.0 {
                f64::from(hi[r.k]) - q[r.k]
            } else {
                q[r.k] - f64::from(lo[r.k])
            }
        };
        rays.sort_by(|a, b| exit(a).total_cmp(&exit(b)));
        rays
    }

    /// Whether the ray may meet the ball of `radius` around `center`. Never `false` for a
    /// ball it meets: the margin covers the rounding of the test.
    #[inline]
    pub(crate) fn meets_ball(&self, center: [f64; 3], radius: f64) -> bool {
        let (di, dj) = (
            center[self.i] - self.origin[self.i],
            center[self.j] - self.origin[self.j],
        );
        let dk = (center[self.k] - self.origin[self.k]) * self.dir;
        let scale = self.origin.abs().max_element() + radius + di.abs().max(dj.abs()).max(dk.abs());
        let reach = radius + 1e-12 * scale;
        dk >= -reach && di * di + dj * dj <= reach * reach
    }

    /// The crossing of the ray with the triangle `t`: `Some(1)` where it leaves through the
    /// triangle's front (the side its normal `(v1 − v0) × (v2 − v0)` points to), `Some(-1)`
    /// where it enters through it, `Some(0)` where it misses, and `None` where that cannot be
    /// told exactly (the ray meets an edge or a vertex, or starts on the triangle).
    #[inline]
    pub(crate) fn crossing(&self, t: &[Vec3; 3]) -> Option<i32> {
        let q = self.origin;
        let [a, b, c] = t.map(|v| v.as_dvec3() - q);
        let (i, j) = (self.i, self.j);
        // Which side of each edge the point lies on, seen along the axis: the sign of the
        // orientation, where its error bound certifies it. An edge along the axis is seen as
        // a point, and its orientation is 0 wherever the point is: the ray meets it only when
        // the point is that point, and otherwise it leaves the triangle flat (missed). Along
        // the axis means equal coordinates as given: differences from the point may round
        // to equal ones.
        let side = |m: usize, n: usize| -> Option<f64> {
            let (u, v) = ([a, b, c][m], [a, b, c][n]);
            if t[m][i] == t[n][i] && t[m][j] == t[n][j] {
                let on = f64::from(t[m][i]) == q[i] && f64::from(t[m][j]) == q[j];
                return (!on).then_some(0.0);
            }
            let (l, r) = (u[i] * v[j], u[j] * v[i]);
            let det = l - r;
            (det.abs() > ORIENT2_BOUND * (l.abs() + r.abs())).then_some(det)
        };
        let ab = side(0, 1)?;
        let bc = side(1, 2)?;
        let ca = side(2, 0)?;
        let inside = (ab > 0.0 && bc > 0.0 && ca > 0.0) || (ab < 0.0 && bc < 0.0 && ca < 0.0);
        if !inside {
            return Some(0);
        }
        // The triangle's plane against the point: `det [a, b, c]` is `n · (v0 − q)`.
        let k = self.k;
        let (bc_k, ca_k, ab_k) = (
            b[i] * c[j] - c[i] * b[j],
            c[i] * a[j] - a[i] * c[j],
            a[i] * b[j] - b[i] * a[j],
        );
        let det = a[k] * bc_k + b[k] * ca_k + c[k] * ab_k;
        let permanent = ((b[i] * c[j]).abs() + (c[i] * b[j]).abs()) * a[k].abs()
            + ((c[i] * a[j]).abs() + (a[i] * c[j]).abs()) * b[k].abs()
            + ((a[i] * b[j]).abs() + (b[i] * a[j]).abs()) * c[k].abs();
        if det.abs() <= ORIENT3_BOUND * permanent {
            return None;
        }
        // The crossing lies ahead when the plane is on the side the ray runs to: `n · (v0 − q)`
        // has the sign of `n · dir`, which is the sign of the projected orientation `ab`
        // along `dir`. It then counts as the sign of `det`: outwards positive.
        let ahead = (det > 0.0) == (ab * self.dir > 0.0);
        Some(if !ahead {
            0
        } else if det > 0.0 {
            1
        } else {
            -1
        })
    }
}

/// The caps that close the triangles `tris` (as [the module documentation](self) says): the
/// edges the triangles leave unmatched (each as many times as it is unmatched) are followed
/// into closed walks, and each walk is closed by triangles between its own vertices, turned
/// against it: [`close_walk`]. Vertices are matched by position.
pub(crate) fn caps(tris: &[[Vec3; 3]]) -> Vec<[Vec3; 3]> {
    // Vertex ids by position; −0.0 and 0.0 are the same point.
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(tris.len());
    let mut points: Vec<Vec3> = Vec::with_capacity(tris.len());
    let mut id = |v: Vec3| {
        let key = (v + Vec3::ZERO).to_array().map(f32::to_bits);
        *ids.entry(key).or_insert_with(|| {
            points.push(v);
            points.len() as u32 - 1
        })
    };
    // Each undirected edge with how many more times it runs from its smaller id than back.
    let mut edges: HashMap<(u32, u32), i64> = HashMap::with_capacity(3 * tris.len() / 2);
    for t in tris {
        let v = t.map(&mut id);
        for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
            if a != b {
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
            }
        }
    }
    // The unmatched edges, directed as the triangles leave them, in a fixed order.
    let mut boundary: Vec<(u32, u32, i64)> = edges
        .into_iter()
        .filter(|&(_, n)| n != 0)
        .map(|((a, b), n)| if n > 0 { (a, b, n) } else { (b, a, -n) })
        .collect();
    boundary.sort_unstable();
    // Closed walks along the unmatched edges, each edge taken as many times as it is
    // unmatched. Every vertex has as many unmatched edges leaving it as entering it (the
    // boundary of triangles is a cycle), so a walk can only stop where it started.
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    for &(a, b, n) in boundary.iter().rev() {
        // Reversed, so that popping takes each vertex's edges in ascending order.
        next.entry(a)
            .or_default()
            .extend(std::iter::repeat_n(b, n as usize));
    }
    let mut caps = Vec::new();
    let mut walk = Vec::new();
    for &(start, _, _) in &boundary {
        while let Some(mut at) = next.get_mut(&start).and_then(Vec::pop) {
            walk.clear();
            walk.push(start);
            while at != start {
                walk.push(at);
                match next.get_mut(&at).and_then(Vec::pop) {
                    Some(to) => at = to,
                    None => break, // cannot happen for a cycle; close what was walked
                }
            }
            close_walk(&walk, &points, &mut caps);
        }
    }
    caps
}

/// Appends triangles that close the closed walk `walk` (vertex ids into `points`, the last
/// joined back to the first), turned against it, so that each of its edges is matched by one
/// running back and every edge between the triangles by another.
///
/// The walk is split in halves by a chord from its first vertex to its middle one, and each
/// half (with the chord) is closed in the same way, down to triangles. All but a few of the
/// triangles join vertices close together along the walk, so they are small, and the tree's
/// clusters of them are small too: a point near a hole can take their expansions, where a fan
/// from one apex (which caps used to be) gives every triangle the hole's size, and a point
/// within that distance had to sum them all.
// PERF: inside tests of 20,000 points in the box grown by a quarter, one thread, AMD Zen 3, a
// scratch harness timing `is_inside`, fans then halves in three alternating runs, µs a point:
// the beetle (11 holes, of up to 512 edges) 20.1 19.1 18.8 -> 9.6 9.3 11.4; the bunny (5 holes,
// of up to 80 edges) 1.0 1.0 1.0 -> 1.7 1.2 1.7, where a fan from each hole's mean was no faster
// for the pieces of up to 16 vertices (1.3 1.3 1.2). The share by area in the tree's first
// walk (`WindingTree::evaluate`) then brought the bunny back to 0.9-1.0.
fn close_walk(walk: &[u32], points: &[Vec3], caps: &mut Vec<[Vec3; 3]>) {
    match *walk {
        [] | [_] | [_, _] => {} // a walk of two edges there and back needs nothing
        [a, b, c] => {
            // A triangle with a repeated vertex matches nothing but itself: leave it out.
            if a != b && b != c && c != a {
                caps.push([points[a as usize], points[c as usize], points[b as usize]]);
            }
        }
        _ => {
            // The first half with the chord back from its last vertex to the first, then the
            // second half with the chord from the first vertex to its first: the two chords
            // run opposite ways and match.
            let mid = walk.len() / 2;
            close_walk(&walk[..=mid], points, caps);
            let mut second = walk[mid..].to_vec();
            second.push(walk[0]);
            close_walk(&second, points, caps);
        }
    }
}

impl WindingTree {
    /// The signed count of the crossings of `ray` with the tree's triangles (see
    /// [`AxisRay::crossing`]), or `None` if one of them cannot be told exactly.
    pub(crate) fn crossings(&self, ray: &AxisRay) -> Option<i64> {
        let mut count = 0i64;
        let mut stack = [0u32; 64];
        let mut top = 0usize;
        let mut next = (!self.nodes.is_empty()).then_some(0usize);
        while let Some(n) = next.take().or_else(|| {
            top = top.checked_sub(1)?;
            Some(stack[top] as usize)
        }) {
            let c = &self.nodes[n];
            if !ray.meets_ball(c.center, c.radius) {
                continue;
            }
            if c.count > 0 {
                let (first, len) = (c.first as usize, c.count as usize);
                for t in &self.tris[first..first + len] {
                    count += i64::from(ray.crossing(t)?);
                }
            } else {
                // Depth below 33 (see `walk`): 64 slots never run out.
                stack[top] = c.first;
                top += 1;
                next = Some(n + 1);
            }
        }
        Some(count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_meshes::sphere;
    use crate::winding_number_exact;
    use rt_core::{Rng, Triangle};

    /// The unit cube `[0, 1]³` as 12 triangles facing outwards: every face in an axis plane.
    fn cube() -> Vec<Triangle> {
        rt_core::Mesh::cuboid(Vec3::ZERO, Vec3::ONE).triangles()
    }

    /// Meshes with every kind of boundary: closed, one hole, a crack of unmatched vertices
    /// (matched by position), a triangle turned inside out, two overlapping spheres, a
    /// sphere with a loose soup, and the soup alone.
    fn meshes(rng: &mut Rng) -> Vec<(&'static str, Vec<Triangle>)> {
        let closed = sphere(Vec3::ZERO, 1.0, 12, 24);
        let mut holed = closed.clone();
        holed.drain(..30);
        let mut flipped = closed.clone();
        for t in flipped.iter_mut().step_by(50) {
            *t = Triangle::new(t.v0, t.v2, t.v1);
        }
        let mut overlapping = closed.clone();
        overlapping.extend(sphere(Vec3::new(0.6, 0.2, 0.1), 0.8, 10, 20));
        let soup: Vec<Triangle> = (0..40)
            .map(|_| {
                let mut p = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3::ONE;
                let a = p();
                Triangle::new(a, a + p() * 0.3, a + p() * 0.3)
            })
            .collect();
        let mut with_soup = holed.clone();
        with_soup.extend(soup.iter().copied());
        vec![
            ("closed", closed),
            ("holed", holed),
            ("flipped", flipped),
            ("overlapping", overlapping),
            ("with soup", with_soup),
            ("soup", soup),
            ("cube", cube()),
        ]
    }

    /// The crossing count minus the caps' exact winding number is the mesh's exact winding
    /// number wherever a ray could be counted, and one nearly always can be.
    #[test]
    fn crossings_less_the_caps_give_the_exact_winding_number() {
        let mut rng = Rng::new(3);
        for (name, tris) in meshes(&mut rng) {
            let tree = WindingTree::build(&tris).unwrap();
            let caps = tree.caps.as_deref().expect(name);
            let mut counted = 0;
            for _ in 0..400 {
                let p = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - Vec3::splat(1.5);
                let q = p.as_dvec3();
                let [lo, hi] = [Vec3::splat(-1.0), Vec3::splat(1.0)];
                let Some(count) = AxisRay::from_point(q, lo, hi)
                    .iter()
                    .find_map(|r| Some(tree.crossings(r)? + caps.crossings(r)?))
                else {
                    continue;
                };
                counted += 1;
                let by_caps = winding_number_exact(
                    &caps
                        .tris
                        .iter()
                        .map(|t| Triangle::new(t[0], t[1], t[2]))
                        .collect::<Vec<_>>(),
                    p,
                )
                .unwrap();
                let exact = winding_number_exact(&tris, p).unwrap();
                assert!(
                    (count as f64 - by_caps - exact).abs() < 1e-9,
                    "{name} at {p}: {count} crossings − {by_caps} (caps) ≠ {exact}"
                );
                let w = tree.winding_number(p, 1e-3);
                assert!(
                    (w.value - exact).abs() <= w.error_bound + 1e-9,
                    "{name} at {p}: {w:?}, {exact}"
                );
                if (exact - 0.5).abs() > 1e-9 {
                    assert_eq!(tree.is_inside(p), exact > 0.5, "{name} at {p}: {exact}");
                }
            }
            assert!(
                counted >= 390,
                "{name}: only {counted} of 400 points counted"
            );
        }
    }

    /// The check above can fail: without the caps, the crossings of a mesh with a hole give
    /// a wrong winding number at some of the same points.
    #[test]
    fn without_caps_a_hole_gives_wrong_counts() {
        let mut rng = Rng::new(3);
        let (_, holed) = meshes(&mut rng).swap_remove(1);
        let tree = WindingTree::build(&holed).unwrap();
        assert!(tree.caps().unwrap() > 0);
        let wrong = (0..400)
            .filter(|_| {
                let p = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - Vec3::splat(1.5);
                let ray = AxisRay::from_point(p.as_dvec3(), Vec3::splat(-1.0), Vec3::ONE)[0];
                let exact = winding_number_exact(&holed, p).unwrap();
                tree.crossings(&ray)
                    .is_some_and(|c| (c as f64 - exact).abs() > 0.01)
            })
            .count();
        assert!(wrong > 10, "{wrong}");
    }

    /// Points on the cube's faces, edges and corners, in the planes of its faces and
    /// diagonals, and just off them: rays along the faces or through edges cannot be counted
    /// and are given up, and every answer is still the exact one.
    #[test]
    fn rays_through_edges_and_along_faces_are_given_up_not_miscounted() {
        let tris = cube();
        let tree = WindingTree::build(&tris).unwrap();
        assert_eq!(tree.caps(), Some(0), "the cube is closed");
        let coords = [-0.5, 0.0, 0.25, 0.5, 1.0, 1.5, 1e-7, 1.0 - 1e-7];
        let (mut given_up, mut total) = (0, 0);
        for &x in &coords {
            for &y in &coords {
                for &z in &coords {
                    let p = Vec3::new(x, y, z);
                    let q = p.as_dvec3();
                    for ray in AxisRay::from_point(q, Vec3::ZERO, Vec3::ONE) {
                        total += 1;
                        match tree.crossings(&ray) {
                            None => given_up += 1,
                            Some(count) => {
                                let exact = winding_number_exact(&tris, p).unwrap();
                                assert_eq!(count as f64, exact.round(), "{p} along {ray:?}");
                                assert!((exact - exact.round()).abs() < 1e-9, "{p}: {exact}");
                            }
                        }
                    }
                    let exact = winding_number_exact(&tris, p).unwrap();
                    if (exact - 0.5).abs() > 1e-9 {
                        assert_eq!(tree.is_inside(p), exact > 0.5, "{p}: {exact}");
                    }
                }
            }
        }
        assert!(given_up > 0 && given_up < total, "{given_up} of {total}");
    }

    /// The certified orientations hold at every scale and far from the origin: a holed sphere
    /// with a sphere inside it, shrunk, grown and moved, answers as the exact sum does.
    #[test]
    fn signs_stay_exact_at_every_scale_and_offset() {
        let mut rng = Rng::new(8);
        for (scale, offset) in [
            (1e-20f32, 0.0f32),
            (1e20, 0.0),
            (1.0, 1e6),
            (1e-3, 1e4),
            (1e15, -1e20),
        ] {
            let mut tris = sphere(Vec3::ZERO, 1.0, 10, 20);
            tris.drain(..25);
            tris.extend(sphere(Vec3::new(0.5, 0.0, 0.0), 0.5, 6, 12));
            let at = |v: Vec3| v * scale + Vec3::splat(offset);
            let tris: Vec<Triangle> = tris
                .iter()
                .map(|t| Triangle::new(at(t.v0), at(t.v1), at(t.v2)))
                .collect();
            let tree = WindingTree::build(&tris).unwrap();
            let mut decided = 0;
            for _ in 0..300 {
                let p = at(Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - Vec3::splat(1.5));
                let exact = tree.winding_number(p, 0.0).value;
                if (exact - 0.5).abs() > 1e-6 {
                    decided += 1;
                    assert_eq!(tree.is_inside(p), exact > 0.5, "×{scale} +{offset}: {p}");
                }
            }
            assert!(decided > 200, "×{scale} +{offset}: {decided}");
        }
    }

    #[test]
    fn caps_close_every_unmatched_edge_and_a_soup_gets_none() {
        let mut rng = Rng::new(5);
        for (name, tris) in meshes(&mut rng) {
            let tree = WindingTree::build(&tris).unwrap();
            let caps = tree.caps.as_deref().unwrap();
            // Mesh and caps together: every edge matched by one running back.
            let mut all = tree.tris.clone();
            all.extend(caps.tris.iter().copied());
            assert!(super::caps(&all).is_empty(), "{name}");
            let expected = match name {
                "closed" | "overlapping" | "cube" => 0,
                _ => 1,
            };
            assert_eq!(caps.is_empty(), expected == 0, "{name}");
        }
        // Each triangle of a soup is a hole of its own, closed by one cap.
        let big_soup: Vec<Triangle> = (0..300)
            .map(|i| {
                let a = Vec3::new(i as f32, 0.0, 0.0);
                Triangle::new(a, a + Vec3::X * 0.5, a + Vec3::Y)
            })
            .collect();
        assert_eq!(
            WindingTree::build(&big_soup).unwrap().caps(),
            None,
            "300 caps > 256"
        );
    }

    /// Closing any closed walk matches each of its edges: with the walk's own edges, the
    /// caps' edges cancel out, on walks of every length from 2 to 200 that revisit vertices
    /// (figures of eight) but never stay on one.
    #[test]
    fn caps_of_a_walk_match_every_edge_it_takes() {
        let mut rng = Rng::new(3);
        let points: Vec<Vec3> = (0..40)
            .map(|i| Vec3::new(i as f32, (i * i % 7) as f32, (i % 5) as f32))
            .collect();
        let id = |p: Vec3| points.iter().position(|&q| q == p).unwrap() as u32;
        for len in 2..200 {
            let mut walk = vec![0u32];
            while walk.len() < len {
                let v = (rng.f32() * 40.0) as u32 % 40;
                if v != *walk.last().unwrap() && (walk.len() + 1 < len || v != walk[0]) {
                    walk.push(v);
                }
            }
            let mut caps = Vec::new();
            close_walk(&walk, &points, &mut caps);
            let mut net: HashMap<(u32, u32), i64> = HashMap::new();
            let mut add = |a: u32, b: u32| {
                if a != b {
                    *net.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
                }
            };
            for (i, &a) in walk.iter().enumerate() {
                add(a, walk[(i + 1) % walk.len()]);
            }
            for t in &caps {
                let [a, b, c] = t.map(id);
                add(a, b);
                add(b, c);
                add(c, a);
            }
            assert!(net.values().all(|&n| n == 0), "a walk of {len}: {walk:?}");
            assert!(
                caps.len() <= len.saturating_sub(2),
                "{} caps for {len}",
                caps.len()
            );
        }
    }
}

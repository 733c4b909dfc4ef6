//! The winding number by counting crossings, exact and cheap.
//!
//! # The idea
//! Around a point off a *closed* surface, the winding number is an integer: the number of
//! times any ray from the point crosses the surface outwards, minus the times it crosses
//! inwards. A mesh with holes is not closed, but it becomes closed once each hole is capped:
//! for every boundary loop, a fan of triangles from one apex to the loop's edges, turned so
//! that each cap edge cancels its mesh edge. The winding number is additive over triangles,
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

/// The caps that close the triangles `tris` (as [the module documentation](self) says): for
/// every edge the triangles leave unmatched, a triangle from its boundary loop's apex, turned
/// against it, as many times as it is unmatched. Vertices are matched by position.
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
    // Boundary loops as the connected parts of the unmatched edges; the apex of each is the
    // mean of its vertices. Any apex closes the loop; one near it keeps the caps small.
    let mut parent: HashMap<u32, u32> = HashMap::new();
    fn root(parent: &mut HashMap<u32, u32>, mut v: u32) -> u32 {
        while let Some(&p) = parent.get(&v).filter(|&&p| p != v) {
            let grand = parent.get(&p).copied().unwrap_or(p);
            parent.insert(v, grand);
            v = p;
        }
        v
    }
    for &(a, b, _) in &boundary {
        parent.entry(a).or_insert(a);
        parent.entry(b).or_insert(b);
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent.insert(ra.max(rb), ra.min(rb));
        }
    }
    let mut sums: HashMap<u32, (DVec3, f64)> = HashMap::new();
    let mut vertices: Vec<u32> = parent.keys().copied().collect();
    vertices.sort_unstable();
    for v in vertices {
        let r = root(&mut parent, v);
        let s = sums.entry(r).or_insert((DVec3::ZERO, 0.0));
        s.0 += points[v as usize].as_dvec3();
        s.1 += 1.0;
    }
    let mut caps = Vec::new();
    for (a, b, n) in boundary {
        let (sum, count) = sums[&root(&mut parent, a)];
        let apex = (sum / count).as_vec3();
        for _ in 0..n {
            caps.push([apex, points[b as usize], points[a as usize]]);
        }
    }
    caps
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
        let big_soup: Vec<Triangle> = (0..200)
            .map(|i| {
                let a = Vec3::new(i as f32, 0.0, 0.0);
                Triangle::new(a, a + Vec3::X * 0.5, a + Vec3::Y)
            })
            .collect();
        assert_eq!(
            WindingTree::build(&big_soup).unwrap().caps(),
            None,
            "600 caps > 256"
        );
    }
}

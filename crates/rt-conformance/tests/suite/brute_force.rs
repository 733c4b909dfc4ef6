//! The reference itself: the conformance kit (which also exercises the kit's own plumbing), and
//! an independent double-precision oracle on every adversarial scene.

use rt_conformance::SCENES;
use rt_core::{Accel, BruteForce, Primitive, Ray, Triangle};

rt_conformance::conformance_tests!(brute_force, BruteForce<Triangle>, ());
// The reference `compare` checks with: brute force whose bundle queries test every triangle
// against a bundle's lanes (rt-simd's lane kernels).
rt_conformance::conformance_tests!(
    bundled_brute_force,
    rt_simd::BundledBruteForce<Triangle>,
    ()
);

#[test]
fn spheres() {
    rt_conformance::check_random_spheres::<BruteForce<rt_core::Sphere>>(&());
    rt_conformance::check_random_spheres::<rt_simd::BundledBruteForce<rt_core::Sphere>>(&());
}

/// Möller–Trumbore in f64: (t, min barycentric margin, |det| relative to edge lengths).
fn oracle(t: &Triangle, r: &Ray) -> Option<(f64, f64, f64)> {
    let [v0, v1, v2] = t.to_f64();
    let (o, d) = (r.origin.as_dvec3(), r.dir().as_dvec3());
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = d.cross(e2);
    let det = e1.dot(p);
    let scale = e1.length() * e2.length() * d.length();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let s = o - v0;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let w = 1.0 - u - v;
    let tt = e2.dot(q) / det;
    let margin = u.min(v).min(w);
    // Hits near an edge or an end of the interval (within rounding) count as possible hits, so
    // they make a ray unclear instead of silently dropping out.
    let (lo, hi) = (r.t_min as f64, r.t_max as f64);
    let near_lo = tt >= lo - 1e-5 * lo.abs().max(1.0);
    let near_hi = tt <= hi + 1e-5 * hi.abs().max(1.0);
    (margin >= -1e-6 && near_lo && near_hi).then_some((tt, margin, det.abs() / scale))
}

#[test]
fn agrees_with_a_double_precision_oracle_where_the_answer_is_clear() {
    let mut clear = 0;
    for name in SCENES {
        let s = rt_conformance::scene(name);
        let bf = BruteForce::build(&s.triangles, &());
        // The oracle only speaks for rays inside the precondition.
        for r in s.rays.iter().filter(|r| r.is_valid()) {
            let mut hits: Vec<(f64, u32, f64, f64)> = s
                .triangles
                .iter()
                .enumerate()
                .filter(|(_, t)| t.is_valid())
                .filter_map(|(i, t)| oracle(t, r).map(|(tt, m, c)| (tt, i as u32, m, c)))
                .collect();
            hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let got = bf.intersect(r);
            // Only rays whose answer does not hinge on rounding: a clear miss of everything
            // (checked loosely), or a nearest hit well inside its triangle, well separated from
            // the next, and not grazing.
            match hits.first() {
                None => {}
                Some(&(tt, id, margin, cond)) => {
                    let separated = hits
                        .get(1)
                        .is_none_or(|n| (n.0 - tt) > 1e-3 * tt.abs().max(1.0));
                    let inside = tt - r.t_min as f64 > 1e-4
                        && (r.t_max as f64 - tt) > 1e-4 * tt.abs().max(1.0);
                    if margin > 1e-3 && cond > 1e-3 && separated && inside {
                        clear += 1;
                        let h = got.unwrap_or_else(|| {
                            panic!("{name}: brute force missed {}", r.to_rust())
                        });
                        assert_eq!(h.prim, id, "{name}: {}", r.to_rust());
                        assert!(
                            ((h.t as f64) - tt).abs() <= 1e-4 * tt.abs().max(1.0),
                            "{name}: t {} vs {tt}",
                            h.t
                        );
                    }
                }
            }
            if let Some(h) = got {
                // Whatever brute force reports must be a real hit on that triangle by the oracle,
                // up to rounding at the edges.
                let t = s.triangles[h.prim as usize];
                let p = r.origin.as_dvec3() + r.dir().as_dvec3() * h.t as f64;
                let [a, b, c] = t.to_f64();
                let n = (b - a).cross(c - a);
                let edge = (b - a).length().max((c - a).length()).max((c - b).length());
                // Slivers have no well-defined plane; check well-shaped triangles only.
                if n.length() > 0.05 * edge * edge {
                    let dist = (p - a).dot(n).abs() / n.length();
                    let size = edge.max(r.origin.as_dvec3().length()).max(p.length());
                    assert!(
                        dist <= 1e-4 * size.max(1.0),
                        "{name}: reported hit is off the triangle plane by {dist}"
                    );
                }
            }
        }
    }
    assert!(
        clear > 2000,
        "only {clear} clear rays: the oracle check would prove little"
    );
}

//! The answers of ray queries: [`PrimHit`], where a ray meets one primitive, and [`Hit`],
//! which primitive a ray hits first, with the tie rule that makes the answer unique.

/// Where a ray meets one primitive: the ray parameter and two surface coordinates.
///
/// For triangles `u` and `v` are the barycentric weights of the second and third vertex (the hit
/// point is `(1 - u - v)·v0 + u·v1 + v·v2`); for spheres they are longitude and colatitude, each
/// scaled to `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit {
    /// The ray parameter of the hit.
    pub t: f32,
    /// First surface coordinate.
    pub u: f32,
    /// Second surface coordinate.
    pub v: f32,
}

/// The closest hit of a ray: which primitive (its index in the slice the structure was built
/// from), where along the ray, and the primitive's surface coordinates there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Index of the primitive in the build input.
    pub prim: u32,
    /// Ray parameter of the hit.
    pub t: f32,
    /// First surface coordinate (barycentric weight of `v1` for triangles).
    pub u: f32,
    /// Second surface coordinate (barycentric weight of `v2` for triangles).
    pub v: f32,
}

impl Hit {
    /// The tie rule every structure follows: a hit at `(t, prim)` replaces the best so far when it
    /// is strictly closer, or equally close on a primitive with a smaller index. This makes the
    /// answer unique, so two correct structures always agree exactly.
    #[inline(always)]
    pub fn beats(t: f32, prim: u32, best_t: f32, best_prim: u32) -> bool {
        t < best_t || (t == best_t && prim < best_prim)
    }

    /// Whether two closest-hit answers agree: both miss, or both hit the same primitive with `t`
    /// equal or within a relative `1e-5`. This is the equality the conformance kit and `compare`
    /// use. (Equal counts for an infinite `t` too: a valid ray with a direction near the
    /// smallest normal `f32` has hits whose `t` overflows.)
    pub fn agree(a: Option<Hit>, b: Option<Hit>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                let close = a.t.is_finite() && (a.t - b.t).abs() <= 1e-5 * a.t.abs().max(1.0);
                a.prim == b.prim && (a.t == b.t || close)
            }
            _ => false,
        }
    }
}

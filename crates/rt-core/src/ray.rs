//! Rays with a parametric interval and a precomputed reciprocal direction.

use glam::Vec3;

/// A ray `origin + t * dir` restricted to the closed interval `t_min ..= t_max`.
///
/// The reciprocal direction is computed once at construction so that every slab test is three
/// multiplications instead of three divisions. A zero direction component gives an infinite
/// reciprocal whose sign follows the zero's sign (`1 / -0.0 == -inf`); [`Aabb::intersect`]
/// relies on that sign to choose the near and far slab planes.
///
/// The direction need not be normalized: `t` is measured in units of `dir`.
///
/// The direction and its reciprocal are private, read through [`Ray::dir`] and
/// [`Ray::inv_dir`], so they cannot disagree: a stale reciprocal would make every box test
/// answer for another ray, and the structures would miss silently. To change the direction,
/// make a new ray ([`Ray::with_dir`]). The origin and the interval are plain fields; nothing
/// is derived from them.
///
/// ```compile_fail
/// use rt_core::{Ray, glam::Vec3};
/// let mut r = Ray::new(Vec3::ZERO, Vec3::X);
/// r.dir = Vec3::Y; // private: the reciprocal would go stale
/// ```
///
/// [`Aabb::intersect`]: crate::Aabb::intersect
// `repr(C)`: eleven `f32` in this order, which the bundles' AVX2 transpose reads as rows
// (`simd::ray_columns8`); the assertions below keep the layout it relies on.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Where the ray starts (at `t = 0`).
    pub origin: Vec3,
    dir: Vec3,
    inv_dir: Vec3,
    /// Hits with `t < t_min` are ignored.
    pub t_min: f32,
    /// Hits with `t > t_max` are ignored.
    pub t_max: f32,
}

const _: () = {
    assert!(std::mem::size_of::<Ray>() == 11 * 4 && std::mem::align_of::<Ray>() == 4);
    assert!(std::mem::offset_of!(Ray, dir) == 12 && std::mem::offset_of!(Ray, inv_dir) == 24);
    assert!(std::mem::offset_of!(Ray, t_min) == 36 && std::mem::offset_of!(Ray, t_max) == 40);
};

impl Ray {
    /// A ray over `[0, +inf]`.
    ///
    /// ```
    /// use rt_core::{Ray, glam::Vec3};
    /// let r = Ray::new(Vec3::ZERO, Vec3::new(0.0, -0.0, 2.0));
    /// assert_eq!(r.inv_dir().y, f32::NEG_INFINITY);
    /// assert_eq!(r.at(1.5), Vec3::new(0.0, 0.0, 3.0));
    /// ```
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::with_interval(origin, dir, 0.0, f32::INFINITY)
    }

    /// A ray over `[t_min, t_max]`.
    #[inline]
    pub fn with_interval(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Self {
            origin,
            dir,
            inv_dir: dir.recip(),
            t_min,
            t_max,
        }
    }

    /// A ray from parts taken from another ray, its reciprocal direction included, as a ray
    /// bundle keeps them (`rt_simd::Bundle`): no division, the same bits. `inv_dir` must be
    /// the reciprocal a ray made of `dir` holds ([`Ray::inv_dir`]); debug builds check it.
    #[inline(always)]
    pub fn from_parts(origin: Vec3, dir: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> Self {
        debug_assert!(
            inv_dir.to_array().map(f32::to_bits) == dir.recip().to_array().map(f32::to_bits),
            "from_parts: {inv_dir} is not the reciprocal of {dir}"
        );
        Self {
            origin,
            dir,
            inv_dir,
            t_min,
            t_max,
        }
    }

    /// The same ray with direction `dir` (and its reciprocal recomputed).
    ///
    /// ```
    /// use rt_core::{Ray, glam::Vec3};
    /// let r = Ray::new(Vec3::ZERO, Vec3::X).with_dir(Vec3::new(0.0, 4.0, 0.0));
    /// assert_eq!((r.dir(), r.inv_dir().y), (Vec3::new(0.0, 4.0, 0.0), 0.25));
    /// ```
    #[inline]
    pub fn with_dir(self, dir: Vec3) -> Self {
        Self::with_interval(self.origin, dir, self.t_min, self.t_max)
    }

    /// The direction; need not be normalized.
    #[inline(always)]
    pub fn dir(&self) -> Vec3 {
        self.dir
    }

    /// Component-wise `1 / dir`, with signed infinities for zero components.
    #[inline(always)]
    pub fn inv_dir(&self) -> Vec3 {
        self.inv_dir
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }

    /// The largest origin coordinate, in magnitude, of a valid ray: 2⁴⁰ (about 1.1·10¹²).
    ///
    /// Beyond it the primitive tests overflow `f32` for geometry at ordinary scale (the
    /// watertight test's `t` is cubic in the coordinates relative to the origin: about
    /// `24·|v - o|³` must stay below `f32::MAX`), and the boxes of any scene smaller than the
    /// spacing of floats there all look alike, so a ray could only walk every node and answer
    /// nothing meaningful.
    pub const MAX_ORIGIN: f32 = (1u64 << 40) as f32;

    /// The range of a valid ray's largest direction component, in magnitude: 2⁻⁴⁰ to 2⁴⁰.
    ///
    /// `t` is measured in units of the direction, so a direction of length 10⁻³⁸ puts ordinary
    /// hits at `t = ∞`, and one of length 10³⁵ puts them at `t` below the smallest normal
    /// `f32`, where the slab tests' products underflow and a box test and a triangle test
    /// disagree (both found by the `trace` fuzz target). Any direction can be scaled into range
    /// without changing the ray; a unit one always is.
    pub const DIR_RANGE: std::ops::RangeInclusive<f32> =
        1.0 / (1u64 << 40) as f32..=(1u64 << 40) as f32;

    /// Whether origin, direction and interval are usable: origin coordinates finite and at most
    /// [`Ray::MAX_ORIGIN`] in magnitude; a finite direction whose largest component lies in
    /// [`Ray::DIR_RANGE`] in magnitude; `0 <= t_min <= t_max` with `t_min` finite (`t_max` may
    /// be `+inf`).
    ///
    /// Every structure checks this first and answers an invalid ray at once, with no hit and
    /// no node visited: a NaN direction or an origin at 10³⁰ must not walk the whole tree.
    #[inline]
    pub fn is_valid(&self) -> bool {
        // Every condition is evaluated and they are combined with `&`, not `&&`: fewer branches
        // at the start of every query. A comparison with NaN is false, so a NaN anywhere fails,
        // and a component at most the range's top is finite.
        // PERF: AMD Zen 3 (EPYC, family 25 model 1), rt-bvh single rays ÷ Embree 3 medium in one
        // process (9 interleaved passes, geometric mean of three runs over six scenes each:
        // the bunny, the teapot, the rocker arm, the sphereflake, the cow, homer; then the
        // beetle, random soup, the terrain, fandisk, spot, the teapot in a stadium), with the
        // walk's change of the same commit (`traverse.rs`): primary 0.922 -> 0.980 and 0.894 ->
        // 0.956, incoherent 0.887 -> 0.906 and 0.890 -> 0.913, shadow 0.974 -> 0.999 and 0.996
        // -> 1.051. Instructions per bunny primary ray (cachegrind) 801 -> 794 for this alone.
        let (o, d) = (self.origin.abs(), self.dir.abs());
        let (lo, hi) = (*Self::DIR_RANGE.start(), *Self::DIR_RANGE.end());
        (o.x <= Self::MAX_ORIGIN)
            & (o.y <= Self::MAX_ORIGIN)
            & (o.z <= Self::MAX_ORIGIN)
            & (d.x <= hi)
            & (d.y <= hi)
            & (d.z <= hi)
            & ((d.x >= lo) | (d.y >= lo) | (d.z >= lo))
            & (self.t_min >= 0.0)
            & (self.t_min < f32::INFINITY)
            & (self.t_min <= self.t_max)
    }

    /// Why the ray is not [valid](Ray::is_valid), the first reason of the checks' order, or
    /// `None` when it is.
    ///
    /// ```
    /// use rt_core::{Ray, RayFault, glam::Vec3};
    /// assert_eq!(Ray::new(Vec3::ZERO, Vec3::X).fault(), None);
    /// assert_eq!(Ray::new(Vec3::ZERO, Vec3::ZERO).fault(), Some(RayFault::ZeroDirection));
    /// assert_eq!(Ray::new(Vec3::NAN, Vec3::X).fault(), Some(RayFault::NonFinite));
    /// ```
    pub fn fault(&self) -> Option<RayFault> {
        if self.is_valid() {
            return None;
        }
        let d = self.dir.abs().max_element();
        Some(if !(self.origin.is_finite() && self.dir.is_finite()) {
            RayFault::NonFinite
        } else if self.origin.abs().max_element() > Self::MAX_ORIGIN {
            RayFault::OriginTooFar
        } else if d < *Self::DIR_RANGE.start() {
            RayFault::ZeroDirection
        } else if d > *Self::DIR_RANGE.end() {
            RayFault::DirectionTooLong
        } else {
            RayFault::Interval
        })
    }

    /// Formats the ray as one line of a rays file (`ox oy oz dx dy dz tmin tmax`), with every
    /// float printed so that it parses back to the same bits.
    pub fn to_line(&self) -> String {
        let o = self.origin;
        let d = self.dir;
        format!(
            "{:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            o.x, o.y, o.z, d.x, d.y, d.z, self.t_min, self.t_max
        )
    }

    /// Formats the ray as Rust source that rebuilds it exactly, for pasting into a test.
    pub fn to_rust(&self) -> String {
        let o = self.origin;
        let d = self.dir;
        format!(
            "Ray::with_interval(Vec3::new({:?}, {:?}, {:?}), Vec3::new({:?}, {:?}, {:?}), {:?}, {})",
            o.x,
            o.y,
            o.z,
            d.x,
            d.y,
            d.z,
            self.t_min,
            if self.t_max.is_infinite() {
                "f32::INFINITY".to_string()
            } else {
                format!("{:?}", self.t_max)
            }
        )
    }
}

/// Why a ray is not valid ([`Ray::fault`]); its `Display` says it in words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayFault {
    /// An origin or direction coordinate is NaN or infinite.
    NonFinite,
    /// An origin coordinate lies beyond [`Ray::MAX_ORIGIN`] in magnitude.
    OriginTooFar,
    /// Every direction component lies below [`Ray::DIR_RANGE`] in magnitude.
    ZeroDirection,
    /// A direction component lies beyond [`Ray::DIR_RANGE`] in magnitude.
    DirectionTooLong,
    /// The interval is not `0 <= t_min <= t_max` with `t_min` finite.
    Interval,
}

impl std::fmt::Display for RayFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "has a non-finite coordinate",
            Self::OriginTooFar => "has an origin coordinate beyond 2**40 in magnitude",
            Self::ZeroDirection => {
                "has a zero direction (every component below 2**-40 in magnitude)"
            }
            Self::DirectionTooLong => {
                "has a direction component beyond 2**40 in magnitude (scale the direction down)"
            }
            Self::Interval => "has an interval that is not 0 <= tnear <= tfar with tnear finite",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`Ray::is_valid`] as its documentation states it, condition by condition.
    fn valid_by_definition(r: &Ray) -> bool {
        r.origin.abs().cmple(Vec3::splat(Ray::MAX_ORIGIN)).all()
            && r.dir.is_finite()
            && Ray::DIR_RANGE.contains(&r.dir.abs().max_element())
            && r.t_min >= 0.0
            && r.t_min.is_finite()
            && r.t_min <= r.t_max
    }

    /// The branch-free form agrees with the definition on every combination of the values at
    /// and beside each limit (signed zeros, the range ends and the floats past them, infinities,
    /// NaN) in every field.
    #[test]
    fn is_valid_agrees_with_its_definition_at_every_limit() {
        let next = |x: f32| f32::from_bits(x.to_bits() + 1);
        let before = |x: f32| f32::from_bits(x.to_bits() - 1);
        let (m, lo, hi) = (
            Ray::MAX_ORIGIN,
            *Ray::DIR_RANGE.start(),
            *Ray::DIR_RANGE.end(),
        );
        let (inf, nan) = (f32::INFINITY, f32::NAN);
        let origins = [0.0, -1.0, m, -next(m), inf, nan];
        let dirs = [0.0, -0.0, 1.0, lo, -before(lo), hi, next(hi), -inf, nan];
        let ts = [0.0, -0.0, -1.0, 1.0, inf, nan];
        let (mut valid, mut invalid) = (0, 0);
        for o in origins.iter().flat_map(|&x| origins.map(|y| (x, y))) {
            for &oz in &origins {
                for d in dirs.iter().flat_map(|&x| dirs.map(|y| (x, y))) {
                    for &dz in &dirs {
                        for (t_min, t_max) in ts.iter().flat_map(|&a| ts.map(|b| (a, b))) {
                            let origin = Vec3::new(o.0, o.1, oz);
                            let dir = Vec3::new(d.0, d.1, dz);
                            let r = Ray::with_interval(origin, dir, t_min, t_max);
                            assert_eq!(r.is_valid(), valid_by_definition(&r), "{}", r.to_line());
                            if r.is_valid() {
                                valid += 1;
                            } else {
                                invalid += 1;
                            }
                        }
                    }
                }
            }
        }
        // Both answers occur, so the comparison could fail either way.
        assert!(valid > 0 && invalid > 0);
    }
}

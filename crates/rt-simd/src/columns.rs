//! A bundle's lanes as columns, between the bundle module and the kernels that fill it: the
//! transposed rays ([`RayColumns`]), where an x86 fill writes (`FillTarget`) and what it finds
//! ([`Sealed`]).

use rt_core::Ray;

/// Eight rays as the eleven vectors of their lanes: origin x, y, z, direction x, y, z,
/// reciprocal direction x, y, z, `t_min`, `t_max` (the order of [`Ray`]'s fields).
pub(crate) type RayColumns = [[f32; 8]; 11];

/// Where `fill_sealed` writes a bundle's lanes: its arrays of [`BUNDLE_LANES`] lanes.
///
/// [`BUNDLE_LANES`]: crate::BUNDLE_LANES
#[cfg(target_arch = "x86_64")]
pub(crate) struct FillTarget<'a> {
    pub origin: &'a mut [[f32; 64]; 3],
    pub dir: &'a mut [[f32; 64]; 3],
    pub inv_dir: &'a mut [[f32; 64]; 3],
    pub t_min: &'a mut [f32; 64],
    pub t_max: &'a mut [f32; 64],
    pub shear: &'a mut [[f32; 64]; 3],
    pub by_axis: &'a mut [u64; 3],
}

/// What `fill_sealed` finds over a bundle's lanes: whether every lane bundles in its octant,
/// and the bounds `Bundle::lane_bounds` reports.
pub(crate) struct Sealed {
    pub good: bool,
    pub origin_lo: [f32; 3],
    pub origin_hi: [f32; 3],
    pub inv_lo: [f32; 3],
    pub inv_hi: [f32; 3],
    pub t_min_lo: f32,
}

/// Eight rays transposed into [`RayColumns`] field by field: the portable transpose, which the
/// AVX2 one matches (the same values, only moved).
#[inline(always)]
pub(crate) fn ray_columns8_portable(rays: &[Ray; 8]) -> RayColumns {
    let mut c = [[0.0; 8]; 11];
    for (i, r) in rays.iter().enumerate() {
        let (o, d, inv) = (r.origin, r.dir(), r.inv_dir());
        for a in 0..3 {
            c[a][i] = o[a];
            c[3 + a][i] = d[a];
            c[6 + a][i] = inv[a];
        }
        c[9][i] = r.t_min;
        c[10][i] = r.t_max;
    }
    c
}

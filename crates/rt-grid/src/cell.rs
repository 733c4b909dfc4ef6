//! The grid's geometry: its box, resolution, and the planes between cells.

use rt_core::Aabb;

/// The most cells along one axis.
pub const MAX_RESOLUTION: u32 = 1 << 12;

/// A box cut into `res[0] × res[1] × res[2]` equal cells.
///
/// Every use of a cell boundary, by the builder and by traversal alike, goes through
/// [`GridShape::plane`], so both see exactly the same `f32` planes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridShape {
    bounds: Aabb,
    res: [u32; 3],
    size: [f32; 3],
    inv_size: [f32; 3],
}

impl GridShape {
    /// The grid of `res` cells over `bounds` (a non-empty box; each resolution at least 1).
    pub fn new(bounds: Aabb, res: [u32; 3]) -> Self {
        let res = res.map(|n| n.clamp(1, MAX_RESOLUTION));
        let ext = bounds.extent().to_array();
        let size: [f32; 3] = std::array::from_fn(|a| ext[a] / res[a] as f32);
        // A flat axis has one cell of size 0; every coordinate maps to cell 0 there.
        let inv_size = size.map(|s| if s > 0.0 { 1.0 / s } else { 0.0 });
        Self {
            bounds,
            res,
            size,
            inv_size,
        }
    }

    /// Cells per axis for `n` primitives in `bounds` at `density` cells per primitive (Cleary &
    /// Wyvill): `n_i = d_i · cbrt(density · n / V)`, rounded, at least 1, at most
    /// [`MAX_RESOLUTION`], and scaled down uniformly until the total is at most `max_cells` and
    /// at most `8 · density · n + 64`.
    ///
    /// An axis of zero extent gets one cell and the rule runs over the others (`V` is then an
    /// area or a length).
    pub fn resolution(bounds: &Aabb, n: usize, density: f32, max_cells: usize) -> [u32; 3] {
        let ext = bounds.extent().to_array();
        let dims: Vec<f64> = ext
            .iter()
            .filter(|&&d| d > 0.0)
            .map(|&d| f64::from(d))
            .collect();
        if n == 0 || dims.is_empty() || !(density > 0.0 && density.is_finite()) {
            return [1; 3];
        }
        let measure: f64 = dims.iter().product();
        let per_unit = (f64::from(density) * n as f64 / measure).powf(1.0 / dims.len() as f64);
        let cells_for = |k: f64| -> [u32; 3] {
            ext.map(|d| {
                if d > 0.0 {
                    (f64::from(d) * k)
                        .round()
                        .clamp(1.0, f64::from(MAX_RESOLUTION)) as u32
                } else {
                    1
                }
            })
        };
        let mut k = per_unit;
        let mut res = cells_for(k);
        // Never far more cells than asked for: an axis of tiny but nonzero extent (a triangle
        // 10⁻⁴³ thick) makes `V` tiny and the other axes' counts huge, while it keeps one cell
        // itself, so without this bound a single triangle got 4096 × 4096 × 1 cells (found by
        // the `trace` fuzz target). Rounding each axis up costs at most 2³ × the target.
        let wanted = 8.0 * f64::from(density) * n as f64 + 64.0;
        let max_cells = max_cells.min(wanted.min(usize::MAX as f64) as usize).max(1);
        // Each round shrinks k by the excess, so it ends within a few rounds; the bound on rounds
        // only guards against a non-finite k.
        for _ in 0..64 {
            let total: usize = res.iter().map(|&r| r as usize).product();
            if total <= max_cells {
                break;
            }
            k *= (max_cells as f64 / total as f64).powf(1.0 / dims.len() as f64) * 0.999;
            res = cells_for(k);
        }
        res
    }

    /// The grid's box.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Cells per axis.
    pub fn resolution_per_axis(&self) -> [u32; 3] {
        self.res
    }

    /// The number of cells.
    pub fn cell_count(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }

    /// The `k`-th boundary plane on `axis` (`0..=res[axis]`): the box's faces at both ends.
    #[inline(always)]
    pub fn plane(&self, axis: usize, k: u32) -> f32 {
        if k >= self.res[axis] {
            self.bounds.max[axis]
        } else {
            self.bounds.min[axis] + k as f32 * self.size[axis]
        }
    }

    /// The cell on `axis` holding coordinate `x`, clamped to the grid. Near a plane it may be
    /// off by one from [`plane`](Self::plane) by rounding; the builder's margin covers that.
    #[inline(always)]
    pub fn cell_of(&self, axis: usize, x: f32) -> u32 {
        let f = (x - self.bounds.min[axis]) * self.inv_size[axis];
        // `as` truncates and saturates (NaN to 0), so any input gives a cell in range; it
        // differs from `floor` only below 0, which the clamp sends to cell 0 either way.
        // PERF: without `floor`, which compiles to a call of the C library's `floorf` on the
        // baseline x86-64 target (1.8% of the hierarchical grid's samples, teapot in a
        // stadium). With the bundles' start slices found on their major axis alone
        // (`dda::first_cell`), the hierarchical grid's bundles went from 5.73 to 6.98 Mrays/s
        // there and from 4.26 to 5.47 on the sphereflake (`compare --bundle 8x8 -j 1`).
        (f as i64).clamp(0, i64::from(self.res[axis]) - 1) as u32
    }

    /// The box of cell `c`.
    pub fn cell_box(&self, c: [u32; 3]) -> Aabb {
        let min: [f32; 3] = std::array::from_fn(|a| self.plane(a, c[a]));
        let max: [f32; 3] = std::array::from_fn(|a| self.plane(a, c[a] + 1));
        Aabb::new(min.into(), max.into())
    }

    /// The cell with linear index `i` (the inverse of [`index`](Self::index)).
    #[inline]
    pub fn coords(&self, i: usize) -> [u32; 3] {
        let (nx, ny) = (self.res[0] as usize, self.res[1] as usize);
        [
            (i % nx) as u32,
            (i / nx % ny) as u32,
            (i / (nx * ny)) as u32,
        ]
    }

    /// The linear index of cell `c` (x fastest).
    #[inline(always)]
    pub fn index(&self, c: [u32; 3]) -> usize {
        (c[2] as usize * self.res[1] as usize + c[1] as usize) * self.res[0] as usize
            + c[0] as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::glam::Vec3;

    #[test]
    fn resolution_follows_the_shape_and_the_budget() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(4.0, 2.0, 1.0));
        // 8 cells per primitive, 1000 primitives: 8000 cells in a 4:2:1 box -> 40 × 20 × 10.
        assert_eq!(
            GridShape::resolution(&b, 1000, 8.0, usize::MAX),
            [40, 20, 10]
        );
        let capped = GridShape::resolution(&b, 1000, 8.0, 1000);
        assert!(capped.iter().map(|&r| r as usize).product::<usize>() <= 1000);
        // A flat box: one cell across it.
        let flat = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(
            GridShape::resolution(&flat, 100, 1.0, usize::MAX),
            [10, 10, 1]
        );
        // Nearly flat: a tiny but nonzero thickness must not blow up the other axes (it did,
        // to 4096 × 4096 × 1 for one triangle).
        let thin = Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 3.6e-43));
        let cells: usize = GridShape::resolution(&thin, 1, 4.0, 1 << 24)
            .iter()
            .map(|&r| r as usize)
            .product();
        assert!(cells <= 8 * 4 + 64, "{cells} cells for one triangle");
        // Degenerate inputs give one cell.
        assert_eq!(GridShape::resolution(&b, 0, 1.0, 10), [1; 3]);
        assert_eq!(GridShape::resolution(&b, 10, f32::NAN, 10), [1; 3]);
    }

    #[test]
    fn planes_and_cells_agree() {
        let g = GridShape::new(Aabb::new(Vec3::splat(-1.0), Vec3::splat(2.0)), [3, 4, 5]);
        for a in 0..3 {
            let n = g.resolution_per_axis()[a];
            assert_eq!(g.plane(a, 0), -1.0);
            assert_eq!(g.plane(a, n), 2.0);
            for k in 0..n {
                let mid = 0.5 * (g.plane(a, k) + g.plane(a, k + 1));
                assert_eq!(g.cell_of(a, mid), k);
            }
            assert_eq!(g.cell_of(a, -5.0), 0);
            assert_eq!(g.cell_of(a, 5.0), n - 1);
            assert_eq!(g.cell_of(a, f32::NAN), 0);
        }
        assert_eq!(g.index([2, 3, 4]), g.cell_count() - 1);
        for i in 0..g.cell_count() {
            assert_eq!(g.index(g.coords(i)), i);
        }
    }
}

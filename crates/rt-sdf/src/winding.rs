//! Inside and outside: the generalised winding number.
//!
//! # The winding number
//! The winding number of a closed surface around a point counts how many times the surface
//! wraps the point: 1 inside a closed mesh whose triangles face outwards, 0 outside. It is the
//! sum of the solid angles the triangles subtend at the point, over 4π ([`solid_angle`]).
//! Jacobson, Kavan & Sorkine-Hornung ("Robust inside-outside segmentation using generalized
//! winding numbers", SIGGRAPH 2013) take the same sum over a mesh that is not closed: with a
//! hole or a crack, it still comes out near 1 deep inside and near 0 far outside, and changes
//! smoothly across the hole instead of flipping, so "inside when above ½" is a robust test
//! where counting the crossings of one ray ([`SignedDistance::inside_by_parity`](crate::SignedDistance::inside_by_parity)) depends on whether
//! that ray happens to leave through the hole.
//!
//! # The fast evaluation and its error bound
//! The exact sum ([`winding_number_exact`]) visits every triangle. [`WindingTree`] follows
//! Barill, Dickson, Schmidt, Levin & Jacobson ("Fast winding numbers for soups and clouds",
//! SIGGRAPH 2018): a tree of clusters of triangles, each with a centre `c`, a radius `R` that
//! holds all of its triangles, its area `A`, and the moments of its surface up to order two.
//! A cluster whose centre is at distance `D > R` from the query point may contribute the
//! Taylor expansion of its integrand about `c`, truncated after the second-order term, instead
//! of its triangles.
//!
//! The error of that truncation is bounded. The winding number of a cluster is
//! `∫ n·(x − q) / (4π|x − q|³) dA = −∫ D_n φ(x − q) dA` with `φ(y) = 1/(4π|y|)`, and the
//! remainder after the terms of order 0, 1 and 2 in `d = x − c` is
//! `D⁴φ(y)[n, d, d, d] / 3!` at some `y` on the segment from `c − q` to `x − q`, whose length
//! is at least `D − R`. The `m`-th derivative of `1/|y|` along one unit vector is
//! `m! P_m(cos θ) / |y|^(m+1)` (the Legendre expansion of `1/|y − t u|`), and `|P_m| ≤ 1`; a
//! symmetric multilinear form on a Euclidean space is no larger on different unit vectors than
//! on one repeated (Banach 1938), so `|D⁴φ(y)[n, d, d, d]| ≤ 4! R³ / (4π |y|⁵)`. Integrated
//! over the cluster's area:
//!
//! ```text
//! |error of one cluster| ≤ A · R³ / (π (D − R)⁵)
//! ```
//!
//! [`WindingTree::winding_number`] takes a cluster's expansion only when that bound is at most
//! `tolerance · A / A_total`, so the bounds of all clusters taken sum to at most the
//! tolerance: the answer is within `tolerance` of the exact sum, whatever the mesh. It returns
//! the sum of the bounds it actually used ([`Winding::error_bound`]), which is usually far
//! smaller. Both hold up to floating-point rounding: every term is computed in `f64`, so the
//! computed exact sum and the computed fast one differ from the true values by about
//! `1e-16 ×` the number of triangles, and the tests allow `1e-9`.
//!
use crate::crossing::{self, AxisRay};
use bytemuck::Zeroable;
use glam::{DVec3, Vec3};
use rt_core::{Geometry, Primitive};
use std::f64::consts::PI;

/// The signed solid angle the triangle `(v0, v1, v2)` subtends at `p`, in steradians, in
/// `[−2π, 2π]`: positive when `p` is on the side the triangle's normal `(v1 − v0) × (v2 − v0)`
/// points away from (inside, for a closed mesh facing outwards).
///
/// The formula of Van Oosterom & Strackee (IEEE Trans. Biomed. Eng. 1983), in `f64`. A point
/// in the triangle's plane outside it gets 0; a point on the triangle itself gets ±2π (the
/// winding number jumps by 1 across the surface, and on it either side is an answer).
///
/// ```
/// use rt_core::glam::Vec3;
/// use rt_sdf::solid_angle;
/// // One face of a cube seen from its centre: a sixth of the sphere.
/// let o = Vec3::splat(0.5);
/// let w = solid_angle(Vec3::ZERO, Vec3::Y, Vec3::X, o) + solid_angle(Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0), o);
/// assert!((w - 4.0 * std::f64::consts::PI / 6.0).abs() < 1e-12);
/// ```
pub fn solid_angle(v0: Vec3, v1: Vec3, v2: Vec3, p: Vec3) -> f64 {
    let p = p.as_dvec3();
    solid_angle_f64(v0.as_dvec3() - p, v1.as_dvec3() - p, v2.as_dvec3() - p)
}

#[inline]
fn solid_angle_f64(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let det = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * det.atan2(den)
}

/// The winding number of `tris` around `q`: their solid angles summed in order, over 4π.
fn winding_sum(tris: &[[Vec3; 3]], q: DVec3) -> f64 {
    let sum: f64 = tris
        .iter()
        .map(|t| {
            solid_angle_f64(
                t[0].as_dvec3() - q,
                t[1].as_dvec3() - q,
                t[2].as_dvec3() - q,
            )
        })
        .sum();
    sum / (4.0 * PI)
}

/// A primitive the winding number cannot use: it has no triangle form
/// ([`Primitive::as_triangle`] is `None`), so its surface has no solid angle here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NotATriangle {
    /// The primitive's index in the input.
    pub prim: u32,
}

impl std::fmt::Display for NotATriangle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "primitive {} is not a triangle: the winding number is defined for triangle meshes",
            self.prim
        )
    }
}

impl std::error::Error for NotATriangle {}

/// The valid triangles of `prims` as vertex triples; invalid primitives (zero area, a
/// non-finite vertex) are left out, as structures leave them out.
fn triangles<G: Geometry + ?Sized>(prims: &G) -> Result<Vec<[Vec3; 3]>, NotATriangle> {
    let mut tris = Vec::with_capacity(prims.len());
    for i in 0..prims.len() {
        let p = prims.prim(i);
        if !p.is_valid() {
            continue;
        }
        match p.as_triangle() {
            Some((t, _)) => tris.push([t.v0, t.v1, t.v2]),
            None => return Err(NotATriangle { prim: i as u32 }),
        }
    }
    Ok(tris)
}

/// The winding number of the valid triangles of `prims` around `point`, summed over every
/// triangle in input order: the reference [`WindingTree`] is checked against. `NaN` for a
/// point with a non-finite coordinate.
///
/// # Errors
/// [`NotATriangle`] for the first valid primitive that is not a triangle.
pub fn winding_number_exact<P: Primitive>(prims: &[P], point: Vec3) -> Result<f64, NotATriangle> {
    // Read in place, not through `triangles`: a copy of every triangle per point would cost
    // more than the sum and make the reference look slower than it is.
    let q = point.as_dvec3();
    let mut sum = 0.0;
    for (i, p) in prims.iter().enumerate().filter(|(_, p)| p.is_valid()) {
        let Some((t, _)) = p.as_triangle() else {
            return Err(NotATriangle { prim: i as u32 });
        };
        sum += solid_angle_f64(
            t.v0.as_dvec3() - q,
            t.v1.as_dvec3() - q,
            t.v2.as_dvec3() - q,
        );
    }
    Ok(if point.is_finite() {
        sum / (4.0 * PI)
    } else {
        f64::NAN
    })
}

/// A winding number and how far from the exact sum it may be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Winding {
    /// The winding number: about 1 inside a closed mesh facing outwards, 0 outside. `NaN` for
    /// a point with a non-finite coordinate.
    pub value: f64,
    /// A bound on `|value − exact|` from the clusters whose expansion was taken (see the
    /// [module documentation](self)), rounding aside: 0 when every triangle was summed.
    pub error_bound: f64,
}

rt_core::pod_struct! {
/// The tree of clusters [`WindingTree`] keeps: one cluster of triangles, the coefficients of
/// its expansion, and where its triangles or children are.
///
/// With `d = x − center`, the cluster's moments are `N = ∫ n dA`, `M_ij = ∫ n_i d_j dA` and
/// `T_ijk = ∫ n_i d_j d_k dA`. The expansion of its winding number at `r = center − q` is
/// `(N·r + tr M)/|r|³ − (3 rᵀMr + 3 r·v)/|r|⁵ + 15 Σ T_ijk r_i r_j r_k / (2|r|⁷)`, all over
/// 4π, with `v_k = Σᵢ (T_iik + T_kii / 2)`; the fields keep exactly what that needs, over
/// 4π and with the constant factors folded in.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cluster {
    /// The area-weighted centroid of the cluster's triangles.
    pub(crate) center: [f64; 3],
    /// Every point of every triangle of the cluster is within this distance of `center`.
    pub(crate) radius: f64,
    /// The triangles' total area.
    area: f64,
    /// `tr M / 4π`: the constant of the `1/|r|³` term.
    trace: f64,
    /// `N / 4π`: the linear part of the `1/|r|³` term (the dipole).
    n: [f64; 3],
    /// The quadratic form `−3 rᵀMr / 4π` by monomial: `xx, yy, zz, xy, xz, yz`.
    quadratic: [f64; 6],
    /// `−3 v / 4π`: the linear part of the `1/|r|⁵` term.
    v: [f64; 3],
    /// The cubic form `15 Σ T_ijk r_i r_j r_k / 8π` by monomial: `xxx, yyy, zzz, xxy, xxz,
    /// xyy, yyz, xzz, yzz, xyz`.
    cubic: [f64; 10],
    /// A leaf's first triangle (in the tree's order); an interior node's second child (its
    /// first is the next cluster).
    pub(crate) first: u32,
    /// A leaf's number of triangles (at least 1); 0 for an interior node.
    pub(crate) count: u32,
}
}

const _: () = assert!(std::mem::size_of::<Cluster>() == 232);

/// The index pairs `(j, k)` of [`Cluster::quadratic`]'s monomials.
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// The index triples `(i, j, k)`, `i ≤ j ≤ k`, of [`Cluster::cubic`]'s monomials.
const TRIPLES: [(usize, usize, usize); 10] = [
    (0, 0, 0),
    (1, 1, 1),
    (2, 2, 2),
    (0, 0, 1),
    (0, 0, 2),
    (0, 1, 1),
    (1, 1, 2),
    (0, 2, 2),
    (1, 2, 2),
    (0, 1, 2),
];

/// The slot in [`TRIPLES`] (and [`Cluster::cubic`]) of each index triple `(i, j, k)`, in
/// any order.
const CUBIC_SLOT: [[[usize; 3]; 3]; 3] = {
    let mut slot = [[[0; 3]; 3]; 3];
    let mut e = 0;
    while e < TRIPLES.len() {
        let (x, y, z) = TRIPLES[e];
        // Every order of the triple.
        let orders = [
            [x, y, z],
            [x, z, y],
            [y, x, z],
            [y, z, x],
            [z, x, y],
            [z, y, x],
        ];
        let mut o = 0;
        while o < orders.len() {
            let [i, j, k] = orders[o];
            slot[i][j][k] = e;
            o += 1;
        }
        e += 1;
    }
    slot
};

/// The moments of a set of triangles about their area-weighted centroid, as the build carries
/// them up the tree: a parent's are its children's shifted to its own centre and summed, so
/// that each triangle's moments are computed once (in its leaf) rather than once per level.
#[derive(Clone, Copy, Debug)]
struct Moments {
    /// The triangles' total area.
    area: f64,
    /// Their centroids weighted by area, summed (the centre times the area).
    weighted: DVec3,
    /// Where the moments below are taken: `weighted / area`, or a vertex where the area is 0.
    center: DVec3,
    /// `∫ n dA`.
    n: DVec3,
    /// `M_ij = ∫ n_i d_j dA`, with `d = x − center`.
    m: [[f64; 3]; 3],
    /// `T_ijk = ∫ n_i d_j d_k dA`.
    t3: [[[f64; 3]; 3]; 3],
}

impl Moments {
    /// The moments of `tris` (at least one), summed triangle by triangle.
    fn of(tris: &[[Vec3; 3]]) -> Self {
        let tri = |t: &[Vec3; 3]| [t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3()];
        let (mut area, mut weighted) = (0.0, DVec3::ZERO);
        for t in tris {
            let [a, b, c] = tri(t);
            let twice = (b - a).cross(c - a).length();
            area += 0.5 * twice;
            weighted += 0.5 * twice * (a + b + c) / 3.0;
        }
        let center = if area > 0.0 {
            weighted / area
        } else {
            tri(&tris[0])[0]
        };
        let (mut n, mut m, mut t3) = (DVec3::ZERO, [[0.0f64; 3]; 3], [[[0.0f64; 3]; 3]; 3]);
        for t in tris {
            let [a, b, c] = tri(t).map(|v| v - center);
            // With the area-weighted normal `an` (the triangle's normal is constant), the
            // moments about the centre are ∫ n dA = an, ∫ n dᵀ dA = an (s/3)ᵀ and
            // ∫ n_i d dᵀ dA = an_i/12 · (a aᵀ + b bᵀ + c cᵀ + s sᵀ), with s = a + b + c
            // (the second moment of a triangle).
            let an = 0.5 * (b - a).cross(c - a);
            let s = a + b + c;
            n += an;
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] += an[i] * s[j] / 3.0;
                    for k in 0..3 {
                        let second = a[j] * a[k] + b[j] * b[k] + c[j] * c[k] + s[j] * s[k];
                        t3[i][j][k] += an[i] * second / 12.0;
                    }
                }
            }
        }
        Self {
            area,
            weighted,
            center,
            n,
            m,
            t3,
        }
    }

    /// The moments of both sets together, about their joint centroid (`fallback` where their
    /// area is 0). Moving the centre by `δ` (so that `d' = d + δ`) gives
    /// `M'_ij = M_ij + N_i δ_j` and `T'_ijk = T_ijk + M_ij δ_k + M_ik δ_j + N_i δ_j δ_k`: no
    /// large terms that cancel, as moments about a far origin would have.
    fn merge(&self, other: &Self, fallback: DVec3) -> Self {
        let area = self.area + other.area;
        let weighted = self.weighted + other.weighted;
        let center = if area > 0.0 {
            weighted / area
        } else {
            fallback
        };
        let mut sum = Self {
            area,
            weighted,
            center,
            n: self.n + other.n,
            m: [[0.0; 3]; 3],
            t3: [[[0.0; 3]; 3]; 3],
        };
        for part in [self, other] {
            let d = part.center - center;
            for i in 0..3 {
                for j in 0..3 {
                    sum.m[i][j] += part.m[i][j] + part.n[i] * d[j];
                    for k in 0..3 {
                        sum.t3[i][j][k] += part.t3[i][j][k]
                            + part.m[i][j] * d[k]
                            + part.m[i][k] * d[j]
                            + part.n[i] * d[j] * d[k];
                    }
                }
            }
        }
        sum
    }
}

impl Cluster {
    /// The cluster of `tris`, moments about their area-weighted centroid.
    #[cfg(test)]
    fn of(tris: &[[Vec3; 3]]) -> Self {
        Self::with_moments(&Moments::of(tris), tris)
    }

    /// The cluster of `tris` whose moments are `moments`: its expansion's coefficients, and
    /// the radius about the moments' centre that holds every vertex.
    fn with_moments(moments: &Moments, tris: &[[Vec3; 3]]) -> Self {
        let Moments {
            area,
            center,
            n,
            m,
            t3,
            ..
        } = *moments;
        // The largest squared distance, then its root: the root is monotonic and correctly
        // rounded, so this is the largest of the distances, with one root instead of three a
        // triangle.
        let farthest = tris
            .iter()
            .flatten()
            .map(|v| (v.as_dvec3() - center).length_squared())
            .fold(0.0f64, f64::max);
        let radius = farthest.sqrt();
        let four_pi = 4.0 * PI;
        let mut cl = Cluster {
            center: center.to_array(),
            area,
            trace: (m[0][0] + m[1][1] + m[2][2]) / four_pi,
            n: (n / four_pi).to_array(),
            ..Zeroable::zeroed()
        };
        for (e, &(j, k)) in PAIRS.iter().enumerate() {
            let both = if j == k { m[j][k] } else { m[j][k] + m[k][j] };
            cl.quadratic[e] = -3.0 * both / four_pi;
        }
        for (k, v) in cl.v.iter_mut().enumerate() {
            let sum: f64 = (0..3).map(|i| t3[i][i][k] + 0.5 * t3[k][i][i]).sum();
            *v = -3.0 * sum / four_pi;
        }
        for (i, plane) in t3.iter().enumerate() {
            for (j, row) in plane.iter().enumerate() {
                for (k, &value) in row.iter().enumerate() {
                    cl.cubic[CUBIC_SLOT[i][j][k]] += 7.5 * value / four_pi;
                }
            }
        }
        // Rounding up by a relative 2⁻⁴⁰ keeps every vertex inside after the f64 rounding of
        // the lengths above.
        cl.radius = radius * (1.0 + 1.0 / (1u64 << 40) as f64);
        cl
    }

    /// The cluster's winding number at offset `r = center − q` from the query point, `dist`
    /// = `|r|`: the terms of order 0, 1 and 2 of its expansion.
    #[inline]
    fn expansion(&self, r: DVec3, dist: f64) -> f64 {
        let inv2 = 1.0 / (dist * dist);
        let inv3 = inv2 / dist;
        let inv5 = inv3 * inv2;
        let inv7 = inv5 * inv2;
        let (x, y, z) = (r.x, r.y, r.z);
        let q = &self.quadratic;
        let quadratic =
            q[0] * x * x + q[1] * y * y + q[2] * z * z + q[3] * x * y + q[4] * x * z + q[5] * y * z;
        let c = &self.cubic;
        let cubic = x
            * (c[0] * x * x
                + c[3] * x * y
                + c[4] * x * z
                + c[5] * y * y
                + c[9] * y * z
                + c[7] * z * z)
            + y * (c[1] * y * y + c[6] * y * z + c[8] * z * z)
            + c[2] * z * z * z;
        (self.trace + DVec3::from_array(self.n).dot(r)) * inv3
            + (quadratic + DVec3::from_array(self.v).dot(r)) * inv5
            + cubic * inv7
    }
}

/// Barill et al.'s fast winding number: a tree of clusters of triangles with their moments,
/// evaluated with an error bound (see the [module documentation](self)).
///
/// It is built over the same primitives as a structure, and is separate from it: the
/// expansion needs each cluster's moments over triangles it holds once, and the kd-tree, the
/// grids and the octree list a triangle in every cell it crosses. Building it sorts the
/// triangles by median splits, `O(n log n)`; it keeps a copy of them and 232 bytes per
/// cluster of at most 8. Each triangle's moments are summed once, in its leaf, and each parent
/// takes its children's, moved to its own centre; with the `parallel` feature (default) the
/// halves of large clusters build on rayon's threads, into the same tree bit for bit. It also finds the edges the triangles leave unmatched and keeps the
/// caps that close them, in a tree of their own, for [counting crossings](crate::crossing)
/// in [`is_inside`](Self::is_inside).
#[derive(Clone, Debug)]
pub struct WindingTree {
    pub(crate) nodes: Vec<Cluster>,
    pub(crate) tris: Vec<[Vec3; 3]>,
    area: f64,
    /// The triangles' bounding box, `lo` then `hi` (empty: `lo > hi`).
    bounds: [Vec3; 2],
    /// The caps that close the triangles ([`crossing`]), in a tree of their
    /// own (which has none); `None` where there would be too many to pay.
    pub(crate) caps: Option<Box<WindingTree>>,
}

/// Triangles in a leaf cluster at most.
const LEAF: usize = 8;

/// The share of the tolerance each cluster may take in [`WindingTree::winding_number`]'s
/// first walk.
const SHARES: f64 = 512.0;

impl WindingTree {
    /// The tree over the valid triangles of `prims` (invalid ones are left out, as structures
    /// leave them out).
    ///
    /// # Errors
    /// [`NotATriangle`] for the first valid primitive that is not a triangle.
    pub fn build<P: Primitive>(prims: &[P]) -> Result<Self, NotATriangle> {
        Self::build_from(prims)
    }

    /// The tree over the valid triangles of `geometry`, read in place: a [`Mesh`] or
    /// [`IndexedTriangles`] as the structures' `Accel::build_from` takes them, with no copy of
    /// its triangles beforehand.
    ///
    /// ```
    /// use rt_core::{Mesh, glam::Vec3};
    /// let mesh = Mesh::cuboid(Vec3::ZERO, Vec3::ONE);
    /// let tree = rt_sdf::WindingTree::build_from(&mesh).unwrap();
    /// assert!(tree.is_inside(Vec3::splat(0.5)) && !tree.is_inside(Vec3::splat(1.5)));
    /// ```
    ///
    /// [`Mesh`]: rt_core::Mesh
    /// [`IndexedTriangles`]: rt_core::IndexedTriangles
    ///
    /// # Errors
    /// [`NotATriangle`] for the first valid primitive that is not a triangle.
    pub fn build_from<G: Geometry + ?Sized>(geometry: &G) -> Result<Self, NotATriangle> {
        let tris = triangles(geometry)?;
        let caps = crossing::caps(&tris);
        let mut tree = Self::of(tris);
        if caps.len() <= crossing::MAX_CAPS.max(tree.len() / 4) {
            tree.caps = Some(Box::new(Self::of(caps)));
        }
        Ok(tree)
    }

    /// The tree over `tris` as they are, without caps.
    fn of(mut tris: Vec<[Vec3; 3]>) -> Self {
        let mut nodes = Vec::new();
        if !tris.is_empty() {
            nodes = vec![Cluster::zeroed(); cluster_count(tris.len())];
            build_node(&mut nodes, 0, &mut tris, 0);
        }
        let area = nodes.first().map_or(0.0, |c| c.area);
        let bounds = tris.iter().flatten().fold(
            [Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)],
            |[lo, hi], &v| [lo.min(v), hi.max(v)],
        );
        Self {
            nodes,
            tris,
            area,
            bounds,
            caps: None,
        }
    }

    /// How many triangles the tree holds.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Whether the tree holds no triangle (every winding number is 0).
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Heap and inline bytes the tree holds.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.nodes.capacity() * std::mem::size_of::<Cluster>()
            + self.tris.capacity() * std::mem::size_of::<[Vec3; 3]>()
            + self.caps.as_ref().map_or(0, |c| c.memory_bytes())
    }

    /// How many triangles close the tree's holes for [counting
    /// crossings](crate::crossing): 0 for a closed mesh; `None` where there would be too many
    /// to pay, and the winding number is always evaluated by the tree.
    pub fn caps(&self) -> Option<usize> {
        self.caps.as_ref().map(|c| c.len())
    }

    /// The winding number around `point`, within `tolerance` of the exact sum (rounding aside;
    /// see the [module documentation](self)). A tolerance of 0 sums every triangle; a negative
    /// or NaN one counts as 0. A point with a non-finite coordinate gets `NaN`.
    pub fn winding_number(&self, point: Vec3, tolerance: f64) -> Winding {
        if !point.is_finite() {
            return Winding {
                value: f64::NAN,
                error_bound: 0.0,
            };
        }
        let q = point.as_dvec3();
        if tolerance.is_nan() || tolerance <= 0.0 {
            return self.walk(q, |_, _| false);
        }
        self.evaluate(q, tolerance)
    }

    /// The signed count of the crossings of an axis ray from `q` with the triangles and their
    /// caps, with the caps: `None` where the tree keeps no caps or no axis ray could be
    /// counted exactly.
    fn crossing_count(&self, q: DVec3) -> Option<(i64, &WindingTree)> {
        let caps = self.caps.as_deref()?;
        let [lo, hi] = self.bounds;
        AxisRay::from_point(q, lo, hi)
            .iter()
            .find_map(|ray| Some(self.crossings(ray)? + caps.crossings(ray)?))
            .map(|count| (count, caps))
    }

    /// The tree's own evaluation of the winding number around `q`, within `tolerance` (above
    /// 0) of the exact sum.
    fn evaluate(&self, q: DVec3, tolerance: f64) -> Winding {
        // PERF: first each cluster may take the larger of a fixed share of the tolerance and
        // its share by area. The fixed share lets the small clusters near the point be taken
        // much closer than an even share by area would; the share by area lets a large
        // cluster (the caps of a hole, which are a few large triangles over many small ones)
        // be taken from as near as its area allows. The bounds actually taken usually sum to
        // far below the tolerance. Only when they do not is the walk redone with shares by
        // area alone, whose sum cannot exceed it. Inside tests of 200,000 points in the box
        // grown by a quarter, one thread, AMD Zen 3, fixed share -> the larger of both, µs a
        // point, two alternating runs: the bunny 1.6 1.4 -> 1.0 0.9, the beetle 10.2 11.8 ->
        // 10.2 10.5, homer 0.5 0.6 -> 0.6 0.6 (a scratch harness; the same answers).
        let (share, per_area) = (tolerance / SHARES, tolerance / self.area);
        let first = self.walk(q, |bound, area| bound <= share.max(per_area * area));
        if first.error_bound <= tolerance {
            return first;
        }
        self.walk(q, |bound, area| bound <= per_area * area)
    }

    /// The winding number around `q`, taking the expansion of every cluster outside its
    /// radius for which `take(bound, area)` holds, where `bound` is the cluster's error bound
    /// `A·R³/(π (D − R)⁵)` and `area` its area `A`; the others are opened, and the triangles of
    /// the leaves opened are summed.
    fn walk(&self, q: DVec3, take: impl Fn(f64, f64) -> bool) -> Winding {
        let (mut value, mut error_bound) = (0.0, 0.0);
        let mut stack = [0u32; 64];
        let mut top = 0usize;
        let mut next = if self.nodes.is_empty() { None } else { Some(0) };
        while let Some(i) = next.take().or_else(|| {
            top = top.checked_sub(1)?;
            Some(stack[top] as usize)
        }) {
            let c = &self.nodes[i];
            let r = DVec3::from_array(c.center) - q;
            let dist = r.length();
            let gap = dist - c.radius;
            if gap > 0.0 {
                let bound = c.area * c.radius.powi(3) / (PI * gap.powi(5));
                if take(bound, c.area) {
                    value += c.expansion(r, dist);
                    error_bound += bound;
                    continue;
                }
            }
            if c.count > 0 {
                let (first, count) = (c.first as usize, c.count as usize);
                value += winding_sum(&self.tris[first..first + count], q);
            } else {
                // The tree's median splits keep its depth below 33, so 64 slots never run out.
                stack[top] = c.first;
                top += 1;
                next = Some(i + 1);
            }
        }
        Winding { value, error_bound }
    }

    /// Whether `point` is inside: whether its winding number is above ½.
    ///
    /// Decided by the crossings of one ray and the caps' fast evaluation where the tree keeps
    /// caps ([`crossing`]), else by the tree's fast evaluation, when its error
    /// bound leaves no doubt; by the exact sum over the tree otherwise. So it answers as
    /// [`winding_number_exact`] would except where the exact value is within rounding (about
    /// `1e-16 ×` the triangle count) of ½. A point with a non-finite coordinate is outside.
    pub fn is_inside(&self, point: Vec3) -> bool {
        if !point.is_finite() {
            return false;
        }
        let q = point.as_dvec3();
        let rounding = 1e-12 + 1e-15 * self.tris.len() as f64;
        let crossings = self.crossing_count(q);
        for tolerance in [0.25, 0.02] {
            let w = match crossings {
                Some((count, caps)) if caps.is_empty() => return count > 0,
                Some((count, caps)) => {
                    let w = caps.evaluate(q, tolerance);
                    Winding {
                        value: count as f64 - w.value,
                        ..w
                    }
                }
                None => self.evaluate(q, tolerance),
            };
            if (w.value - 0.5).abs() > w.error_bound + rounding {
                return w.value > 0.5;
            }
        }
        self.walk(q, |_, _| false).value > 0.5
    }
}

/// Subtrees of at least this many triangles build their halves on two threads at once.
const PARALLEL_MIN: usize = 4096;

/// How many clusters the tree of `n ≥ 1` triangles has. Median splits make it a function of
/// `n` alone, so each subtree's slots in the tree's depth-first list are known before it is
/// built, and the halves can fill theirs at the same time.
fn cluster_count(n: usize) -> usize {
    // The counts of `m` and `m + 1` triangles from those of `h = ⌊m/2⌋` and `h + 1`: the
    // halves of `m` and of `m + 1` are each `h` or `h + 1` triangles.
    fn pair(m: usize) -> (usize, usize) {
        if m < LEAF {
            return (1, 1);
        }
        let (a, b) = pair(m / 2);
        if m.is_multiple_of(2) {
            (if m <= LEAF { 1 } else { 1 + 2 * a }, 1 + a + b)
        } else {
            (if m <= LEAF { 1 } else { 1 + a + b }, 1 + 2 * b)
        }
    }
    pair(n).0
}

/// Fills `nodes` (exactly [`cluster_count`] of `tris.len()` slots, the first at `index` in the
/// tree's list) with the cluster of `tris` (starting at `first` in the tree's order) and, if it
/// holds more than [`LEAF`] triangles, its two halves split at the median of the triangles'
/// centroids along the axis where they spread most, the first half's subtree next, then the
/// second's. Returns the moments of `tris`.
fn build_node(
    nodes: &mut [Cluster],
    index: usize,
    tris: &mut [[Vec3; 3]],
    first: usize,
) -> Moments {
    let (node, below) = nodes
        .split_first_mut()
        .expect("a slot for every cluster of the subtree");
    if tris.len() <= LEAF {
        let moments = Moments::of(tris);
        *node = Cluster {
            first: first as u32,
            count: tris.len() as u32,
            ..Cluster::with_moments(&moments, tris)
        };
        return moments;
    }
    let centroid = |t: &[Vec3; 3]| t[0] + t[1] + t[2];
    let (lo, hi) = tris.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), t| (lo.min(centroid(t)), hi.max(centroid(t))),
    );
    let axis = (hi - lo).max_position();
    let mid = tris.len() / 2;
    tris.select_nth_unstable_by(mid, |a, b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
    let parallel = tris.len() >= PARALLEL_MIN;
    let (left, right) = tris.split_at_mut(mid);
    let (left_nodes, right_nodes) = below.split_at_mut(cluster_count(mid));
    let second = index + 1 + left_nodes.len();
    let (l, r) = if parallel {
        rt_core::par::join(
            || build_node(left_nodes, index + 1, left, first),
            || build_node(right_nodes, second, right, first + mid),
        )
    } else {
        (
            build_node(left_nodes, index + 1, left, first),
            build_node(right_nodes, second, right, first + mid),
        )
    };
    let moments = l.merge(&r, tris[0][0].as_dvec3());
    *node = Cluster {
        first: second as u32,
        count: 0,
        ..Cluster::with_moments(&moments, tris)
    };
    moments
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_meshes::sphere;
    use rt_core::{Rng, Triangle};

    fn random_soup(rng: &mut Rng, n: usize, spread: f32) -> Vec<Triangle> {
        let mut point = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * spread;
        (0..n)
            .map(|_| {
                let a = point();
                Triangle::new(a, a + point() * 0.1, a + point() * 0.1)
            })
            .collect()
    }

    #[test]
    fn a_closed_sphere_winds_once_inside_and_never_outside() {
        let tris = sphere(Vec3::new(1.0, 2.0, 3.0), 2.0, 24, 48);
        let tree = WindingTree::build(&tris).unwrap();
        for (p, expected) in [
            (Vec3::new(1.0, 2.0, 3.0), 1.0),
            (Vec3::new(2.5, 2.0, 3.0), 1.0),
            (Vec3::new(3.5, 2.0, 3.0), 0.0),
            (Vec3::new(40.0, -7.0, 3.0), 0.0),
        ] {
            let exact = winding_number_exact(&tris, p).unwrap();
            assert!((exact - expected).abs() < 1e-9, "{p}: {exact}");
            let fast = tree.winding_number(p, 1e-3);
            assert!((fast.value - expected).abs() <= 1e-3, "{p}: {fast:?}");
            assert_eq!(tree.is_inside(p), expected == 1.0, "{p}");
        }
    }

    /// Each cluster's expansion, taken at every distance outside its radius (an infinite
    /// tolerance), is within the stated bound of the exact sum. A wrong or missing term of order
    /// 1 or 2 misses by about `A·R/D³` or `A·R²/D⁴`, which at `D = 100 R` is 30 or 3 times the
    /// bound `A·R³/(π (D − R)⁵)`.
    #[test]
    fn the_expansion_stays_within_its_bound_at_every_distance() {
        let mut rng = Rng::new(7);
        for _ in 0..50 {
            let tris = random_soup(&mut rng, 8, 1.0);
            let tree = WindingTree::build(&tris).unwrap();
            assert_eq!(tree.nodes.len(), 1, "eight triangles make one leaf");
            let c = &tree.nodes[0];
            let centre = Vec3::from_array(c.center.map(|x| x as f32));
            for scale in [1.5, 3.0, 10.0, 100.0, 1000.0] {
                let dir = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5).normalize();
                let p = centre + dir * (c.radius * scale) as f32;
                let exact = winding_number_exact(&tris, p).unwrap();
                let fast = tree.winding_number(p, f64::INFINITY);
                assert!(
                    fast.error_bound > 0.0,
                    "the expansion was taken at {scale} R"
                );
                assert!(
                    (fast.value - exact).abs() <= fast.error_bound + 1e-13,
                    "at {scale} R: fast {} exact {exact} bound {}",
                    fast.value,
                    fast.error_bound
                );
            }
        }
    }

    /// On soups of every size the fast evaluation stays within the tolerance asked for and
    /// within the bound it reports, and `is_inside` agrees with the exact sum.
    #[test]
    fn the_fast_winding_number_keeps_its_tolerance_on_soups() {
        let mut rng = Rng::new(11);
        for n in [1, 9, 100, 2000] {
            let mut tris = random_soup(&mut rng, n, 2.0);
            tris.extend(sphere(Vec3::ONE, 0.7, 8, 16));
            let tree = WindingTree::build(&tris).unwrap();
            for _ in 0..60 {
                let p = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - Vec3::splat(0.5);
                let exact = winding_number_exact(&tris, p).unwrap();
                for tolerance in [0.0, 1e-4, 0.01, 0.25] {
                    let w = tree.winding_number(p, tolerance);
                    assert!(
                        w.error_bound <= tolerance + 1e-12,
                        "{n}: {w:?} over {tolerance}"
                    );
                    assert!(
                        (w.value - exact).abs() <= w.error_bound + 1e-9,
                        "{n} triangles at {p}: {w:?}, exact {exact}, tolerance {tolerance}"
                    );
                }
                if (exact - 0.5).abs() > 1e-9 {
                    assert_eq!(
                        tree.is_inside(p),
                        exact > 0.5,
                        "{n} triangles at {p}: {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_hole_leaves_a_smooth_winding_number_instead_of_a_flip() {
        // The sphere without the triangles around its north pole: inside is still inside.
        let mut tris = sphere(Vec3::ZERO, 1.0, 16, 32);
        tris.drain(..32);
        let tree = WindingTree::build(&tris).unwrap();
        let w = tree.winding_number(Vec3::new(0.0, 0.0, -0.5), 0.0).value;
        assert!(w > 0.9 && w < 1.0, "{w}");
        assert!(tree.is_inside(Vec3::ZERO));
        // Just above the hole, outside: well under a half.
        assert!(!tree.is_inside(Vec3::new(0.0, 0.0, 1.2)));
    }

    #[test]
    fn bad_input_gets_nan_or_an_error_not_a_panic() {
        let tris = [
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0),
            Triangle::new(Vec3::NAN, Vec3::X, Vec3::Y),
        ];
        let tree = WindingTree::build(&tris).unwrap();
        assert_eq!(
            tree.len(),
            1,
            "the degenerate and the NaN triangle are left out"
        );
        assert!(tree.winding_number(Vec3::NAN, 0.0).value.is_nan());
        assert!(!tree.is_inside(Vec3::new(f32::INFINITY, 0.0, 0.0)));
        let empty = WindingTree::build::<Triangle>(&[]).unwrap();
        assert_eq!(empty.winding_number(Vec3::ONE, 0.0).value, 0.0);
        let spheres = [rt_core::Sphere::new(Vec3::ZERO, 1.0)];
        assert_eq!(
            WindingTree::build(&spheres).unwrap_err(),
            NotATriangle { prim: 0 }
        );
        assert!(winding_number_exact(&spheres, Vec3::ZERO).is_err());
    }

    /// The slots the build gives each subtree are exactly the clusters it makes: the count
    /// of the recursion it stands for, for every size up to a few thousand.
    #[test]
    fn the_cluster_count_is_the_recursion_it_stands_for() {
        fn counted(n: usize) -> usize {
            if n <= LEAF {
                1
            } else {
                1 + counted(n / 2) + counted(n - n / 2)
            }
        }
        for n in 1..3000 {
            assert_eq!(cluster_count(n), counted(n), "{n} triangles");
        }
    }

    /// Every cluster of a tree, whose moments the build merged from its children's, has the
    /// coefficients and radius of the cluster computed directly from its triangles, up to
    /// rounding: a shift with a wrong sign or a missing term is off by the size of the terms
    /// themselves. The soup lies far from the origin and spreads unevenly, so that the shifts
    /// are large, and the tree is big enough to build some halves on two threads.
    #[test]
    fn merged_moments_are_the_moments_of_the_triangles() {
        let mut rng = Rng::new(11);
        let far = Vec3::new(1000.0, -500.0, 250.0);
        let tris: Vec<Triangle> = random_soup(&mut rng, 2 * PARALLEL_MIN + 37, 10.0)
            .into_iter()
            .map(|t| {
                Triangle::new(
                    t.v0 * t.v0.x + far,
                    t.v1 * t.v0.x + far,
                    t.v2 * t.v0.x + far,
                )
            })
            .collect();
        let tree = WindingTree::build(&tris).unwrap();
        assert_eq!(tree.nodes.len(), cluster_count(tris.len()));
        // Each cluster's triangles, by a walk over the tree's list.
        fn spans(
            tree: &WindingTree,
            i: usize,
            out: &mut Vec<(usize, usize, usize)>,
        ) -> (usize, usize) {
            let c = &tree.nodes[i];
            let span = if c.count > 0 {
                (c.first as usize, c.first as usize + c.count as usize)
            } else {
                let (lo, _) = spans(tree, i + 1, out);
                let (_, hi) = spans(tree, c.first as usize, out);
                (lo, hi)
            };
            out.push((i, span.0, span.1));
            span
        }
        let mut all = Vec::new();
        assert_eq!(spans(&tree, 0, &mut all), (0, tris.len()));
        assert_eq!(all.len(), tree.nodes.len(), "every cluster is reached once");
        let close = |a: f64, b: f64, scale: f64| (a - b).abs() <= 1e-9 * scale;
        let mut interior = 0;
        for (i, lo, hi) in all {
            let (built, direct) = (&tree.nodes[i], Cluster::of(&tree.tris[lo..hi]));
            interior += usize::from(built.count == 0);
            let r = direct.radius;
            // Each coefficient scaled by its order's size: area × radius to the power.
            let a = direct.area;
            assert!(close(built.area, a, a), "cluster {i}: area");
            assert!(close(built.radius, r, r), "cluster {i}: radius");
            for k in 0..3 {
                assert!(
                    close(built.center[k], direct.center[k], r),
                    "cluster {i}: centre"
                );
                assert!(close(built.n[k], direct.n[k], a), "cluster {i}: n");
                assert!(close(built.v[k], direct.v[k], a * r * r), "cluster {i}: v");
            }
            assert!(
                close(built.trace, direct.trace, a * r),
                "cluster {i}: trace"
            );
            for (b, d) in built.quadratic.iter().zip(&direct.quadratic) {
                assert!(close(*b, *d, a * r), "cluster {i}: quadratic {b} {d}");
            }
            for (b, d) in built.cubic.iter().zip(&direct.cubic) {
                assert!(close(*b, *d, a * r * r), "cluster {i}: cubic {b} {d}");
            }
        }
        assert!(interior > 1000, "{interior} interior clusters");
    }
}

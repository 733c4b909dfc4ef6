//! Lab: a uniform grid, in six steps.
//!
//! A uniform grid cuts the scene's box into `nx × ny × nz` equal cells and lists, for each
//! cell, the triangles that may touch it. A ray walks the cells it crosses in order (a 3D-DDA,
//! Amanatides & Woo 1987) and tests only their triangles. Read `HANDOUT.md` first; then fill in
//! the `todo!()`s step by step, checking each with `cargo test step_N`:
//!
//! 1. [`step1`]: the box around the scene, and the slab test of a ray against a box.
//! 2. [`step2`]: the resolution (how many cells), and the build (which triangles in which cell).
//! 3. [`step3`]: the walk through the cells the ray crosses, in order.
//! 4. [`step4`]: the walk for a query (the closest hit is one), with the rule for when it may
//!    stop.
//! 5. [`step5`]: the any-hit walk (shadow rays): stop at the first hit.
//! 6. [`step6`]: mailboxing: a triangle in several cells is tested once per ray.
//!
//! Nothing outside the step files needs to change: this file wires them into the
//! [`rt_core::Accel`] trait, so the conformance kit and the shootout can run your grid.

// Until a step is written, its stub leaves parameters and imports unused. (The reference
// solution's copy of this file has no such line.)
#![allow(unused_imports, unused_variables)]

use rt_core::glam::Vec3;
use rt_core::query::Deduplicated;
use rt_core::{Aabb, Accel, BallQuery, BuildStats, Ray, RayQuery, Region, Stats, Triangle};

pub mod step1;
pub mod step2;
pub mod step3;
pub mod step4;
pub mod step5;
pub mod step6;

/// Build parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct GridParams {
    /// Cells per triangle: the grid has about `density × N` cells (step 2).
    pub density: f32,
    /// Whether each ray keeps a mailbox of the triangles it tested (step 6).
    pub mailbox: bool,
}

impl Default for GridParams {
    fn default() -> Self {
        Self {
            density: 2.0,
            mailbox: false,
        }
    }
}

impl GridParams {
    /// The default density, with mailboxes (step 6).
    pub fn mailboxed() -> Self {
        Self {
            mailbox: true,
            ..Self::default()
        }
    }
}

/// The grid: its box, its resolution, and the triangles listed per cell.
#[derive(Clone, Debug)]
pub struct LabGrid {
    /// The box around the valid triangles (step 1).
    pub bounds: Aabb,
    /// Cells along x, y and z (step 2); each at least 1.
    pub res: [u32; 3],
    /// `res / extent` per axis: multiply a coordinate's offset from `bounds.min` by it to get
    /// its cell. Zero on an axis where the box is flat.
    pub inv_cell: Vec3,
    /// `cells[i]..cells[i + 1]` is the range of `refs` listing cell `i`'s triangles; cell
    /// `[x, y, z]` is number `x + nx * (y + ny * z)` (step 2).
    pub cells: Vec<u32>,
    /// Triangle indices, cell after cell.
    pub refs: Vec<u32>,
    /// The input triangles; hits name their index here.
    pub tris: Vec<Triangle>,
    /// The parameters it was built with.
    pub params: GridParams,
}

impl LabGrid {
    /// The number of cell `c`.
    pub fn index(&self, c: [u32; 3]) -> usize {
        (c[0] + self.res[0] * (c[1] + self.res[1] * c[2])) as usize
    }

    /// The triangles listed in cell `c`.
    pub fn cell(&self, c: [u32; 3]) -> &[u32] {
        let i = self.index(c);
        &self.refs[self.cells[i] as usize..self.cells[i + 1] as usize]
    }

    /// The coordinate of the `k`-th cell boundary on `axis` (0 is `bounds.min`, `res` is
    /// `bounds.max`, exactly).
    pub fn plane(&self, axis: usize, k: u32) -> f32 {
        if k >= self.res[axis] {
            return self.bounds.max[axis];
        }
        let t = k as f32 / self.res[axis] as f32;
        self.bounds.min[axis] + (self.bounds.max[axis] - self.bounds.min[axis]) * t
    }

    /// The box of cell `c`.
    pub fn cell_box(&self, c: [u32; 3]) -> Aabb {
        let lo = Vec3::new(
            self.plane(0, c[0]),
            self.plane(1, c[1]),
            self.plane(2, c[2]),
        );
        let hi = Vec3::new(
            self.plane(0, c[0] + 1),
            self.plane(1, c[1] + 1),
            self.plane(2, c[2] + 1),
        );
        Aabb::new(lo, hi)
    }
}

impl Accel for LabGrid {
    type Prim = Triangle;
    type Params = GridParams;
    const NAME: &'static str = "lab-grid";

    fn presets() -> Vec<(&'static str, GridParams)> {
        vec![
            ("default", GridParams::default()),
            ("mailbox", GridParams::mailboxed()),
        ]
    }

    fn build(prims: &[Triangle], params: &GridParams) -> Self {
        let bounds = step1::scene_bounds(prims);
        let valid = prims
            .iter()
            .filter(|t| rt_core::Primitive::is_valid(*t))
            .count();
        let res = step2::resolution(&bounds, valid, params.density);
        let extent = bounds.max - bounds.min;
        let inv_cell = Vec3::from_array(std::array::from_fn(|a| {
            if extent[a] > 0.0 {
                res[a] as f32 / extent[a]
            } else {
                0.0
            }
        }));
        let mut grid = LabGrid {
            bounds,
            res,
            inv_cell,
            cells: Vec::new(),
            refs: Vec::new(),
            tris: prims.to_vec(),
            params: params.clone(),
        };
        (grid.cells, grid.refs) = step2::fill_cells(&grid);
        // A vector that grew by doubling may hold up to twice what it uses: the grid keeps only
        // its cells and references, so that its memory figure counts those.
        grid.cells.shrink_to_fit();
        grid.refs.shrink_to_fit();
        grid
    }

    /// The walks of steps 4 and 5: an occlusion query (a shadow ray's) takes step 5's walk,
    /// every other query step 4's. A query that must see each hit once (all hits, counts) is
    /// offered each triangle once ([`Deduplicated`]), since the walk may meet a triangle again.
    fn ray_query<Q: RayQuery, S: Stats>(&self, ray: &Ray, query: &mut Q, stats: &mut S) {
        if Q::OCCLUSION {
            step5::any_hit(self, ray, query, stats);
        } else if Q::REPEATABLE {
            step4::walk(self, ray, query, stats);
        } else {
            step4::walk(self, ray, &mut Deduplicated::new(query), stats);
        }
    }

    fn bounds(&self) -> Aabb {
        if self.refs.is_empty() {
            Aabb::EMPTY
        } else {
            self.bounds
        }
    }

    /// Closest points are not a step of this lab. This answers them simply and correctly: every
    /// cell the ball still reaches, in index order (`rt-grid` visits cells in growing shells
    /// around the point instead).
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        if self.refs.is_empty() {
            return;
        }
        for z in 0..self.res[2] {
            for y in 0..self.res[1] {
                for x in 0..self.res[0] {
                    let c = [x, y, z];
                    if self.cell_box(c).distance_squared(query.center()) > query.radius_sq() {
                        continue;
                    }
                    stats.node_visit();
                    for &id in self.cell(c) {
                        stats.prim_test();
                        query.test(&self.tris[id as usize], id);
                    }
                }
            }
        }
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.cells.capacity() * 4
            + self.refs.capacity() * 4
            + self.tris.capacity() * size_of::<Triangle>()
    }

    fn build_stats(&self) -> BuildStats {
        let n = self.res.iter().map(|&r| r as usize).product::<usize>();
        let full = (0..n)
            .filter(|&i| self.cells[i + 1] > self.cells[i])
            .count();
        BuildStats {
            nodes: n,
            leaves: n,
            empty_leaves: n - full,
            max_depth: 0,
            prim_refs: self.refs.len(),
            valid_prims: self
                .tris
                .iter()
                .filter(|t| rt_core::Primitive::is_valid(*t))
                .count(),
            extra: vec![],
        }
    }

    fn regions(&self, visit: &mut dyn FnMut(Region)) {
        if self.refs.is_empty() {
            return;
        }
        for z in 0..self.res[2] {
            for y in 0..self.res[1] {
                for x in 0..self.res[0] {
                    let c = [x, y, z];
                    visit(Region {
                        bounds: self.cell_box(c),
                        depth: 0,
                        prims: Some(self.cell(c).len() as u32),
                        split: None,
                    });
                }
            }
        }
    }
}

//! Lab: the hierarchical grid's nested walk, in five steps.
//!
//! A uniform grid sized for a stadium puts a whole teapot into a few cells. The hierarchical grid
//! keeps the grid's cheap steps and refines where triangles crowd: a coarse top grid, and in each
//! crowded cell a grid of its own over that cell, sized by the cell's triangles, recursively.
//! The hierarchy here is built for you by `rt-hgrid`'s builder (the one the `hgrid` row of the
//! shootout uses), and the 3D-DDA that walks one grid is given (`rt_grid::dda`, the uniform
//! grid lab's step 3); you write the nesting: which cell is which, the cells beside the path,
//! and the walk that goes down into a nested grid and comes back up. Read `HANDOUT.md` first;
//! then fill in the `todo!()`s step by step, checking each with `cargo test step_N`:
//!
//! 1. [`step1`]: a cell of a grid of the hierarchy, the triangles to test in a cell, and a DDA
//!    started in a grid.
//! 2. [`step2`]: the cells beside the path, where two boundaries are crossed at once.
//! 3. [`step3`]: the nested walk over the cells, front to back, with a stack of DDAs.
//! 4. [`step4`]: the walk for a query (the closest hit is one), with the rule for when it may
//!    stop, and a mailbox.
//! 5. [`step5`]: the any-hit walk (shadow rays): stop at the first hit.
//!
//! Nothing outside the step files needs to change: this file builds the hierarchy and wires the
//! steps into the [`rt_core::Accel`] trait, so the conformance kit and the shootout can run
//! your walk.

// Until a step is written, its stub leaves parameters and imports unused. (The reference
// solution's copy of this file has no such line.)
#![allow(unused_imports, unused_variables)]

use rt_core::query::Deduplicated;
use rt_core::{Aabb, Accel, BallQuery, BuildStats, Ray, RayQuery, Region, Stats, Triangle};
use rt_hgrid::HGrid;

pub use rt_grid::GridShape;
pub use rt_grid::dda::{Dda, RayAxes};
pub use rt_hgrid::{Cell, HGridParams, Level, MAX_LEVELS};

pub mod step1;
pub mod step2;
pub mod step3;
pub mod step4;
pub mod step5;

/// Parameters: how the hierarchy is built, and whether the walk keeps a mailbox.
#[derive(Clone, Debug, Default)]
pub struct HGridLabParams {
    /// The builder's parameters (`rt_hgrid::HGridParams`).
    pub grid: HGridParams,
    /// Whether a ray skips a triangle it tested in an earlier cell (step 4).
    pub no_mailbox: bool,
}

/// A hierarchical grid built by `rt-hgrid`, walked by your code.
#[derive(Clone, Debug)]
pub struct LabHGrid {
    /// The built hierarchy: [`HGrid::levels`] (level 0 is the top grid; each [`Level`] has its
    /// [`GridShape`], where its cells start in [`HGrid::cells`], and for a nested grid the
    /// reference range of the parent cell it refines), [`HGrid::cells`] (a [`Cell`] lists
    /// `references()[cell.references()]`, or holds the nested grid `levels()[cell.nested()]`)
    /// and [`HGrid::references`].
    pub grid: HGrid<Triangle>,
    /// The input triangles; hits name their index here.
    pub tris: Vec<Triangle>,
    /// The parameters it was built with.
    pub params: HGridLabParams,
}

impl Accel for LabHGrid {
    type Prim = Triangle;
    type Params = HGridLabParams;
    const NAME: &'static str = "lab-hgrid";

    fn presets() -> Vec<(&'static str, HGridLabParams)> {
        let no_mailbox = HGridLabParams {
            no_mailbox: true,
            ..HGridLabParams::default()
        };
        vec![
            ("default", HGridLabParams::default()),
            ("nomailbox", no_mailbox),
        ]
    }

    fn build(prims: &[Triangle], params: &HGridLabParams) -> Self {
        Self {
            grid: HGrid::build(prims, &params.grid),
            tris: prims.to_vec(),
            params: params.clone(),
        }
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
        Accel::bounds(&self.grid)
    }

    /// Closest points are not a step of this lab: `rt-hgrid`'s own query answers them.
    fn ball_query<Q: BallQuery<Triangle>, S: Stats>(&self, query: &mut Q, stats: &mut S) {
        self.grid.ball_query(query, stats);
    }

    fn memory_bytes(&self) -> usize {
        size_of::<Self>() + self.grid.memory_bytes() + self.tris.capacity() * size_of::<Triangle>()
    }

    fn build_stats(&self) -> BuildStats {
        self.grid.build_stats()
    }

    fn regions(&self, visit: &mut dyn FnMut(Region)) {
        self.grid.regions(visit);
    }
}

//! Structural checks: the invariants traversal relies on.

use crate::Grid;
use crate::builder::margin;
use rt_core::{Primitive, ValidationError};

impl<P: Primitive> Grid<P> {
    /// Checks the grid: offsets that start at 0, never decrease and end at the reference count;
    /// references to valid primitives, strictly increasing within a cell; and each valid
    /// primitive listed in exactly the cells of its bounding box that it overlaps (the builder's
    /// test), so none is missing where a ray could hit it.
    pub fn validate(&self) -> Result<(), ValidationError> {
        let err = |s: String| Err(ValidationError::new(s));
        let n = self.shape.cell_count();
        if self.cells.len() != n + 1 || self.cells[0] != 0 {
            return err(format!("{} offsets for {n} cells", self.cells.len()));
        }
        if self.cells[n] as usize != self.refs.len() {
            return err(format!(
                "the last offset is {}, with {} references",
                self.cells[n],
                self.refs.len()
            ));
        }
        let mut listed = vec![0usize; self.prims.len()];
        for i in 0..n {
            let (lo, hi) = (self.cells[i] as usize, self.cells[i + 1] as usize);
            if lo > hi || hi > self.refs.len() {
                return err(format!(
                    "cell {i}: offsets {lo}..{hi} decrease or pass the {} references",
                    self.refs.len()
                ));
            }
            let list = &self.refs[lo..hi];
            if list.windows(2).any(|w| w[0] >= w[1]) {
                return err(format!("cell {i}: references not strictly increasing"));
            }
            for &id in list {
                let Some(p) = self.prims.get(id as usize) else {
                    return err(format!("cell {i}: reference {id} out of range"));
                };
                if !p.is_valid() {
                    return err(format!("cell {i}: invalid primitive {id} referenced"));
                }
                listed[id as usize] += 1;
            }
        }
        let valid = self.prims.iter().filter(|p| p.is_valid()).count();
        if valid != self.valid_prims {
            return err(format!(
                "{} valid primitives counted, {valid} found",
                self.valid_prims
            ));
        }
        // Recompute every valid primitive's cells with the builder's test.
        let m = margin(&self.shape);
        let mut cells = Vec::new();
        for (id, p) in self.prims.iter().enumerate() {
            if !p.is_valid() {
                continue;
            }
            cells.clear();
            crate::builder::cells_of(&self.shape, m, p, id as u32, self.exact, &mut cells);
            if cells.is_empty() || cells.len() != listed[id] {
                return err(format!(
                    "primitive {id}: listed in {} cells, overlaps {}",
                    listed[id],
                    cells.len()
                ));
            }
            for &(c, _) in &cells {
                let (lo, hi) = (
                    self.cells[c as usize] as usize,
                    self.cells[c as usize + 1] as usize,
                );
                if self.refs[lo..hi].binary_search(&(id as u32)).is_err() {
                    return err(format!("primitive {id}: missing from cell {c}"));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::{Grid, GridParams};
    use rt_core::{Accel, Triangle};

    fn grid() -> Grid<Triangle> {
        let mesh = rt_scene::scenes::random_soup(300, 3);
        Grid::build(&mesh.triangles(), &GridParams::standard())
    }

    /// The first cell holding at least two references.
    fn full_cell(g: &Grid<Triangle>) -> usize {
        (0..g.shape.cell_count())
            .find(|&i| g.cells[i + 1] - g.cells[i] >= 2)
            .unwrap()
    }

    #[test]
    fn each_corruption_is_caught() {
        assert!(grid().validate().is_ok());

        let mut g = grid();
        let i = full_cell(&g);
        let lo = g.cells[i] as usize;
        g.refs.swap(lo, lo + 1);
        assert!(g.validate().unwrap_err().message.contains("increasing"));

        // The cell's last reference, so its list stays increasing.
        let mut g = grid();
        let last = g.cells[full_cell(&g) + 1] as usize - 1;
        g.refs[last] = 10_000;
        assert!(g.validate().unwrap_err().message.contains("out of range"));

        // A reference moved from one cell to the next: the primitive is missing where it
        // overlaps and listed where it does not.
        let mut g = grid();
        let i = full_cell(&g);
        g.cells[i + 1] -= 1;
        assert!(g.validate().is_err());

        let mut g = grid();
        g.cells.pop();
        assert!(g.validate().unwrap_err().message.contains("offsets"));
    }
}

//! Structural checks: the invariants traversal relies on.

use crate::HGrid;
use crate::builder::MAX_LEVELS;
use rt_core::{Primitive, ValidationError};
use rt_grid::cells_overlapping;

impl<P: Primitive> HGrid<P> {
    /// Checks the hierarchy: every grid's cells in range and each nested grid referenced by
    /// exactly one cell of a grid before it, one level up, over that cell's box, at most
    /// [`MAX_LEVELS`] levels; and in every grid, each cell listing exactly the primitives of its
    /// parent's list that overlap it (the builder's test), in increasing order, a parent cell
    /// through its own list. So no primitive is missing where a ray could hit it.
    pub fn validate(&self) -> Result<(), ValidationError> {
        let err = |s: String| Err(ValidationError::new(s));
        let Some(top) = self.levels.first() else {
            return err("no grid".into());
        };
        if top.first_cell != 0 || top.depth != 0 {
            return err("the top grid does not start the cells".into());
        }
        let mut parent_of = vec![None; self.levels.len()];
        for (g, level) in self.levels.iter().enumerate() {
            let end = level.first_cell.checked_add(level.shape.cell_count());
            let Some(end) = end.filter(|&end| end <= self.cells.len()) else {
                return err(format!("grid {g}: cells out of range"));
            };
            if level.depth as usize >= MAX_LEVELS {
                return err(format!("grid {g}: depth out of range"));
            }
            let (lo, hi) = level.all;
            if lo > hi || hi > self.refs.len() || (g == 0 && hi != 0) {
                return err(format!(
                    "grid {g}: parent references {lo}..{hi} out of range"
                ));
            }
            for (c, cell) in self.cells[level.first_cell..end].iter().enumerate() {
                match cell.nested() {
                    Some(n) if n <= g || n >= self.levels.len() || parent_of[n].is_some() => {
                        return err(format!("grid {g} cell {c}: bad nested grid {n}"));
                    }
                    Some(n) => {
                        parent_of[n] = Some(g);
                        let child = &self.levels[n];
                        if child.depth != level.depth + 1
                            || child.shape.bounds() != level.shape.cell_box(level.shape.coords(c))
                        {
                            return err(format!("grid {n}: not the box of its parent cell"));
                        }
                    }
                    None if cell.references().end > self.refs.len() => {
                        return err(format!("grid {g} cell {c}: references out of range"));
                    }
                    None => {}
                }
            }
        }
        if let Some(g) = (1..self.levels.len()).find(|&g| parent_of[g].is_none()) {
            return err(format!("grid {g}: no parent cell"));
        }
        let deepest = self.levels.iter().map(|l| l.depth).max().unwrap_or(0);
        let valid_count = self.prims.iter().filter(|p| p.is_valid()).count();
        if (deepest, valid_count) != (self.depth, self.valid_prims) {
            return err(format!(
                "stats say depth {} and {} valid primitives; there are {deepest} and {valid_count}",
                self.depth, self.valid_prims
            ));
        }
        // Every grid lists exactly what the builder's test says, given its parent's list.
        let valid: Vec<u32> = (0..self.prims.len() as u32)
            .filter(|&i| self.prims[i as usize].is_valid())
            .collect();
        let mut pairs = Vec::new();
        for (g, level) in self.levels.iter().enumerate() {
            let input: &[u32] = if g == 0 {
                &valid
            } else {
                &self.refs[level.all.0..level.all.1]
            };
            if input
                .iter()
                .any(|&i| self.prims.get(i as usize).is_none_or(|p| !p.is_valid()))
            {
                return err(format!(
                    "grid {g}: an invalid or unknown primitive is listed"
                ));
            }
            pairs.clear();
            for &id in input {
                cells_overlapping(&level.shape, &self.prims[id as usize], id, &mut pairs);
            }
            pairs.sort_unstable();
            let n = level.shape.cell_count();
            let mut k = 0;
            for c in 0..n {
                let start = k;
                while k < pairs.len() && pairs[k].0 as usize == c {
                    k += 1;
                }
                let expected: Vec<u32> = pairs[start..k].iter().map(|p| p.1).collect();
                let cell = self.cells[level.first_cell + c];
                let listed = match cell.nested() {
                    Some(nested) => {
                        let (lo, hi) = self.levels[nested].all;
                        &self.refs[lo..hi]
                    }
                    None => &self.refs[cell.references()],
                };
                if listed != expected.as_slice() {
                    return err(format!(
                        "grid {g} cell {c}: lists {} primitives, overlaps {}",
                        listed.len(),
                        expected.len()
                    ));
                }
            }
        }
        Ok(())
    }
}

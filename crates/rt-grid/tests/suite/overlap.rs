//! `cells_meeting` finds exactly the cells whose boxes meet a query box: boxes with corners on
//! the grid's planes, between them, of zero size, and reaching outside the grid.

use rt_core::glam::Vec3;
use rt_core::{Aabb, Rng};
use rt_grid::GridShape;
use rt_grid::overlap::cells_meeting;
use std::ops::ControlFlow;

#[test]
fn cells_meeting_is_the_cells_whose_boxes_meet_the_query() {
    let mut rng = Rng::new(29);
    let shapes = [
        GridShape::new(Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)), [7, 5, 3]),
        GridShape::new(
            Aabb::new(Vec3::new(-1e3, 0.1, -0.3), Vec3::new(2e3, 0.7, 0.4)),
            [13, 1, 9],
        ),
    ];
    for shape in &shapes {
        let res = shape.resolution_per_axis();
        let b = shape.bounds();
        // A coordinate on axis `a`: a plane, a point between planes, or beyond the grid.
        let coordinate = |rng: &mut Rng, a: usize| match rng.below(3) {
            0 => shape.plane(a, rng.below(res[a] + 1)),
            1 => rng.range(b.min[a], b.max[a]),
            _ => rng.range(b.min[a] - 1.0, b.max[a] + 1.0),
        };
        for _ in 0..2000 {
            let p = Vec3::from_array(std::array::from_fn(|a| coordinate(&mut rng, a)));
            let q = if rng.below(4) == 0 {
                p
            } else {
                Vec3::from_array(std::array::from_fn(|a| coordinate(&mut rng, a)))
            };
            let query = Aabb::new(p.min(q), p.max(q));
            let mut found = Vec::new();
            let _ = cells_meeting(shape, &query, |c| {
                found.push(c);
                ControlFlow::Continue(())
            });
            let mut expected = Vec::new();
            for z in 0..res[2] {
                for y in 0..res[1] {
                    for x in 0..res[0] {
                        if shape.cell_box([x, y, z]).overlaps(&query) {
                            expected.push([x, y, z]);
                        }
                    }
                }
            }
            assert_eq!(found, expected, "query {query:?}");
        }
    }
}

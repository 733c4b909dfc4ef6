//! Box queries over Möller–Trumbore triangles, whose packs keep edges rather than vertices:
//! the tree must list exactly what brute force lists, on boxes that touch the triangles at the
//! vertices the edges give back.

use rt_bvh::{Bvh, BvhParams};
use rt_conformance::{compare_boxes, scene_boxes};
use rt_core::{Aabb, Accel, BruteForce, MtTriangle, Triangle};
use rt_scene::scenes;

#[test]
fn moller_trumbore_packs_list_what_brute_force_lists() {
    let scenes: [(&str, Vec<Triangle>); 3] = [
        ("lattice", rt_conformance::lattice_triangles(5, 300)),
        ("soup", scenes::random_soup(400, 13).triangles()),
        ("sphereflake", scenes::sphereflake(1, 4, 6).triangles()),
    ];
    for (name, tris) in scenes {
        let mt: Vec<MtTriangle> = tris.iter().copied().map(MtTriangle).collect();
        let mut boxes = scene_boxes(&mt, 3);
        // Point and flat boxes on the vertices the packs give back, which can differ from the
        // input's vertices in the last bit.
        for t in mt.iter().take(200) {
            for v in t.edge_form() {
                boxes.push(Aabb::new(v, v));
                let mut flat = Aabb::from_points(&t.edge_form());
                flat.min.x = v.x;
                flat.max.x = v.x;
                boxes.push(flat);
            }
        }
        let reference = BruteForce::build(&mt, &());
        for params in [BvhParams::wide(), BvhParams::sah()] {
            let bvh = Bvh::build(&mt, &params);
            compare_boxes(&bvh, &reference, &boxes)
                .unwrap_or_else(|e| panic!("{name}, {:?}: {e}", params.layout));
        }
    }
}

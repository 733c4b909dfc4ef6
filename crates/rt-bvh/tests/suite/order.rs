//! The wide walk's visiting order: at every node a closest-hit ray enters two or more children
//! of, it goes on to the nearest and pushes the others farthest first, so that they come off
//! the stack nearest first. The order changes no answer (a popped subtree is skipped only by
//! its own entry distance), so the answers cannot show a wrong sort; the walk's trace does.

use rt_bvh::{Bvh, BvhParams};
use rt_core::trace::{Event, Place};
use rt_core::{Accel, Trace};
use rt_scene::raygen::incoherent_rays;
use rt_scene::scenes;

/// For each node whose ray entered `n >= 2` children: the children's entry distances as the
/// `Child` events gave them, the pushed ones in push order, and the one entered next.
struct Branch {
    entered: Vec<f32>,
    pushed: Vec<f32>,
    next: f32,
}

fn branches(events: &[Event]) -> Vec<Branch> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < events.len() {
        if !matches!(
            events[i],
            Event::Enter {
                place: Place::Node(_),
                ..
            }
        ) {
            i += 1;
            continue;
        }
        let mut j = i + 1;
        let mut entered = Vec::new();
        while let Some(Event::Child { t, .. }) = events.get(j) {
            entered.push(*t);
            j += 1;
        }
        let mut pushed = Vec::new();
        while let Some(Event::Push { t, .. }) = events.get(j) {
            pushed.push(*t);
            j += 1;
        }
        if entered.len() >= 2 {
            let Some(Event::Enter { t0, .. }) = events.get(j) else {
                panic!(
                    "after a node's pushes, the walk enters a child: {:?}",
                    events.get(j)
                );
            };
            out.push(Branch {
                entered,
                pushed,
                next: *t0,
            });
        }
        i = j;
    }
    out
}

#[test]
fn closest_hit_rays_take_the_nearest_child_and_push_the_others_farthest_first() {
    let mesh = scenes::builtin("random-soup:4000").expect("a built-in scene");
    let tris = mesh.triangles();
    let bvh = Bvh::build(&tris, &BvhParams::wide());
    // Rays from inside the soup enter many children of a node at once.
    let rays = incoherent_rays(&mesh.bounds(), 3000, 11);
    // How many nodes were entered through 2, 3, 4 and 5 or more children.
    let mut seen = [0usize; 4];
    for ray in &rays {
        let mut trace = Trace::default();
        let answer = bvh.intersect_with(ray, &mut trace);
        assert_eq!(answer, bvh.intersect(ray), "tracing changes no answer");
        for b in branches(&trace.events) {
            seen[b.entered.len().min(5) - 2] += 1;
            assert_eq!(
                b.pushed.len(),
                b.entered.len() - 1,
                "every other child is pushed"
            );
            assert!(
                b.pushed.windows(2).all(|w| w[0] >= w[1]),
                "pushed farthest first: {:?}",
                b.pushed
            );
            assert!(
                b.pushed.iter().all(|&t| b.next <= t),
                "the nearest child next: {} before {:?}",
                b.next,
                b.pushed
            );
            let mut all = b.pushed.clone();
            all.push(b.next);
            let mut entered = b.entered.clone();
            for v in [&mut all, &mut entered] {
                v.sort_by(f32::total_cmp);
            }
            assert_eq!(all, entered, "each entered child is visited or pushed once");
        }
    }
    assert!(
        seen.iter().all(|&n| n > 0),
        "nodes entered through 2, 3, 4 and 5+ children: {seen:?}"
    );
}

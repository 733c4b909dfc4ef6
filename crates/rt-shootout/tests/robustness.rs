//! Every row of the shootout, built-in and preset alike: a parallel build equals a
//! single-threaded one and answers bit for bit the same, and a closed mesh far from the origin
//! lets no ray from inside escape.

use rt_core::glam::Vec3;
use rt_core::{Counters, Hit, Ray, Triangle};
use rt_scene::{raygen, scenes};
use rt_shootout::structures::{self, Entry, Query};

/// Runs `f` on a rayon pool of `threads` threads.
fn on<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// An answer's bits, so that two answers compare equal only if they are the same to the bit.
fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
}

fn rows() -> Vec<Entry> {
    let mut rows = structures::all();
    rows.push(structures::brute_force());
    rows
}

#[test]
fn every_row_builds_and_answers_the_same_on_one_thread_and_on_two() {
    let mesh = scenes::builtin("teapot-in-stadium").unwrap();
    let tris = mesh.triangles();
    let scene = scenes::find("teapot-in-stadium").unwrap();
    let mut rays = scene.camera(&mesh.bounds(), 64, 48).primary_rays(64, 48);
    rays.extend(raygen::incoherent_rays(&mesh.bounds(), 2000, 7));
    for row in rows() {
        let one = on(1, || (row.build)(&tris));
        let two = on(2, || (row.build)(&tris));
        assert_eq!(one.build_stats_dyn(), two.build_stats_dyn(), "{}", row.name);
        assert!(
            one.regions_dyn() == two.regions_dyn(),
            "{}: the trees differ between one and two build threads",
            row.name
        );
        for query in [Query::Closest, Query::Any] {
            let (a, ca): (Vec<_>, Counters) =
                on(1, || structures::trace_counted(&*one, &rays, query));
            let (b, cb) = on(2, || structures::trace_counted(&*two, &rays, query));
            let differ = a.iter().zip(&b).position(|(x, y)| bits(*x) != bits(*y));
            if let Some(i) = differ {
                panic!(
                    "{} {query:?}: ray {} answers {:?} on one thread, {:?} on two",
                    row.name,
                    rays[i].to_line(),
                    a[i],
                    b[i]
                );
            }
            assert_eq!(ca, cb, "{} {query:?}: counters differ", row.name);
        }
    }
}

/// `n` directions spread evenly over the sphere (a Fibonacci lattice).
fn directions(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), y, r * phi.sin())
        })
        .collect()
}

#[test]
fn no_ray_escapes_a_closed_sphere_near_or_far_from_the_origin() {
    let dirs = directions(3000);
    for offset in [0.0, 1.0, 100.0, 1e4, 1.5e5] {
        let center = Vec3::new(1.0, 0.8, 0.6) * offset;
        let sphere = scenes::uv_sphere(center, 1.0, 48, 96);
        let tris: Vec<Triangle> = sphere.triangles();
        let rays: Vec<Ray> = dirs.iter().map(|&d| Ray::new(center, d)).collect();
        for row in rows() {
            let built = (row.build)(&tris);
            for query in [Query::Closest, Query::Any] {
                let (answers, _) = structures::trace_counted(&*built, &rays, query);
                if let Some(i) = answers.iter().position(Option::is_none) {
                    panic!(
                        "{} {query:?}: the ray {} escapes the sphere centred {offset} from the \
                         origin",
                        row.name,
                        rays[i].to_line()
                    );
                }
            }
        }
    }
}

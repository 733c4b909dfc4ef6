//! rt-bvh's presets against Embree 3 on the same triangles and the same rays, in one run:
//! primary, incoherent and shadow (any-hit) rays traced on one thread, and builds on one thread
//! and on all threads, over every built-in scene and every shared mesh (`--scenes peers`: the
//! bunny, the teapot, the sphereflake and the teapot in a stadium; or a list of names).
//! It prints the measurements and the ratio table (rt-bvh's default preset ÷ Embree, per scene
//! and ray kind, with geometric means), so nobody divides by hand, and a table of rt-bvh's ray
//! bundles against its single rays and Embree's coherent paths (16- and 8-ray packets, 64-ray
//! streams). Primary and shadow rays come from the view each scene fills (`compare`'s default),
//! which the ratios judge, and again from the sparse view, where most rays of a compact mesh
//! miss its box; every ray set's hit share is printed beside its speeds.
//!
//! ```sh
//! cargo bench -p rt-benches --features embree --bench peers            # with Embree
//! cargo bench -p rt-benches --bench peers                              # rt-bvh's presets only
//! cargo bench -p rt-benches --features embree --bench peers -- --passes 3 --scenes peers --json out.json
//! ```
//!
//! Method: every contender traces every ray set `--passes` times (5 by default), the passes of
//! all contenders interleaved (A B C A B C ...) so that drift in the machine's speed affects all
//! alike, after one untimed warm-up pass each; the median pass is reported. Builds likewise.
//! Embree uses its default scene flags and build quality `medium` (its default; the ratios divide
//! by it), with `high` (spatial splits) and `robust` (medium with `RTC_SCENE_FLAG_ROBUST`, the
//! mode Open3D ships and the one whose guarantee is closest to the watertight test's) beside it. Answers are checked: all rt-bvh presets
//! must agree exactly (the run panics otherwise), and the rays on which Embree's answer differs
//! from rt-bvh's are counted (Embree's triangle test is not watertight and breaks ties its own
//! way, so a few edge rays differ).

use rt_benches::{BenchScene, geomean, median};
use rt_bvh::{Bvh, BvhParams};
use rt_core::{Accel, Hit, MtTriangle, Ray, Triangle};
use rt_scene::raygen::RayKind;
use rt_scene::scenes::View;
use std::fmt::Write as _;
use std::time::Instant;

/// One traced contender: a timed pass over a ray slice (returns the hit count, so the work
/// cannot be optimized away) and single answers for the checks. The per-ray loop inside `pass`
/// is monomorphized; the box is crossed once per pass.
struct Tracer {
    name: String,
    pass: PassFn,
    answer: AnswerFn,
    /// Must answer exactly like the first contender (rt-bvh with the watertight test).
    exact: bool,
}

/// Traces a ray slice (closest hits, or any hits when the flag is set); returns the hit count.
type PassFn = Box<dyn Fn(&[Ray], bool) -> usize>;
/// One ray's answer (any-hit answers are `Some` with primitive `u32::MAX` when occluded).
type AnswerFn = Box<dyn Fn(&Ray, bool) -> Option<Hit>>;

const OCCLUDED: Hit = Hit {
    prim: u32::MAX,
    t: f32::NAN,
    u: 0.0,
    v: 0.0,
};

fn accel_tracer<A: Accel + 'static>(name: String, accel: A, exact: bool) -> Tracer {
    let accel = std::rc::Rc::new(accel);
    let a2 = accel.clone();
    Tracer {
        name,
        pass: Box::new(move |rays, any| {
            if any {
                rays.iter().filter(|r| accel.occluded(r)).count()
            } else {
                rays.iter().filter(|r| accel.intersect(r).is_some()).count()
            }
        }),
        answer: Box::new(move |r, any| {
            if any {
                a2.occluded(r).then_some(OCCLUDED)
            } else {
                a2.intersect(r)
            }
        }),
        exact,
    }
}

#[cfg(feature = "embree")]
fn embree_tracer(name: &str, scene: rt_benches::embree::EmbreeScene) -> Tracer {
    let scene = std::rc::Rc::new(scene);
    let s2 = scene.clone();
    Tracer {
        name: name.to_string(),
        pass: Box::new(move |rays, any| {
            if any {
                rays.iter().filter(|r| scene.occluded(r)).count()
            } else {
                rays.iter().filter(|r| scene.intersect(r).is_some()).count()
            }
        }),
        answer: Box::new(move |r, any| {
            if any {
                s2.occluded(r).then_some(OCCLUDED)
            } else {
                s2.intersect(r)
            }
        }),
        exact: false,
    }
}

/// One timed contender: runs one pass (a build or a trace) and drops the result.
type BuildFn<'a> = Box<dyn Fn() + 'a>;

type Options = rt_benches::RunOptions;

/// Times each closure `passes` times, interleaved, after one untimed warm-up; medians in ms.
fn time_interleaved(fs: &[BuildFn<'_>], passes: usize) -> Vec<f64> {
    for f in fs {
        f();
    }
    let mut times = vec![Vec::new(); fs.len()];
    for _ in 0..passes {
        for (i, f) in fs.iter().enumerate() {
            let t = Instant::now();
            f();
            times[i].push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    times.into_iter().map(median).collect()
}

/// The ray sets each scene is traced with: primary rays, their hits' shadow rays and diffuse
/// bounces from the view the scene fills (`compare`'s default, `--view filled`), incoherent
/// rays (no camera), and primary and shadow rays from the sparse view (`--view sparse`), where
/// most rays of a compact mesh miss its box and leave after one test. The ratio tables judge
/// rt-bvh on the first four.
const SETS: [(&str, RayKind, View); 6] = [
    ("primary", RayKind::Primary, View::Filled),
    ("incoherent", RayKind::Incoherent, View::Filled),
    ("shadow", RayKind::Shadow, View::Filled),
    ("diffuse", RayKind::Diffuse, View::Filled),
    ("sparse primary", RayKind::Primary, View::Sparse),
    ("sparse shadow", RayKind::Shadow, View::Sparse),
];

/// Results of one scene and ray set.
struct TraceResult {
    scene: &'static str,
    /// The ray set's name in [`SETS`].
    set: &'static str,
    rays: usize,
    /// Share of the rays that hit (closest hit) or are blocked (any hit), by rt-bvh's answers.
    hit_share: f64,
    /// Mrays/s per tracer, in tracer order.
    mrays: Vec<f64>,
    /// Rays on which each tracer's answer differs from rt-bvh's default preset.
    differs: Vec<usize>,
}

struct BuildResult {
    scene: &'static str,
    triangles: usize,
    /// (contender, threads label, median ms)
    rows: Vec<(String, String, f64)>,
}

fn agree(any: bool, a: Option<Hit>, b: Option<Hit>) -> bool {
    if any {
        a.is_some() == b.is_some()
    } else {
        Hit::agree(a, b)
    }
}

fn threads_all() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Times every build contender on one thread and on all threads: `passes` interleaved blocks of
/// builds each, after a warm-up pass; medians in ms. rt-bvh builds on the calling thread (one
/// thread: `parallel: false`; all threads: rayon's global pool, one worker per core).
///
/// Embree runs on TBB, whose thread limit is process-wide: while a 1-thread device exists, every
/// device is limited to one thread. So each pass makes one device for its thread count and
/// drops it before the next thread count's device is made.
fn bench_builds(scene: &BenchScene, passes: usize) -> BuildResult {
    let tris = &scene.triangles;
    let counts = [1, threads_all()];
    let presets = Bvh::<Triangle>::presets();
    let mut names: Vec<(String, String)> = Vec::new();
    let mut times: Vec<Vec<f64>> = Vec::new();
    let mut record = |name: String, threads: usize, pass: usize, ms: f64| {
        let label = if threads == 1 {
            "1".to_string()
        } else {
            "all".to_string()
        };
        let key = (name, label);
        let i = names.iter().position(|k| *k == key).unwrap_or_else(|| {
            names.push(key);
            times.push(Vec::new());
            names.len() - 1
        });
        if pass > 0 {
            times[i].push(ms);
        }
    };
    // Builds are timed in blocks. Before each block every core works for 50 ms (a busy loop on
    // rayon's threads) and then rests 20 ms, so the block starts with all cores up to speed and
    // no pool's workers still spinning; the contender then builds BLOCK + 1 times back to back at
    // one thread count, the first build untimed, and the fastest of the others counts. Blocks of
    // all contenders and thread counts are interleaved, pass after pass; each contender's median
    // over the passes is reported.
    //
    // PERF: this machine kind is a VM whose second core, once it has idled for some tens of
    // milliseconds, comes back slowly. Without the busy loop, rt-bvh's 2-thread sphereflake
    // build measured 1.16-1.49x its 1-thread time when nothing else ran between its blocks, and
    // 1.68-1.74x with Embree's builds (which use both cores) interleaved; standalone, back to
    // back, 1.78x. Single builds after a pause lost even more, for Embree too.
    const BLOCK: usize = 3;
    let warm_cores = || {
        let until = Instant::now() + std::time::Duration::from_millis(50);
        rayon::broadcast(|_| {
            while Instant::now() < until {
                std::hint::spin_loop();
            }
        });
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let block = |f: &mut dyn FnMut()| -> f64 {
        warm_cores();
        f();
        (0..BLOCK)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64() * 1e3
            })
            .fold(f64::INFINITY, f64::min)
    };
    for pass in 0..=passes {
        for threads in &counts {
            // As a user builds: on the calling thread, with rayon's global pool for the parallel
            // build, and `parallel: false` for one thread (the same tree, as tests check).
            for (preset, params) in &presets {
                let params = BvhParams {
                    parallel: params.parallel && *threads > 1,
                    ..params.clone()
                };
                let ms = block(&mut || drop(Bvh::build(tris, &params)));
                record(format!("rt-bvh {preset}"), *threads, pass, ms);
            }
            #[cfg(feature = "embree")]
            {
                use rt_benches::embree::{EmbreeScene, Quality};
                let device = EmbreeScene::device((*threads == 1).then_some(1)).expect("a device");
                for quality in Quality::ALL {
                    let ms = block(&mut || {
                        drop(EmbreeScene::build(&device, tris, quality).expect("Embree build"));
                    });
                    record(format!("embree {}", quality.name()), *threads, pass, ms);
                }
            }
        }
    }
    // Rows in pairs: each contender's 1-thread time, then its all-threads time.
    let mut rows: Vec<(String, String, f64)> = names
        .into_iter()
        .zip(times)
        .map(|((n, l), t)| (n, l, median(t)))
        .collect();
    let mut order: Vec<String> = Vec::new();
    for (n, _, _) in &rows {
        if !order.contains(n) {
            order.push(n.clone());
        }
    }
    rows.sort_by_key(|(n, l, _)| (order.iter().position(|o| o == n), l != "1"));
    BuildResult {
        scene: scene.name,
        triangles: tris.len(),
        rows,
    }
}

fn tracers(scene: &BenchScene) -> Vec<Tracer> {
    let mut out: Vec<Tracer> = Bvh::<Triangle>::presets()
        .into_iter()
        .map(|(preset, params)| {
            accel_tracer(
                format!("rt-bvh {preset}"),
                Bvh::build(&scene.triangles, &params),
                true,
            )
        })
        .collect();
    // The wide tree over Möller–Trumbore triangles: its own pack kernel (edges stored), not
    // watertight, so a few edge rays may be answered differently.
    let mt: Vec<MtTriangle> = scene.triangles.iter().copied().map(MtTriangle).collect();
    out.insert(
        1,
        accel_tracer(
            "rt-bvh wide-mt".into(),
            Bvh::build(&mt, &BvhParams::wide()),
            false,
        ),
    );
    #[cfg(feature = "embree")]
    {
        use rt_benches::embree::{EmbreeScene, Quality};
        let device = EmbreeScene::device(Some(1)).expect("an Embree device");
        for quality in Quality::ALL {
            let s = EmbreeScene::build(&device, &scene.triangles, quality).expect("Embree build");
            out.push(embree_tracer(&format!("embree {}", quality.name()), s));
        }
    }
    out
}

fn bench_traces(scene: &BenchScene, tracers: &[Tracer], o: &Options, out: &mut Vec<TraceResult>) {
    for (set, kind, view) in SETS {
        let rays = scene.rays(kind, view, (o.width, o.height), |primary| {
            primary
                .iter()
                .map(|r| (tracers[0].answer)(r, false))
                .collect()
        });
        let any = kind.is_any_hit();
        // The checks: every rt-bvh preset answers exactly like the default; other peers' differing
        // rays are counted.
        let reference: Vec<Option<Hit>> =
            rays.iter().map(|r| (tracers[0].answer)(r, any)).collect();
        let hit_share =
            reference.iter().filter(|h| h.is_some()).count() as f64 / rays.len().max(1) as f64;
        let differs: Vec<usize> = tracers
            .iter()
            .map(|t| {
                rays.iter()
                    .zip(&reference)
                    .filter(|(r, e)| !agree(any, **e, (t.answer)(r, any)))
                    .count()
            })
            .collect();
        for (t, &d) in tracers.iter().zip(&differs) {
            assert!(
                !t.exact || d == 0,
                "{} disagrees with {} on {d} {set} rays of {}",
                t.name,
                tracers[0].name,
                scene.name
            );
        }
        let fs: Vec<BuildFn<'_>> = tracers
            .iter()
            .map(|t| {
                let rays = &rays;
                Box::new(move || {
                    std::hint::black_box((t.pass)(rays, any));
                }) as BuildFn<'_>
            })
            .collect();
        let ms = time_interleaved(&fs, o.passes);
        out.push(TraceResult {
            scene: scene.name,
            set,
            rays: rays.len(),
            hit_share,
            mrays: ms.iter().map(|ms| rays.len() as f64 / ms / 1e3).collect(),
            differs,
        });
    }
}

/// Bundles against packets on one scene, view and ray kind: Mrays/s of rt-bvh's wide tree with
/// single rays and with bundles, and (with the feature `embree`) of Embree medium with single
/// rays and with 16-ray packets.
struct BundleResult {
    scene: &'static str,
    view: &'static str,
    kind: &'static str,
    rays: usize,
    hit_share: f64,
    /// (contender, Mrays/s)
    mrays: Vec<(&'static str, f64)>,
}

/// The views of the bundle comparison: the view the scene fills (`compare`'s default), the
/// sparse view at half the distance ("close", where the mesh fills more of the image), and the
/// sparse view itself.
fn views(scene: &BenchScene, o: &Options) -> [(&'static str, rt_scene::Camera); 3] {
    let sparse = scene.camera(View::Sparse, o.width, o.height);
    let mut close = sparse;
    close.eye = close.target + 0.5 * (close.eye - close.target);
    [
        ("filled", scene.camera(View::Filled, o.width, o.height)),
        ("close", close),
        ("sparse", sparse),
    ]
}

/// rt-bvh's bundles against its single rays and against Embree's packets, on primary rays in
/// 8×8 pixel tiles and on the shadow rays of their hits in the same order, and (on the filled
/// view) on primary rays in image order, a row of pixels after another, and their shadow rays
/// in that order. Every bundle answer
/// must equal the single answer bit for bit (the run panics otherwise); each of Embree's
/// coherent paths must give its single rays' primitive (or any-hit answer) on all but 0.1% of
/// the rays (the run panics otherwise: a few edge rays may round differently in its packet
/// kernels).
///
/// Runs [`bench_bundles_here`] on a thread of its own that is the only thread of its rayon
/// pool, so that `intersect_image` runs on the thread that times it, as every contender here
/// does.
// PERF: through a one-thread pool's `install`, each call moved to the pool's thread, and a third
// of the `image` figures came out 0.5-0.7 of the same rays' in the next run (Intel Emerald
// Rapids, `--scenes peers`, Mrays/s, `install` -> own thread: the teapot in a stadium's primary
// rays in image order 27.2 -> 50.0, the teapot's shadow rays in image order 20.2 -> 28.9).
fn bench_bundles(scene: &BenchScene, o: &Options, out: &mut Vec<BundleResult>) {
    std::thread::scope(|s| {
        s.spawn(|| {
            let _pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .use_current_thread()
                .build()
                .expect("a one-thread pool on this thread");
            bench_bundles_here(scene, o, out);
        })
        .join()
        .expect("the bundles' thread");
    });
}

fn bench_bundles_here(scene: &BenchScene, o: &Options, out: &mut Vec<BundleResult>) {
    let bvh = Bvh::build(&scene.triangles, &BvhParams::wide());
    #[cfg(feature = "embree")]
    let (_device, embree) = {
        use rt_benches::embree::{EmbreeScene, Quality};
        let device = EmbreeScene::device(Some(1)).expect("an Embree device");
        let e = EmbreeScene::build(&device, &scene.triangles, Quality::Medium).expect("Embree");
        (device, e)
    };
    let light = rt_scene::raygen::default_light(&scene.bounds());
    // Primary rays and the shadow rays of their hits, in the primary rays' order, each set with
    // its rays' pixels.
    let with_shadows = |primary: Vec<Ray>, pixels: Vec<u32>| {
        let hits: Vec<Option<Hit>> = primary.iter().map(|r| bvh.intersect(r)).collect();
        let shadow = rt_scene::raygen::shadow_rays(&primary, &hits, &scene.triangles, light);
        // One shadow ray per hit, in the hits' order.
        let lit: Vec<u32> = pixels
            .iter()
            .zip(&hits)
            .filter(|(_, h)| h.is_some())
            .map(|(&p, _)| p)
            .collect();
        assert_eq!(lit.len(), shadow.len(), "one shadow ray per hit");
        ((primary, pixels), (shadow, lit))
    };
    for (view, camera) in views(scene, o) {
        let (tiled, pixels) = camera.tiled_rays(o.width, o.height, (8, 8));
        let (primary, shadow) = with_shadows(tiled, pixels);
        let mut sets = vec![("primary", primary), ("shadow", shadow)];
        // As many renderers make them: a row of pixels after another, and the shadow rays of
        // their hits in the same order, handed over as they come.
        if view == "filled" {
            let rows = camera.primary_rays(o.width, o.height);
            let pixels = (0..rows.len() as u32).collect();
            let (primary, shadow) = with_shadows(rows, pixels);
            sets.extend([("primary, rows", primary), ("shadow, rows", shadow)]);
        }
        for (kind, (rays, pixels)) in &sets {
            let kind = *kind;
            // Rays in tile order are not in image order: `intersect_image` traces them as
            // they come, which times its check.
            let image = rt_core::bundle::Image::pixels(o.width, pixels);
            let any = kind.starts_with("shadow");
            let mut single = vec![None; rays.len()];
            let mut bundled = vec![None; rays.len()];
            let (mut blocked, mut blocked_b) = (vec![false; rays.len()], vec![false; rays.len()]);
            let check = |a: &[Option<Hit>], b: &[Option<Hit>]| {
                let bits = |h: &Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits()));
                a.iter().zip(b).all(|(a, b)| bits(a) == bits(b))
            };
            if any {
                blocked
                    .iter_mut()
                    .zip(rays.iter())
                    .for_each(|(o, r)| *o = bvh.occluded(r));
                bvh.occluded_bundle(rays, &mut blocked_b);
                assert_eq!(blocked, blocked_b, "bundles differ: {} {view}", scene.name);
                rt_core::bundle::occluded_image(&bvh, rays, image, &mut blocked_b);
                assert_eq!(
                    blocked, blocked_b,
                    "occluded_image differs: {} {view}",
                    scene.name
                );
            } else {
                single
                    .iter_mut()
                    .zip(rays.iter())
                    .for_each(|(o, r)| *o = bvh.intersect(r));
                bvh.intersect_bundle(rays, &mut bundled);
                assert!(
                    check(&single, &bundled),
                    "bundles differ: {} {view}",
                    scene.name
                );
                rt_core::bundle::intersect_image(&bvh, rays, image, &mut bundled);
                assert!(
                    check(&single, &bundled),
                    "intersect_image differs: {} {view}",
                    scene.name
                );
            }
            let hit_share = if any {
                blocked.iter().filter(|&&b| b).count()
            } else {
                single.iter().filter(|h| h.is_some()).count()
            } as f64
                / rays.len().max(1) as f64;
            // The answer buffers of the bundle and packet contenders, made before the timing:
            // the single-ray contenders only count hits, so an allocation in the timed call
            // would weigh on one side alone.
            let bundle_out = (
                std::cell::RefCell::new(vec![None; rays.len()]),
                std::cell::RefCell::new(vec![false; rays.len()]),
            );
            #[cfg(feature = "embree")]
            let packet_out = (
                std::cell::RefCell::new(vec![None; rays.len()]),
                std::cell::RefCell::new(vec![false; rays.len()]),
            );
            // Embree's two contenders join these with the feature `embree`.
            #[cfg_attr(not(feature = "embree"), allow(unused_mut))]
            let mut names: Vec<&'static str> =
                vec!["rt-bvh wide", "rt-bvh wide bundles", "rt-bvh wide image"];
            #[cfg_attr(not(feature = "embree"), allow(unused_mut))]
            let mut fs: Vec<BuildFn<'_>> = vec![
                Box::new(|| {
                    let n = if any {
                        rays.iter().filter(|r| bvh.occluded(r)).count()
                    } else {
                        rays.iter().filter(|r| bvh.intersect(r).is_some()).count()
                    };
                    std::hint::black_box(n);
                }),
                Box::new(|| {
                    let (mut hit, mut blocked) =
                        (bundle_out.0.borrow_mut(), bundle_out.1.borrow_mut());
                    if any {
                        bvh.occluded_bundle(rays, &mut blocked);
                    } else {
                        bvh.intersect_bundle(rays, &mut hit);
                    }
                    std::hint::black_box((&*hit, &*blocked));
                }),
                Box::new(|| {
                    let (mut hit, mut blocked) =
                        (bundle_out.0.borrow_mut(), bundle_out.1.borrow_mut());
                    let (hit, blocked): (&mut [Option<Hit>], &mut [bool]) =
                        (&mut hit, &mut blocked);
                    if any {
                        rt_core::bundle::occluded_image(&bvh, rays, image, blocked);
                    } else {
                        rt_core::bundle::intersect_image(&bvh, rays, image, hit);
                    }
                    std::hint::black_box((&*hit, &*blocked));
                }),
            ];
            #[cfg(feature = "embree")]
            {
                let embree = &embree;
                names.extend([
                    "embree medium",
                    "embree medium packets16",
                    "embree medium packets8",
                    "embree medium stream64",
                ]);
                fs.push(Box::new(move || {
                    let n = if any {
                        rays.iter().filter(|r| embree.occluded(r)).count()
                    } else {
                        rays.iter()
                            .filter(|r| embree.intersect(r).is_some())
                            .count()
                    };
                    std::hint::black_box(n);
                }));
                use rt_benches::embree::EmbreeScene;
                let packet_out = &packet_out;
                type Closest = fn(&EmbreeScene, &[Ray], &mut [Option<Hit>]);
                type Any = fn(&EmbreeScene, &[Ray], &mut [bool]);
                let paths: [(Closest, Any); 3] = [
                    (
                        EmbreeScene::intersect_packets,
                        EmbreeScene::occluded_packets,
                    ),
                    (
                        EmbreeScene::intersect_packets8,
                        EmbreeScene::occluded_packets8,
                    ),
                    (EmbreeScene::intersect_stream, EmbreeScene::occluded_stream),
                ];
                // Each coherent path answers as Embree's single rays do, but for the few edge
                // rays its packet kernels may round differently: a check of the wrappers, where
                // a lane filled or read wrongly would differ on many rays.
                for (name, (closest, any_hit)) in
                    ["packets16", "packets8", "stream64"].into_iter().zip(paths)
                {
                    let differ = if any {
                        let mut b = vec![false; rays.len()];
                        any_hit(embree, rays, &mut b);
                        rays.iter()
                            .zip(&b)
                            .filter(|&(r, &x)| embree.occluded(r) != x)
                            .count()
                    } else {
                        let mut h = vec![None; rays.len()];
                        closest(embree, rays, &mut h);
                        rays.iter()
                            .zip(&h)
                            .filter(|&(r, x)| {
                                embree.intersect(r).map(|h| h.prim) != x.map(|h| h.prim)
                            })
                            .count()
                    };
                    assert!(
                        differ * 1000 <= rays.len(),
                        "Embree's {name} differ from its single rays on {differ} of {} rays: {} {view}",
                        rays.len(),
                        scene.name
                    );
                }
                for (closest, any_hit) in paths {
                    fs.push(Box::new(move || {
                        let (mut hit, mut blocked) =
                            (packet_out.0.borrow_mut(), packet_out.1.borrow_mut());
                        if any {
                            any_hit(embree, rays, &mut blocked);
                        } else {
                            closest(embree, rays, &mut hit);
                        }
                        std::hint::black_box((&*hit, &*blocked));
                    }));
                }
            }
            let ms = time_interleaved(&fs, o.passes);
            out.push(BundleResult {
                scene: scene.name,
                view,
                kind,
                rays: rays.len(),
                hit_share,
                mrays: names
                    .into_iter()
                    .zip(ms)
                    .map(|(n, ms)| (n, rays.len() as f64 / ms / 1e3))
                    .collect(),
            });
        }
    }
}

/// The bundle table: every contender's Mrays/s, and the ratios the bundles are judged by.
fn bundle_report(results: &[BundleResult]) -> String {
    let mut s = String::new();
    let Some(first) = results.first() else {
        return s;
    };
    let names: Vec<&str> = first.mrays.iter().map(|(n, _)| *n).collect();
    let _ = writeln!(
        s,
        "\nBundles: primary rays in 8×8 pixel tiles and their shadow rays in the same order \
         (`primary`, `shadow`), and on the filled view primary rays in image order, a row of \
         pixels after another, and their shadow rays in that order (`primary, rows`, `shadow, \
         rows`); single-threaded. rt-bvh's bundles take 64 consecutive rays; `rt-bvh wide \
         image` is `rt_core::bundle::intersect_image` (`occluded_image`) given each ray's pixel, \
         which bundles rays in image order tile by tile (rays in tile order are not in image \
         order: it traces them as they come). Embree's coherent \
         paths, each with the coherent flag, on the same rays in the same order: packets of 16 \
         consecutive rays (8×2 pixels of a tile), packets of 8, and streams of 64 \
         (`rtcIntersect1M` / `rtcOccluded1M`, which Embree gathers into packets itself). \
         Mrays/s; bundles ÷ single rays, and bundles and image ÷ the fastest of Embree's coherent \
         paths on that row\n"
    );
    let _ = writeln!(
        s,
        "| scene | view | rays | count | hit | {} | bundles ÷ single | bundles ÷ Embree's best | image ÷ Embree's best |",
        names.join(" | ")
    );
    let _ = writeln!(
        s,
        "| --- | --- | --- | ---: | ---: |{}",
        " ---: |".repeat(names.len() + 3)
    );
    let get = |r: &BundleResult, name: &str| r.mrays.iter().find(|(n, _)| *n == name).map(|m| m.1);
    // The bundles against the fastest of Embree's coherent paths on this row.
    let best_embree = |r: &BundleResult, ours: &str| {
        let best = r
            .mrays
            .iter()
            .filter(|(n, _)| n.starts_with("embree medium "))
            .map(|m| m.1)
            .reduce(f64::max);
        match (get(r, ours), best) {
            (Some(a), Some(b)) => format!("{:.2}", a / b),
            _ => "-".into(),
        }
    };
    for r in results {
        let cells: Vec<String> = r.mrays.iter().map(|(_, m)| format!("{m:.2}")).collect();
        let over = |a: &str, b: &str| match (get(r, a), get(r, b)) {
            (Some(a), Some(b)) => format!("{:.2}", a / b),
            _ => "-".into(),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1}% | {} | {} | {} | {} |",
            r.scene,
            r.view,
            r.kind,
            r.rays,
            100.0 * r.hit_share,
            cells.join(" | "),
            over("rt-bvh wide bundles", "rt-bvh wide"),
            best_embree(r, "rt-bvh wide bundles"),
            best_embree(r, "rt-bvh wide image"),
        );
    }
    s
}

fn report(names: &[String], traces: &[TraceResult], builds: &[BuildResult], o: &Options) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n{} ({} threads); {}×{} rays per set; traces single-threaded; medians of {} interleaved passes",
        rt_shootout::measure::cpu_model(),
        threads_all(),
        o.width,
        o.height,
        o.passes
    );
    let _ = writeln!(
        s,
        "\nMrays/s (differing answers from `{}` in brackets, where any); hit: the share of the \
         rays that hit (primary, incoherent) or are blocked (shadow)\n",
        names[0]
    );
    let _ = writeln!(s, "| scene | rays | count | hit | {} |", names.join(" | "));
    let _ = writeln!(
        s,
        "| --- | --- | ---: | ---: |{}",
        " ---: |".repeat(names.len())
    );
    for r in traces {
        let cells: Vec<String> = r
            .mrays
            .iter()
            .zip(&r.differs)
            .map(|(m, &d)| {
                if d == 0 {
                    format!("{m:.2}")
                } else {
                    format!("{m:.2} [{d}]")
                }
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1}% | {} |",
            r.scene,
            r.set,
            r.rays,
            100.0 * r.hit_share,
            cells.join(" | ")
        );
    }
    let _ = writeln!(s, "\nBuild ms (1 thread / {} threads)\n", threads_all());
    if let Some(b) = builds.first() {
        let mut heads: Vec<String> = Vec::new();
        for (n, _, _) in b.rows.iter().step_by(2) {
            heads.push(n.clone());
        }
        let _ = writeln!(s, "| scene | triangles | {} |", heads.join(" | "));
        let _ = writeln!(s, "| --- | ---: |{}", " ---: |".repeat(heads.len()));
        for b in builds {
            let cells: Vec<String> = b
                .rows
                .chunks(2)
                .map(|c| format!("{:.1} / {:.1} ({:.2}×)", c[0].2, c[1].2, c[0].2 / c[1].2))
                .collect();
            let _ = writeln!(
                s,
                "| {} | {} | {} |",
                b.scene,
                b.triangles,
                cells.join(" | ")
            );
        }
    }
    // The ratio table: rt-bvh's presets ÷ Embree medium (the default), if Embree ran.
    let Some(base) = names.iter().position(|n| n == "embree medium") else {
        let _ = writeln!(
            s,
            "\nEmbree not linked: build with `--features embree` (needs libembree-dev) for the ratio table."
        );
        return s;
    };
    let _ = writeln!(
        s,
        "\nRatios, speed ÷ Embree medium's (its default build quality), single-threaded\n"
    );
    let sets = SETS.map(|(set, _, _)| set);
    let _ = writeln!(
        s,
        "| {} ÷ Embree | {} | build, 1 thread (Embree's time ÷ ours) |",
        names[0],
        sets.join(" | ")
    );
    let _ = writeln!(s, "| --- |{}", " ---: |".repeat(sets.len() + 1));
    let ratio = |r: &TraceResult, i: usize| r.mrays[i] / r.mrays[base];
    let scenes: Vec<&'static str> = builds.iter().map(|b| b.scene).collect();
    let build_ratio = |b: &BuildResult| {
        let ours = b.rows[0].2;
        let embree = b
            .rows
            .iter()
            .find(|(n, l, _)| n == "embree medium" && l == "1")
            .map_or(f64::NAN, |r| r.2);
        embree / ours
    };
    for (si, scene) in scenes.iter().enumerate() {
        let cells: Vec<String> = sets
            .iter()
            .map(|set| {
                traces
                    .iter()
                    .find(|r| r.scene == *scene && r.set == *set)
                    .map_or("-".into(), |r| format!("{:.2}", ratio(r, 0)))
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} |",
            scene,
            cells.join(" | "),
            build_ratio(&builds[si])
        );
    }
    let gm = |i: usize, set: &str| {
        let v: Vec<f64> = traces
            .iter()
            .filter(|r| r.set == set)
            .map(|r| ratio(r, i))
            .collect();
        geomean(&v)
    };
    let build_gm = geomean(&builds.iter().map(build_ratio).collect::<Vec<_>>());
    let _ = writeln!(
        s,
        "| **geometric mean** | {} | {:.2} |",
        sets.map(|set| format!("**{:.2}**", gm(0, set))).join(" | "),
        build_gm
    );
    // The default preset against every Embree configuration: the geometric mean over the
    // scenes, with the lowest scene beside it.
    let _ = writeln!(
        s,
        "\n{} ÷ each Embree configuration: geometric mean over the scenes (lowest scene)\n",
        names[0]
    );
    let _ = writeln!(s, "| {} ÷ | {} |", names[0], sets.join(" | "));
    let _ = writeln!(s, "| --- |{}", " ---: |".repeat(sets.len()));
    for (e, embree) in names.iter().enumerate() {
        if !embree.starts_with("embree ") {
            continue;
        }
        let cells = sets.map(|set| {
            let v: Vec<f64> = traces
                .iter()
                .filter(|r| r.set == set)
                .map(|r| r.mrays[0] / r.mrays[e])
                .collect();
            let low = v.iter().copied().fold(f64::INFINITY, f64::min);
            format!("{:.2} ({low:.2})", geomean(&v))
        });
        let _ = writeln!(s, "| {embree} | {} |", cells.join(" | "));
    }
    let _ = writeln!(
        s,
        "\nGeometric means over the scenes, each contender ÷ Embree medium\n"
    );
    let _ = writeln!(s, "| contender | {} |", sets.join(" | "));
    let _ = writeln!(s, "| --- |{}", " ---: |".repeat(sets.len()));
    for (i, n) in names.iter().enumerate() {
        let _ = writeln!(
            s,
            "| {} | {} |",
            n,
            sets.map(|set| format!("{:.2}", gm(i, set))).join(" | ")
        );
    }
    s
}

fn to_json(
    names: &[String],
    traces: &[TraceResult],
    builds: &[BuildResult],
    o: &Options,
) -> String {
    let traces: Vec<serde_json::Value> = traces
        .iter()
        .map(|r| {
            serde_json::json!({
                "scene": r.scene, "rays": r.set, "count": r.rays, "hit_share": r.hit_share,
                "mrays_per_s": r.mrays, "differing": r.differs,
            })
        })
        .collect();
    let builds: Vec<serde_json::Value> = builds
        .iter()
        .map(|b| {
            let rows: Vec<serde_json::Value> = b
                .rows
                .iter()
                .map(|(n, l, ms)| serde_json::json!({"contender": n, "threads": l, "ms": ms}))
                .collect();
            serde_json::json!({"scene": b.scene, "triangles": b.triangles, "rows": rows})
        })
        .collect();
    serde_json::to_string_pretty(&serde_json::json!({
        "cpu": rt_shootout::measure::cpu_model(), "threads": threads_all(), "width": o.width, "height": o.height,
        "passes": o.passes, "contenders": names, "traces": traces, "builds": builds,
    }))
    .expect("JSON")
}

fn main() {
    let o = Options::from_args();
    let scenes: Vec<BenchScene> = o.scenes();
    let mut traces = Vec::new();
    let mut builds = Vec::new();
    let mut bundles = Vec::new();
    let mut names = Vec::new();
    for scene in &scenes {
        eprintln!("{}: {} triangles", scene.name, scene.triangles.len());
        builds.push(bench_builds(scene, o.passes));
        let tracers = tracers(scene);
        names = tracers.iter().map(|t| t.name.clone()).collect();
        bench_traces(scene, &tracers, &o, &mut traces);
        bench_bundles(scene, &o, &mut bundles);
    }
    print!("{}", report(&names, &traces, &builds, &o));
    print!("{}", bundle_report(&bundles));
    if let Some(path) = &o.json {
        std::fs::write(path, to_json(&names, &traces, &builds, &o)).expect("write the JSON file");
        eprintln!("wrote {path}");
    }
}

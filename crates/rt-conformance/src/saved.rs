//! Saved structures: a structure loaded from its file answers every query bit for bit as the
//! one that was built, and a damaged or hostile file gives an error or a structure whose
//! queries return, never a panic or a walk that does not end.

use crate::{STALL_LIMIT, boxes::scene_boxes, scene_points, watched};
use rt_core::{Accel, Ray, Rng, Triangle};
use rt_persist::{Persist, SavedPrimitive, file_checksum};

/// Damaged copies of each scene's file that [`check_saved_case`] loads.
pub const DAMAGES: usize = 100;

/// The most truncations of one file [`check_saved_case`] tries (every length of a small file,
/// an even spread of a large one's).
pub const TRUNCATIONS: usize = 256;

/// Saves `built`, loads it back, and compares every query of `rays` and the points and boxes
/// of `prims`' scene bit for bit; then checks that the saved bytes of the loaded structure are
/// the same file.
///
/// # Errors
/// The first difference.
pub fn compare_saved<A: Accel + Persist>(
    built: &A,
    prims: &[A::Prim],
    rays: &[Ray],
) -> Result<(), String> {
    let bytes = built.save();
    let loaded = A::load(&bytes).map_err(|e| format!("its own file does not load: {e}"))?;
    if loaded.save() != bytes {
        return Err("saving the loaded structure writes another file".into());
    }
    let (a, b) = (built.build_stats(), loaded.build_stats());
    if format!("{a:?}") != format!("{b:?}") {
        return Err(format!("build_stats() {b:?} after loading, {a:?} built"));
    }
    same_answers(built, &loaded, prims, rays)
}

/// Bits of a hit, so that equal means bit for bit.
fn bits(h: Option<rt_core::Hit>) -> Option<[u32; 4]> {
    h.map(|h| [h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()])
}

/// Every query of the kit, asked of both structures: the answers must be bit for bit the same.
/// (Floats are compared through `{:?}`, which writes the shortest text that reads back as the
/// same value, for the answers that are not hits.)
fn same_answers<A: Accel>(
    built: &A,
    loaded: &A,
    prims: &[A::Prim],
    rays: &[Ray],
) -> Result<(), String> {
    for ray in rays {
        let differ = |what: &str| Err(format!("{what} differs after loading for {ray:?}"));
        if bits(built.intersect(ray)) != bits(loaded.intersect(ray)) {
            return differ("the closest hit");
        }
        if built.occluded(ray) != loaded.occluded(ray) {
            return differ("the any-hit answer");
        }
        let all =
            |s: &A| -> Vec<_> { s.all_hits(ray).into_iter().map(|h| bits(Some(h))).collect() };
        if all(built) != all(loaded) {
            return differ("the list of all hits");
        }
    }
    let mut out = (vec![None; rays.len()], vec![None; rays.len()]);
    built.intersect_bundle(rays, &mut out.0);
    loaded.intersect_bundle(rays, &mut out.1);
    if out
        .0
        .iter()
        .map(|&h| bits(h))
        .ne(out.1.iter().map(|&h| bits(h)))
    {
        return Err("a bundle's closest hits differ after loading".into());
    }
    for (p, max) in scene_points(prims, rays) {
        let (a, b) = (built.closest_point(p, max), loaded.closest_point(p, max));
        if format!("{a:?}") != format!("{b:?}") {
            return Err(format!(
                "the closest point to {p} differs after loading: {b:?}, built {a:?}"
            ));
        }
    }
    for bounds in scene_boxes(prims, prims.len() as u64) {
        if built.overlapping(&bounds) != loaded.overlapping(&bounds) {
            return Err(format!(
                "the primitives overlapping {bounds:?} differ after loading"
            ));
        }
    }
    Ok(())
}

/// Every kind of query once per ray, for a structure loaded from a damaged file: only that
/// each returns matters.
fn ask_everything<A: Accel>(accel: &A, rays: &[Ray]) {
    for ray in rays {
        let _ = (
            accel.intersect(ray),
            accel.occluded(ray),
            accel.all_hits(ray),
        );
        let _ = accel.closest_point(ray.origin, f32::INFINITY);
        let _ = accel.overlapping(&rt_core::Aabb::new(ray.origin - 1.0, ray.origin + 1.0));
    }
    let mut out = vec![None; rays.len()];
    accel.intersect_bundle(rays, &mut out);
    let _ = accel.overlapping(&accel.bounds());
}

/// Loads damaged copies of `bytes`: every truncation (at most [`TRUNCATIONS`]), which must be
/// refused, and [`DAMAGES`] copies with one to four bytes after the header changed and the
/// checksum written again, as a hostile file would have it. Each must load to an error or to a
/// structure that answers every query of `rays` (without a panic; a walk that does not end is
/// the caller's watchdog's to catch).
///
/// # Errors
/// The first damaged file that loads wrongly.
pub fn check_damaged<A: Accel + Persist>(
    bytes: &[u8],
    rays: &[Ray],
    seed: u64,
) -> Result<(), String> {
    let stride = bytes.len().div_ceil(TRUNCATIONS).max(1);
    for len in (0..bytes.len()).step_by(stride) {
        if A::load(&bytes[..len]).is_ok() {
            return Err(format!(
                "the file cut to {len} of {} bytes loads",
                bytes.len()
            ));
        }
    }
    let mut rng = Rng::new(seed);
    for _ in 0..DAMAGES {
        let mut file = bytes.to_vec();
        let mut changed = Vec::new();
        for _ in 0..=rng.below(4) {
            let at = 96 + rng.below((file.len() - 96) as u32) as usize;
            let value = rng.below(256) as u8;
            file[at] = value;
            changed.push((at, value));
        }
        let sum = file_checksum(&file);
        file[88..96].copy_from_slice(&sum.to_le_bytes());
        let loaded = std::panic::catch_unwind(|| A::load(&file))
            .map_err(|_| format!("loading panics with bytes {changed:?} (offset, value) set"))?;
        if let Ok(loaded) = loaded {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                ask_everything(&loaded, rays)
            }))
            .map_err(|_| {
                format!("a query panics on the file with bytes {changed:?} (offset, value) set")
            })?;
        }
    }
    Ok(())
}

/// [`compare_saved`] and [`check_damaged`] for `A` with `params` over `prims`, under the kit's
/// watchdog.
///
/// # Errors
/// A description of the first failure.
pub fn check_saved_case<A: Accel + Persist + 'static>(
    params: &A::Params,
    prims: &[A::Prim],
    rays: &[Ray],
    seed: u64,
) -> Result<(), String>
where
    A::Prim: SavedPrimitive,
{
    let (params, prims, rays) = (params.clone(), prims.to_vec(), rays.to_vec());
    let scene = format!("\n  scene: {} primitives", prims.len());
    watched(A::NAME, STALL_LIMIT, &scene, move |_| {
        let built = A::build(&prims, &params);
        let context = |m: String| format!("{} with {params:?}, saved and loaded: {m}", A::NAME);
        compare_saved(&built, &prims, &rays).map_err(context)?;
        // Damaged files: fewer rays, since each loaded one runs every query.
        let some: Vec<Ray> = rays
            .iter()
            .step_by(rays.len().div_ceil(16).max(1))
            .copied()
            .collect();
        check_damaged::<A>(&built.save(), &some, seed).map_err(context)
    })
}

/// [`check_saved_case`] on every adversarial scene ([`SCENES`](crate::SCENES)) with every
/// preset of `A` ([`Accel::presets`]).
///
/// # Panics
/// At the first failure.
pub fn check_saved_scenes<A: Accel<Prim = Triangle> + Persist + 'static>() {
    for (preset, params) in A::presets() {
        for (k, name) in crate::SCENES.iter().enumerate() {
            let s = crate::scene(name);
            if let Err(e) = check_saved_case::<A>(&params, &s.triangles, &s.rays, k as u64) {
                panic!("saved `{preset}` on scene `{name}`: {e}");
            }
        }
    }
}

//! The bodies of the fuzz targets in `fuzz/`, here so that the normal test suite runs them too:
//! over the seed corpora and over every input a fuzzer ever found failing
//! (`crates/rt-shootout/tests/fuzz_corpus.rs`).
//!
//! - [`load`]: bytes to a mesh or an error, for each loader. A loader may reject anything, but
//!   must not panic, and a mesh it returns must be sound (indices in range, finite positions).
//! - [`trace`]: bytes decoded ([`decode`]) into a small triangle soup and rays; every structure,
//!   in several configurations, is built, validated and queried. On the quarter lattice it must
//!   answer each ray exactly as brute force does (the conformance kit's rule), invalid rays
//!   included; with raw `f32` coordinates it must not panic or loop, and invalid rays must not
//!   hit.
//! - [`saved`]: bytes as a saved structure of each kind, with the checksum written again: an
//!   error or a structure that answers, and that saves and loads to the same answers.
//! - [`bundle`]: the same cases; every structure's bundle queries must answer each ray exactly
//!   as its single-ray queries do (the same bits), in every order and bundle size the kit uses
//!   ([`rt_conformance::compare_bundles`]), raw coordinates included: that promise has no
//!   conditioning caveat, since both answers come from the same structure.

use rt_bvh::{Bvh, BvhParams};
use rt_conformance::{compare_bundles, compare_rays};
use rt_core::glam::Vec3;
use rt_core::{Accel, BruteForce, Ray, Triangle};
use rt_grid::{Grid, GridParams};
use rt_hgrid::{HGrid, HGridParams};
use rt_kdtree::{KdParams, KdTree};
use rt_octree::{Octree, OctreeParams};
use rt_persist::Persist;
use rt_scene::{SceneFormat, load_mesh_bytes};

/// Loads `bytes` as `format`.
///
/// # Panics
/// If the loader returns a mesh with an index out of range, a non-finite position or no
/// triangle (the loader itself panicking is what the fuzzer looks for).
pub fn load(format: SceneFormat, bytes: &[u8]) {
    let Ok(mesh) = load_mesh_bytes("fuzz", format, bytes) else {
        return;
    };
    let n = mesh.positions().len();
    assert!(mesh.triangle_count() > 0, "a mesh without triangles");
    assert!(
        mesh.positions().iter().all(|p| p.is_finite()),
        "a non-finite position"
    );
    assert!(
        mesh.indices().iter().flatten().all(|&i| (i as usize) < n),
        "an index out of range"
    );
}

/// A decoded fuzz input: a triangle soup and rays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Case {
    /// Whether the coordinates are on the quarter lattice (else raw `f32` bits); see [`trace`].
    pub lattice: bool,
    /// The triangles (some may be degenerate or non-finite: structures skip invalid ones).
    pub tris: Vec<Triangle>,
    /// The rays (some may be invalid: structures must return at once).
    pub rays: Vec<Ray>,
}

/// The most triangles and rays one input decodes to: small scenes, so a fuzzer runs fast and a
/// failure is easy to read.
pub const MAX_TRIANGLES: usize = 24;
/// See [`MAX_TRIANGLES`].
pub const MAX_RAYS: usize = 32;

/// Raw coordinates smaller than this in magnitude (2⁻⁴⁰), zero aside, become zeros of the same
/// sign. At that scale the kd-tree's exact clipping underflows: its builder listed a triangle
/// in a cell 10⁻³⁸ wide that the triangle's bounding box misses, so `validate` failed
/// (`fuzz/regressions/trace/subnormal-cell-validation.bin`, `tiny-cell-validation.bin`; an
/// extra listing, harmless to answers, but whether a tiny scene can also lose a listing is not
/// known). Rays and scenes of ordinary scale never come near it.
pub const TINY: f32 = 1.0 / (1u64 << 40) as f32;

/// Decodes bytes into a [`Case`]. The first byte picks the number encoding: with its low bit
/// clear, every coordinate is a signed byte over 4 (a lattice from -32 to 31.75 in quarters, so
/// that shared vertices and edges, coplanar triangles and rays through edges are common);
/// with it set, coordinates are raw `f32` bits (NaN, infinities, huge values; magnitudes below
/// [`TINY`] become zeros).
/// The second byte gives the triangle count (1 to [`MAX_TRIANGLES`]); then come nine
/// coordinates per triangle and six per ray (origin, direction), until the bytes run out.
pub fn decode(bytes: &[u8]) -> Case {
    let (Some(&flags), Some(&count)) = (bytes.first(), bytes.get(1)) else {
        return Case::default();
    };
    let raw = flags & 1 == 1;
    let mut rest = &bytes[2..];
    let mut next = || -> Option<f32> {
        if raw {
            let (head, tail) = rest.split_first_chunk::<4>()?;
            rest = tail;
            let x = f32::from_le_bytes(*head);
            // Magnitudes below `TINY` become zeros: see there.
            Some(if x.abs() < TINY {
                0.0f32.copysign(x)
            } else {
                x
            })
        } else {
            let (&b, tail) = rest.split_first()?;
            rest = tail;
            Some(f32::from(b as i8) / 4.0)
        }
    };
    let mut vec3 = || Some(Vec3::new(next()?, next()?, next()?));
    let mut case = Case {
        lattice: !raw,
        ..Case::default()
    };
    for _ in 0..1 + usize::from(count) % MAX_TRIANGLES {
        let (Some(a), Some(b), Some(c)) = (vec3(), vec3(), vec3()) else {
            return case;
        };
        case.tris.push(Triangle::new(a, b, c));
    }
    while case.rays.len() < MAX_RAYS {
        let (Some(o), Some(d)) = (vec3(), vec3()) else {
            break;
        };
        case.rays.push(Ray::new(o, d));
    }
    case
}

/// The input that [`decode`] turns back into `tris` and `rays` (at most [`MAX_TRIANGLES`] and
/// [`MAX_RAYS`] of them, and without the rays' intervals), with raw `f32` coordinates, so that
/// any scene can seed the fuzzer exactly. Without triangles, the empty input.
pub fn encode(tris: &[Triangle], rays: &[Ray]) -> Vec<u8> {
    if tris.is_empty() {
        return Vec::new();
    }
    let tris = &tris[..tris.len().min(MAX_TRIANGLES)];
    let mut out = vec![1, (tris.len() - 1) as u8];
    let mut put = |v: Vec3| {
        for c in v.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    };
    for t in tris {
        put(t.v0);
        put(t.v1);
        put(t.v2);
    }
    for r in rays.iter().take(MAX_RAYS) {
        put(r.origin);
        put(r.dir());
    }
    out
}

/// [`encode`] on the quarter lattice, for a scene whose every coordinate is a multiple of 1/4
/// from -32 to 31.75 (`None` otherwise): the cases [`trace`] compares with brute force.
pub fn encode_lattice(tris: &[Triangle], rays: &[Ray]) -> Option<Vec<u8>> {
    if tris.is_empty() {
        return Some(Vec::new());
    }
    let tris = &tris[..tris.len().min(MAX_TRIANGLES)];
    let mut out = vec![0, (tris.len() - 1) as u8];
    let points = tris
        .iter()
        .flat_map(|t| [t.v0, t.v1, t.v2])
        .chain(rays.iter().take(MAX_RAYS).flat_map(|r| [r.origin, r.dir()]));
    for c in points.flat_map(|p| p.to_array()) {
        let q = c * 4.0;
        if q != q.round() || !(-128.0..=127.0).contains(&q) {
            return None;
        }
        out.push(q as i8 as u8);
    }
    Some(out)
}

/// Builds every structure on the decoded case and validates it; then, on a lattice case,
/// compares every answer with brute force ([`compare_rays`]), and on a raw case asks every query
/// and checks only that invalid rays answer at once with no hit.
///
/// Raw cases are not compared because exact agreement is not promised for ill-conditioned
/// geometry: a sliver triangle spanning 10¹⁸ seen by a ray at scale 1 gets a hit from brute
/// force's triangle test 150 units outside the triangle's bounding box (rounding at that
/// scale), which a BVH's box test rightly culls (`fuzz/regressions/trace/sliver-*`). Raw cases
/// still prove that no input makes a build or a query panic, loop or fail validation.
///
/// # Errors
/// The first structure that fails validation or disagrees, with the ray.
pub fn trace(bytes: &[u8]) -> Result<(), String> {
    let case = decode(bytes);
    if case.tris.is_empty() {
        return Ok(());
    }
    let brute = BruteForce::build(&case.tris, &());
    let check = |name: &str, result: Result<(), String>| result.map_err(|e| format!("{name}: {e}"));
    let ask = |name: &str, accel: &dyn Fn(&Ray) -> (Option<rt_core::Hit>, bool)| {
        for ray in &case.rays {
            let (hit, occluded) = accel(ray);
            if !ray.is_valid() && (hit.is_some() || occluded) {
                return Err(format!("{name}: an invalid ray hit: {}", ray.to_rust()));
            }
        }
        Ok(())
    };
    macro_rules! each {
        ($name:literal, $accel:expr) => {{
            let accel = $accel;
            check($name, accel.validate().map_err(|e| e.to_string()))?;
            if case.lattice {
                check($name, compare(&accel, &brute, &case.rays))?;
            } else {
                ask($name, &|r| (accel.intersect(r), accel.occluded(r)))?;
            }
        }};
    }
    each!("bvh", Bvh::build(&case.tris, &BvhParams::default()));
    each!("bvh-binary", Bvh::build(&case.tris, &BvhParams::sah()));
    each!("kdtree", KdTree::build(&case.tris, &KdParams::default()));
    each!("grid", Grid::build(&case.tris, &GridParams::default()));
    each!("hgrid", HGrid::build(&case.tris, &HGridParams::default()));
    each!(
        "octree",
        Octree::build(&case.tris, &OctreeParams::default())
    );
    Ok(())
}

/// The body of the `bundle` fuzz target: [`decode`]s the case, builds every structure and
/// checks that its bundle queries give its single-ray answers bit for bit
/// ([`compare_bundles`]).
///
/// # Errors
/// The first structure whose bundle answer differs, with the ray, the order and the bundle size.
pub fn bundle(bytes: &[u8]) -> Result<(), String> {
    let case = decode(bytes);
    if case.tris.is_empty() {
        return Ok(());
    }
    let rays = &case.rays;
    compare_bundles(&Bvh::build(&case.tris, &BvhParams::default()), rays, true)?;
    compare_bundles(&Bvh::build(&case.tris, &BvhParams::sah()), rays, true)?;
    compare_bundles(&KdTree::build(&case.tris, &KdParams::default()), rays, true)?;
    compare_bundles(&Grid::build(&case.tris, &GridParams::default()), rays, true)?;
    compare_bundles(
        &HGrid::build(&case.tris, &HGridParams::default()),
        rays,
        true,
    )?;
    compare_bundles(
        &Octree::build(&case.tris, &OctreeParams::default()),
        rays,
        true,
    )
}

fn compare<A: Accel<Prim = Triangle>>(
    accel: &A,
    brute: &BruteForce<Triangle>,
    rays: &[Ray],
) -> Result<(), String> {
    compare_rays(accel, brute, rays).map_err(|m| m.to_string())
}

/// The structures the `saved_*` fuzz targets load, by target name.
pub const SAVED_TARGETS: [&str; 5] = [
    "saved_bvh",
    "saved_kdtree",
    "saved_grid",
    "saved_hgrid",
    "saved_octree",
];

/// The body of the `saved_*` fuzz targets: `bytes` as a saved structure of `target` (one of
/// [`SAVED_TARGETS`]). Loaded as they are (the checksum refuses nearly every change), then
/// with the checksum written again, as a hostile file would have it. A loader may refuse
/// anything but must not panic; a structure it returns must answer rays through its box, the
/// closest points to its corners and the boxes around them without a panic (a walk that never
/// ends is libFuzzer's `-timeout` to catch), and must save to a file that loads to a structure
/// answering the same, bit for bit ([`rt_conformance::compare_saved`]).
///
/// # Errors
/// A loaded structure whose own file does not load back or answers differently.
///
/// # Panics
/// If `target` is not one of [`SAVED_TARGETS`].
pub fn saved(target: &str, bytes: &[u8]) -> Result<(), String> {
    match target {
        "saved_bvh" => saved_as::<Bvh<Triangle>>(bytes),
        "saved_kdtree" => saved_as::<KdTree<Triangle>>(bytes),
        "saved_grid" => saved_as::<Grid<Triangle>>(bytes),
        "saved_hgrid" => saved_as::<HGrid<Triangle>>(bytes),
        "saved_octree" => saved_as::<Octree<Triangle>>(bytes),
        _ => panic!("unknown saved target `{target}`"),
    }
}

fn saved_as<A: Accel<Prim = Triangle> + Persist>(bytes: &[u8]) -> Result<(), String> {
    let _ = A::load(bytes);
    let mut file = bytes.to_vec();
    if file.len() >= 96 {
        let sum = rt_persist::file_checksum(&file);
        file[88..96].copy_from_slice(&sum.to_le_bytes());
    }
    let Ok(accel) = A::load(&file) else {
        return Ok(());
    };
    rt_conformance::compare_saved(&accel, &[], &rays_through(&accel.bounds()))
}

/// Rays through a box from outside along the axes and the diagonals, and from its centre.
fn rays_through(bounds: &rt_core::Aabb) -> Vec<Ray> {
    let (c, e) = if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
        (Vec3::ZERO, Vec3::ONE)
    } else {
        (bounds.center(), bounds.extent().max(Vec3::splat(1e-3)))
    };
    let mut rays = Vec::new();
    for d in [
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        Vec3::ONE,
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(-1.0, 1.0, 1.0),
        Vec3::new(1.0, 1.0, -1.0),
    ] {
        rays.push(Ray::new(c - d * e * 2.0, d));
        rays.push(Ray::new(c, -d));
    }
    rays
}

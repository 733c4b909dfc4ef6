//! The queries over flat arrays, run on rayon's threads with the GIL released: input checks,
//! and the answers laid out as Open3D's `RaycastingScene` lays them out.

use crate::scene::{Built, Structure, with_structure};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use rt_core::glam::{DVec3, Vec3};
use rt_core::{Aabb, Accel, Hit, PointHit, Ray, Triangle};
use rt_sdf::WindingTree;

/// Rays or points per rayon task.
const CHUNK: usize = 256;

/// Runs `f` on a pool of `nthreads` threads, or on rayon's global pool (every core) for 0.
pub(crate) fn pool<R: Send>(nthreads: usize, f: impl FnOnce() -> R + Send) -> PyResult<R> {
    if nthreads == 0 {
        return Ok(f());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(nthreads)
        .build()
        .map_err(|e| PyValueError::new_err(format!("cannot start {nthreads} threads: {e}")))?;
    Ok(pool.install(f))
}

/// Element `i` of an array whose leading shape is `shape`, as numpy prints an index.
fn index(mut i: usize, shape: &[usize]) -> String {
    let mut at = vec![0; shape.len()];
    for (a, &n) in at.iter_mut().zip(shape).rev() {
        if n > 0 {
            *a = i % n;
            i /= n;
        }
    }
    let at: Vec<String> = at.iter().map(usize::to_string).collect();
    format!("[{}]", at.join(", "))
}

/// Why ray `r` is refused, or `None` when it is valid.
fn ray_fault(r: &Ray) -> Option<&'static str> {
    if r.is_valid() {
        return None;
    }
    let d = r.dir().abs().max_element();
    Some(if !(r.origin.is_finite() && r.dir().is_finite()) {
        "has a non-finite coordinate"
    } else if r.origin.abs().max_element() > Ray::MAX_ORIGIN {
        "has an origin coordinate beyond 2**40 in magnitude"
    } else if d < *Ray::DIR_RANGE.start() {
        "has a zero direction (every component below 2**-40 in magnitude)"
    } else {
        "has a direction component beyond 2**40 in magnitude (scale the direction down)"
    })
}

/// The rays of `(n, 6)` rows `ox oy oz dx dy dz` over `[tnear, tfar]`; an invalid one is a
/// `ValueError` naming the first.
pub(crate) fn rays(flat: &[f32], tnear: f32, tfar: f32, shape: &[usize]) -> PyResult<Vec<Ray>> {
    let make = |r: &[f32]| {
        Ray::with_interval(
            Vec3::new(r[0], r[1], r[2]),
            Vec3::new(r[3], r[4], r[5]),
            tnear,
            tfar,
        )
    };
    let rays: Vec<Ray> = flat.par_chunks_exact(6).map(make).collect();
    if let Some(i) = rays.par_iter().position_first(|r| !r.is_valid()) {
        let why = ray_fault(&rays[i]).unwrap_or("is invalid");
        return Err(PyValueError::new_err(format!(
            "rays{} {why}: {:?}",
            index(i, shape),
            &flat[6 * i..6 * i + 6]
        )));
    }
    Ok(rays)
}

/// The points of `(n, 3)` rows; a non-finite one is a `ValueError` naming the first.
pub(crate) fn points(flat: &[f32], shape: &[usize]) -> PyResult<Vec<Vec3>> {
    let points: Vec<Vec3> = flat
        .par_chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    if let Some(i) = points.par_iter().position_first(|p| !p.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "query_points{} has a non-finite coordinate: {:?}",
            index(i, shape),
            points[i].to_array()
        )));
    }
    Ok(points)
}

/// The geometry of scene triangle `prim` and its index there.
fn locate(offsets: &[u32], prim: u32) -> (u32, u32) {
    let g = offsets.partition_point(|&o| o <= prim) - 1;
    (g as u32, prim - offsets[g])
}

/// The unit geometric normal `(v1 - v0) × (v2 - v0)` (zero for a degenerate triangle).
fn unit_normal(t: &Triangle) -> Vec3 {
    t.normal().normalize_or_zero()
}

/// The closest hits, as `cast_rays` returns them.
#[derive(Debug)]
pub(crate) struct Cast {
    pub t: Vec<f32>,
    pub geometry: Vec<u32>,
    pub primitive: Vec<u32>,
    pub uv: Vec<f32>,
    pub normal: Vec<f32>,
}

pub(crate) fn cast(
    built: &Built,
    tris: &[Triangle],
    offsets: &[u32],
    rays: &[Ray],
) -> PyResult<Cast> {
    let mut hits: Vec<Option<Hit>> = vec![None; rays.len()];
    // The structures' bundles: coherent runs of rays (a camera's, in image order) walk
    // together, and rays that spread go singly, with the same answers either way.
    // PERF: AMD Zen 3, two threads, `python/bench/peers.py --repeats 5` (1024×768 views the mesh
    // fills, 57-67% hit), time of Open3D 0.20's `cast_rays` ÷ ours on the bunny, spot and the
    // rocker arm: 0.71, 0.90, 0.95 with single rays and the answers laid out on one thread;
    // 1.34, 1.65, 1.84 with bundles and the layout below on every thread. Scattered rays:
    // 0.71, 0.78, 0.86 before, 0.69, 0.79, 0.86 after. Shadow rays (`occluded_bundle`):
    // 1.03, 1.17, 1.04 before, 1.68, 1.64, 1.86 after.
    with_structure!(&built.structure, a => fill_chunks(rays, &mut hits, |r, o| a.intersect_bundle(r, o)));
    consistent(&hits, |h| h.map(|h| h.prim), tris.len())?;
    let n = rays.len();
    let mut out = Cast {
        t: vec![f32::INFINITY; n],
        geometry: vec![u32::MAX; n],
        primitive: vec![u32::MAX; n],
        uv: vec![0.0; 2 * n],
        normal: vec![0.0; 3 * n],
    };
    (
        out.t.par_chunks_mut(CHUNK),
        out.geometry.par_chunks_mut(CHUNK),
        out.primitive.par_chunks_mut(CHUNK),
        out.uv.par_chunks_mut(2 * CHUNK),
        out.normal.par_chunks_mut(3 * CHUNK),
        hits.par_chunks(CHUNK),
    )
        .into_par_iter()
        .for_each(|(t, geometry, primitive, uv, normal, hits)| {
            for (i, hit) in hits.iter().enumerate() {
                if let Some(h) = hit {
                    (t[i], (geometry[i], primitive[i])) = (h.t, locate(offsets, h.prim));
                    uv[2 * i..2 * i + 2].copy_from_slice(&[h.u, h.v]);
                    let n = unit_normal(&tris[h.prim as usize]);
                    normal[3 * i..3 * i + 3].copy_from_slice(&n.to_array());
                }
            }
        });
    Ok(out)
}

/// Checks that every triangle a structure answered with is one of the scene's: always so for a
/// scene built here, and checked for one loaded from bytes whose sections disagree.
fn consistent<T: Sync>(
    answers: &[T],
    prim: impl Fn(&T) -> Option<u32> + Send + Sync,
    len: usize,
) -> PyResult<()> {
    match answers
        .par_iter()
        .filter_map(prim)
        .find_any(|&p| p as usize >= len)
    {
        Some(p) => Err(PyValueError::new_err(format!(
            "the scene is inconsistent: its structure answered triangle {p}, but it has {len}"
        ))),
        None => Ok(()),
    }
}

/// Every hit of every ray, as `list_intersections` returns them: ragged, each ray's hits in
/// order of `t` (then of triangle).
#[derive(Debug)]
pub(crate) struct Listed {
    pub splits: Vec<u32>,
    pub ray: Vec<u32>,
    pub t: Vec<f32>,
    pub geometry: Vec<u32>,
    pub primitive: Vec<u32>,
    pub uv: Vec<f32>,
}

pub(crate) fn list(built: &Built, offsets: &[u32], len: usize, rays: &[Ray]) -> PyResult<Listed> {
    let mut hits: Vec<Vec<Hit>> = vec![Vec::new(); rays.len()];
    with_structure!(&built.structure, a => fill(rays, &mut hits, |r| a.all_hits(r)));
    consistent(&hits, |h: &Vec<Hit>| h.iter().map(|h| h.prim).max(), len)?;
    let total: usize = hits.iter().map(Vec::len).sum();
    if total >= u32::MAX as usize {
        return Err(PyValueError::new_err(format!(
            "{total} intersections: more than a uint32 ray_splits can index"
        )));
    }
    let mut out = Listed {
        splits: Vec::with_capacity(rays.len() + 1),
        ray: Vec::with_capacity(total),
        t: Vec::with_capacity(total),
        geometry: Vec::with_capacity(total),
        primitive: Vec::with_capacity(total),
        uv: Vec::with_capacity(2 * total),
    };
    out.splits.push(0);
    for (i, hits) in hits.iter().enumerate() {
        for h in hits {
            let (g, p) = locate(offsets, h.prim);
            out.ray.push(i as u32);
            out.t.push(h.t);
            out.geometry.push(g);
            out.primitive.push(p);
            out.uv.extend([h.u, h.v]);
        }
        out.splits.push(out.ray.len() as u32);
    }
    Ok(out)
}

/// The boxes of `(n, 6)` rows `min x y z, max x y z`; one with a non-finite coordinate or a
/// minimum above its maximum is a `ValueError` naming the first.
pub(crate) fn boxes(flat: &[f32], shape: &[usize]) -> PyResult<Vec<Aabb>> {
    let boxes: Vec<Aabb> = flat
        .par_chunks_exact(6)
        .map(|b| Aabb::new(Vec3::new(b[0], b[1], b[2]), Vec3::new(b[3], b[4], b[5])))
        .collect();
    let bad = |b: &Aabb| !(b.min.is_finite() && b.max.is_finite() && b.min.cmple(b.max).all());
    if let Some(i) = boxes.par_iter().position_first(bad) {
        return Err(PyValueError::new_err(format!(
            "boxes{} is not a box (finite, min <= max on every axis): {:?}",
            index(i, shape),
            &flat[6 * i..6 * i + 6]
        )));
    }
    Ok(boxes)
}

/// The triangles meeting each box, ragged, in ascending order: splits, geometry ids,
/// primitive ids.
pub(crate) fn overlapping(
    built: &Built,
    offsets: &[u32],
    len: usize,
    boxes: &[Aabb],
) -> PyResult<(Vec<u32>, Vec<u32>, Vec<u32>)> {
    let mut found: Vec<Vec<u32>> = vec![Vec::new(); boxes.len()];
    with_structure!(&built.structure, a => fill(boxes, &mut found, |b| a.overlapping(b)));
    consistent(&found, |ids: &Vec<u32>| ids.last().copied(), len)?;
    let total: usize = found.iter().map(Vec::len).sum();
    if total >= u32::MAX as usize {
        return Err(PyValueError::new_err(format!(
            "{total} overlaps: more than a uint32 box_splits can index"
        )));
    }
    let mut splits = Vec::with_capacity(boxes.len() + 1);
    let (mut geometry, mut primitive) = (Vec::with_capacity(total), Vec::with_capacity(total));
    splits.push(0);
    for ids in &found {
        for &id in ids {
            let (g, p) = locate(offsets, id);
            geometry.push(g);
            primitive.push(p);
        }
        splits.push(primitive.len() as u32);
    }
    Ok((splits, geometry, primitive))
}

pub(crate) fn occluded(built: &Built, rays: &[Ray]) -> Vec<bool> {
    let mut out = vec![false; rays.len()];
    with_structure!(&built.structure, a => fill_chunks(rays, &mut out, |r, o| a.occluded_bundle(r, o)));
    out
}

pub(crate) fn count(built: &Built, rays: &[Ray]) -> Vec<i32> {
    let mut out = vec![0; rays.len()];
    // A scene holds fewer than 2**32 - 1 triangles, but a count past i32::MAX saturates
    // rather than wraps (Open3D's counts are int32).
    with_structure!(&built.structure, a => fill(rays, &mut out, |r| {
        i32::try_from(a.count_hits(r)).unwrap_or(i32::MAX)
    }));
    out
}

/// The closest points, as `compute_closest_points` returns them, with the distances and
/// (when asked) the signs.
#[derive(Debug)]
pub(crate) struct Closest {
    pub point: Vec<f32>,
    pub geometry: Vec<u32>,
    pub primitive: Vec<u32>,
    pub uv: Vec<f32>,
    pub normal: Vec<f32>,
    pub distance: Vec<f32>,
    pub inside: Option<Vec<bool>>,
}

pub(crate) fn closest(
    built: &Built,
    tris: &[Triangle],
    offsets: &[u32],
    points: &[Vec3],
    winding: Option<&WindingTree>,
) -> PyResult<Closest> {
    let mut near: Vec<Option<PointHit>> = vec![None; points.len()];
    with_structure!(&built.structure, a => {
        rt_core::batch::closest_points(a, points, f32::INFINITY, &mut near)
    });
    consistent(&near, |h| h.map(|h| h.prim), tris.len())?;
    let inside = winding.map(|w| {
        let mut inside = vec![false; points.len()];
        fill(points, &mut inside, |&p| w.is_inside(p));
        inside
    });
    let n = points.len();
    let mut out = Closest {
        point: vec![f32::NAN; 3 * n],
        geometry: vec![u32::MAX; n],
        primitive: vec![u32::MAX; n],
        uv: vec![0.0; 2 * n],
        normal: vec![0.0; 3 * n],
        distance: vec![f32::INFINITY; n],
        inside,
    };
    for (i, near) in near.iter().enumerate() {
        // Every valid point has a nearest triangle in a scene that has one.
        if let Some(h) = near {
            let (g, p) = locate(offsets, h.prim);
            let tri = &tris[h.prim as usize];
            out.point[3 * i..3 * i + 3].copy_from_slice(&h.point.to_array());
            out.geometry[i] = g;
            out.primitive[i] = p;
            out.uv[2 * i..2 * i + 2].copy_from_slice(&barycentric(tri, h.point));
            out.normal[3 * i..3 * i + 3].copy_from_slice(&unit_normal(tri).to_array());
            out.distance[i] = h.distance;
        }
    }
    Ok(out)
}

pub(crate) fn winding(winding: &WindingTree, points: &[Vec3]) -> Vec<f64> {
    let mut out = vec![0.0; points.len()];
    fill(points, &mut out, |&p| winding.winding_number(p, 1e-9).value);
    out
}

pub(crate) fn inside(winding: &WindingTree, points: &[Vec3]) -> Vec<bool> {
    let mut out = vec![false; points.len()];
    fill(points, &mut out, |&p| winding.is_inside(p));
    out
}

/// The weights `(u, v)` of `v1` and `v2` at `p`, a point of the triangle (Embree's and Open3D's
/// convention: `p = (1 - u - v) v0 + u v1 + v v2`), in `f64`; `(0, 0)` on a degenerate one.
fn barycentric(t: &Triangle, p: Vec3) -> [f32; 2] {
    let (v0, e1, e2) = (
        t.v0.as_dvec3(),
        (t.v1 - t.v0).as_dvec3(),
        (t.v2 - t.v0).as_dvec3(),
    );
    let q: DVec3 = p.as_dvec3() - v0;
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (q.dot(e1), q.dot(e2));
    let det = d00 * d11 - d01 * d01;
    if det <= 0.0 || !det.is_finite() {
        return [0.0, 0.0];
    }
    let u = (d11 * d20 - d01 * d21) / det;
    let v = (d00 * d21 - d01 * d20) / det;
    [u as f32, v as f32]
}

/// `out[i] = f(&items[i])` on rayon's threads, in chunks.
fn fill<T: Sync, R: Send>(items: &[T], out: &mut [R], f: impl Fn(&T) -> R + Sync) {
    fill_chunks(items, out, |items, out| {
        for (o, item) in out.iter_mut().zip(items) {
            *o = f(item);
        }
    });
}

/// `f(items, out)` over matching chunks of both, on rayon's threads.
fn fill_chunks<T: Sync, R: Send>(items: &[T], out: &mut [R], f: impl Fn(&[T], &mut [R]) + Sync) {
    out.par_chunks_mut(CHUNK)
        .zip(items.par_chunks(CHUNK))
        .for_each(|(out, items)| f(items, out));
}

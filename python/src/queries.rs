//! The queries over flat arrays, run on rayon's threads with the GIL released: input checks,
//! and the answers laid out as Open3D's `RaycastingScene` lays them out.

use crate::scene::{Built, Structure, with_structure};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use rt_core::batch::{self, CHUNK, FlatRays, FlatRaysError};
use rt_core::bytemuck::cast_slice_mut;
use rt_core::glam::{DVec3, Vec3};
use rt_core::{Aabb, Accel, Hit, PointHit, Triangle};
use rt_sdf::WindingTree;
use std::sync::atomic::{AtomicU32, Ordering};

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

/// The rays of `(n, 6)` rows `ox oy oz dx dy dz` over `[tnear, tfar]`, made a chunk at a time
/// as the queries read them; an invalid one is a `ValueError` naming the first.
pub(crate) fn rays<'a>(
    flat: &'a [f32],
    tnear: f32,
    tfar: f32,
    shape: &[usize],
) -> PyResult<FlatRays<'a>> {
    FlatRays::new(flat, tnear, tfar).map_err(|e| {
        PyValueError::new_err(match e {
            FlatRaysError::Invalid { row, fault } => format!(
                "rays{} {fault}: {:?}",
                index(row, shape),
                &flat[6 * row..6 * row + 6]
            ),
            FlatRaysError::Ragged { .. } => format!("rays: {e}"),
        })
    })
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

/// Every triangle's [`unit_normal`], then a zero normal, which `cast_rays` gives a miss.
pub(crate) fn normals(tris: &[Triangle]) -> Vec<[f32; 3]> {
    let mut normals: Vec<[f32; 3]> = tris.par_iter().map(|t| unit_normal(t).to_array()).collect();
    normals.push([0.0; 3]);
    normals
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
    rays: &FlatRays,
) -> PyResult<Cast> {
    let n = rays.len();
    // Zeroed storage is mapped lazily and each thread writes every slot of its chunks, so the
    // pages are first touched by the threads that fill them; the rays are made a chunk at a
    // time on the stack, and the hits laid out from a buffer there.
    // PERF: AMD Zen 3, two threads, `python/bench/peers.py --repeats 3`, time of Open3D 0.20's
    // `cast_rays` ÷ ours on the bunny, spot and the rocker arm. Primary rays (1024×768 views
    // the mesh fills, 57-67% hit): 0.90, 1.72, 1.42 with a list of rays, a list of hits and
    // outputs first written on one thread (a third of the time was the kernel's, mapping and
    // clearing those pages); 1.53, 1.53, 1.65 as here. Scattered rays: 0.86, 0.82, 0.92 before,
    // 0.94, 1.08, 0.91 after.
    let mut out = Cast {
        t: vec![0.0; n],
        geometry: vec![0; n],
        primitive: vec![0; n],
        uv: vec![0.0; 2 * n],
        normal: vec![0.0; 3 * n],
    };
    let unknown = AtomicU32::new(u32::MAX);
    let slots = (
        &mut out.t[..],
        &mut out.geometry[..],
        &mut out.primitive[..],
        cast_slice_mut::<f32, [f32; 2]>(&mut out.uv),
        cast_slice_mut::<f32, [f32; 3]>(&mut out.normal),
    );
    // The structures' bundles: coherent runs of rays (a camera's, in image order) walk
    // together, and rays that spread go singly, with the same answers either way.
    // PERF: (the same bench, before the change above) bundles ÷ single rays with the layout on
    // one thread, Open3D's time ÷ ours: primary 0.71, 0.90, 0.95 -> 1.34, 1.65, 1.84; shadow
    // rays (`occluded_bundle`) 1.03, 1.17, 1.04 -> 1.68, 1.64, 1.86.
    // The normals come from a table of them, read in a loop of their own with no branch.
    // PERF: AMD Zen 3, one thread, 500k scattered rays and 1024×768 primary rays, medians of
    // 15 paired calls in one process, time ÷ that of making each normal from `tris` in the
    // loop below: the bunny scattered 0.91, primary 0.96; spot 0.96, 0.85; the rocker arm
    // 0.88, 0.92; the beetle 0.91, 0.92. What remains is the table's cache misses (4-5% of a
    // bunny scattered call in `perf`), which a walk handing back the normal of the triangle it
    // hit would not have.
    let normals = built.normals.get_or_init(|| normals(tris));
    let miss = normals.len() - 1;
    with_structure!(&built.structure, a => batch::for_each_ray_chunk(rays, slots, |rays, (t, g, p, uv, normal)| {
        let mut hits = [None; CHUNK];
        let hits = &mut hits[..rays.len()];
        a.intersect_bundle(rays, hits);
        for (n, h) in normal.iter_mut().zip(hits.iter()) {
            *n = normals[h.map_or(miss, |h| h.prim as usize).min(miss)];
        }
        for (i, hit) in hits.iter().enumerate() {
            match hit.filter(|h| (h.prim as usize) < tris.len()) {
                Some(h) => {
                    (t[i], (g[i], p[i])) = (h.t, locate(offsets, h.prim));
                    uv[i] = [h.u, h.v];
                }
                None => {
                    if let Some(h) = hit {
                        unknown.fetch_min(h.prim, Ordering::Relaxed);
                    }
                    (t[i], g[i], p[i]) = (f32::INFINITY, u32::MAX, u32::MAX);
                }
            }
        }
    }));
    match unknown.into_inner() {
        u32::MAX => Ok(out),
        p => Err(inconsistent(p, tris.len())),
    }
}

fn inconsistent(p: u32, len: usize) -> PyErr {
    PyValueError::new_err(format!(
        "the scene is inconsistent: its structure answered triangle {p}, but it has {len}"
    ))
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
        Some(p) => Err(inconsistent(p, len)),
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

pub(crate) fn list(
    built: &Built,
    offsets: &[u32],
    len: usize,
    rays: &FlatRays,
) -> PyResult<Listed> {
    let mut hits: Vec<Vec<Hit>> = vec![Vec::new(); rays.len()];
    with_structure!(&built.structure, a => batch::all_hits(a, rays, &mut hits));
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
    with_structure!(&built.structure, a => batch::overlapping(a, boxes, &mut found));
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

pub(crate) fn occluded(built: &Built, rays: &FlatRays) -> Vec<bool> {
    let mut out = vec![false; rays.len()];
    with_structure!(&built.structure, a => batch::occluded(a, rays, &mut out));
    out
}

pub(crate) fn count(built: &Built, rays: &FlatRays) -> Vec<i32> {
    let mut out = vec![0; rays.len()];
    // A scene holds fewer than 2**32 - 1 triangles, but a count past i32::MAX saturates
    // rather than wraps (Open3D's counts are int32).
    with_structure!(&built.structure, a => batch::for_each_ray_chunk(rays, &mut out[..], |rays, out| {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = i32::try_from(a.count_hits(r)).unwrap_or(i32::MAX);
        }
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
    let n = points.len();
    let mut near: Vec<Option<PointHit>> = vec![None; n];
    let inside = match winding {
        Some(w) => {
            let mut signed = vec![None; n];
            with_structure!(&built.structure, a => {
                rt_sdf::batch::signed_distances(a, w, points, f32::INFINITY, &mut signed)
            });
            let mut inside = vec![false; n];
            batch::for_each_chunk(
                &signed,
                (&mut near[..], &mut inside[..]),
                |s, (near, inside)| {
                    for (s, (n, i)) in s.iter().zip(near.iter_mut().zip(inside)) {
                        (*n, *i) = (s.map(|s| s.near), s.is_some_and(|s| s.inside));
                    }
                },
            );
            Some(inside)
        }
        None => {
            with_structure!(&built.structure, a => {
                batch::closest_points(a, points, f32::INFINITY, &mut near)
            });
            None
        }
    };
    consistent(&near, |h| h.map(|h| h.prim), tris.len())?;
    // Zeroed and then written in every slot, on every thread, as `cast` does.
    let mut out = Closest {
        point: vec![0.0; 3 * n],
        geometry: vec![0; n],
        primitive: vec![0; n],
        uv: vec![0.0; 2 * n],
        normal: vec![0.0; 3 * n],
        distance: vec![0.0; n],
        inside,
    };
    let slots = (
        cast_slice_mut::<f32, [f32; 3]>(&mut out.point),
        &mut out.geometry[..],
        &mut out.primitive[..],
        cast_slice_mut::<f32, [f32; 2]>(&mut out.uv),
        cast_slice_mut::<f32, [f32; 3]>(&mut out.normal),
        &mut out.distance[..],
    );
    batch::for_each_chunk(&near, slots, |near, (point, g, p, uv, normal, distance)| {
        for (i, near) in near.iter().enumerate() {
            // Every valid point has a nearest triangle in a scene that has one.
            match near {
                Some(h) => {
                    let tri = &tris[h.prim as usize];
                    point[i] = h.point.to_array();
                    (g[i], p[i]) = locate(offsets, h.prim);
                    uv[i] = barycentric(tri, h.point);
                    normal[i] = unit_normal(tri).to_array();
                    distance[i] = h.distance;
                }
                None => {
                    point[i] = [f32::NAN; 3];
                    (g[i], p[i], distance[i]) = (u32::MAX, u32::MAX, f32::INFINITY);
                }
            }
        }
    });
    Ok(out)
}

pub(crate) fn winding(winding: &WindingTree, points: &[Vec3]) -> Vec<f64> {
    let mut out = vec![0.0; points.len()];
    rt_sdf::batch::winding_numbers(winding, points, 1e-9, &mut out);
    out
}

pub(crate) fn inside(winding: &WindingTree, points: &[Vec3]) -> Vec<bool> {
    let mut out = vec![false; points.len()];
    rt_sdf::batch::inside(winding, points, &mut out);
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

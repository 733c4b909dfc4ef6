"""Every query of every structure against brute force, and brute force against independent
float64 references written here in numpy."""

from __future__ import annotations

import numpy as np
import pytest

import rt_accel
from conftest import (
    SCENES,
    STRUCTURES,
    moller_trumbore,
    point_triangle_distance,
    points_for,
    rays_for,
    scene_of,
    shared_meshes,
    soup,
    winding_exact,
)


def two_meshes():
    """The cube and a soup beside it, as two geometries of one scene."""
    cv, ct = SCENES["cube"]()
    sv, st = soup(120, seed=3)
    return [(cv, ct), (sv + np.float32(0.5), st)]


CASES = {name: [make()] for name, make in SCENES.items()}
CASES["two_meshes"] = two_meshes()


def all_vertices(meshes):
    return np.vstack([v for v, _ in meshes])


def assert_same_hits(got, want):
    np.testing.assert_array_equal(got["primitive_ids"], want["primitive_ids"])
    np.testing.assert_array_equal(got["geometry_ids"], want["geometry_ids"])
    hit = want["primitive_ids"] != rt_accel.INVALID_ID
    np.testing.assert_array_equal(np.isinf(got["t_hit"]), ~hit)
    np.testing.assert_allclose(got["t_hit"][hit], want["t_hit"][hit], rtol=1e-5)
    np.testing.assert_allclose(got["primitive_uvs"], want["primitive_uvs"], atol=1e-5)
    np.testing.assert_array_equal(got["primitive_normals"], want["primitive_normals"])


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("structure", STRUCTURES)
def test_ray_queries_agree_with_brute_force(structure, case):
    meshes = CASES[case]
    rays = rays_for(all_vertices(meshes))
    got, want = scene_of(structure, *meshes), scene_of("brute", *meshes)
    assert_same_hits(got.cast_rays(rays), want.cast_rays(rays))
    np.testing.assert_array_equal(got.test_occlusions(rays), want.test_occlusions(rays))
    np.testing.assert_array_equal(
        got.test_occlusions(rays, tnear=0.5, tfar=2.0),
        want.test_occlusions(rays, tnear=0.5, tfar=2.0),
    )
    np.testing.assert_array_equal(got.count_intersections(rays), want.count_intersections(rays))


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("structure", STRUCTURES)
def test_point_queries_agree_with_brute_force(structure, case):
    meshes = CASES[case]
    points = points_for(all_vertices(meshes))
    got, want = scene_of(structure, *meshes), scene_of("brute", *meshes)
    g, w = got.compute_closest_points(points), want.compute_closest_points(points)
    for key in ("primitive_ids", "geometry_ids", "points"):
        np.testing.assert_array_equal(g[key], w[key])
    np.testing.assert_array_equal(got.compute_distance(points), want.compute_distance(points))
    np.testing.assert_array_equal(
        got.compute_signed_distance(points), want.compute_signed_distance(points)
    )
    np.testing.assert_array_equal(got.compute_occupancy(points), want.compute_occupancy(points))


def test_the_kit_check_fails_on_a_wrong_answer():
    """The comparison above can fail: a scene missing one triangle is told apart."""
    v, t = SCENES["cube"]()
    rays = rays_for(v)
    full, short = scene_of("bvh", (v, t)), scene_of("brute", (v, t[1:]))
    with pytest.raises(AssertionError):
        assert_same_hits(full.cast_rays(rays), short.cast_rays(rays))


def test_brute_force_matches_float64_moller_trumbore():
    """The reference itself: where a float64 test leaves no doubt (the closest hit clear of
    every edge and of the next hit), brute force's answer is that hit; where no triangle comes
    near the ray, it misses."""
    v, t = soup(200, seed=5)
    rays = rays_for(v, n=1500, seed=9)[:1500]
    got = scene_of("brute", (v, t)).cast_rays(rays)
    tt, u, w, raw = moller_trumbore(rays, v, t)
    order = np.argsort(tt, axis=1)
    best, second = order[:, 0], order[:, 1]
    rows = np.arange(len(rays))
    t0, t1 = tt[rows, best], tt[rows, second]
    margin = np.minimum.reduce([u[rows, best], w[rows, best], 1 - u[rows, best] - w[rows, best]])
    with np.errstate(invalid="ignore"):
        alone = np.isinf(t1) | (t1 - t0 > 1e-4 * t0)
    clear = np.isfinite(t0) & (margin > 1e-4) & alone
    assert clear.sum() > 250
    np.testing.assert_array_equal(got["primitive_ids"][clear], best[clear])
    np.testing.assert_allclose(got["t_hit"][clear], t0[clear], rtol=1e-5)
    # A miss: no triangle within 1e-3 of its barycentric range ahead of the origin.
    near = (u > -1e-3) & (w > -1e-3) & (u + w < 1 + 1e-3) & (raw > -1e-3)
    far = ~np.any(near, axis=1)
    assert far.sum() > 100
    assert np.all(got["primitive_ids"][far] == rt_accel.INVALID_ID)


def test_brute_force_distances_match_float64():
    v, t = soup(150, seed=2)
    points = points_for(v, n=600)
    want = point_triangle_distance(points, v, t)
    got = scene_of("brute", (v, t)).compute_closest_points(points)
    np.testing.assert_allclose(
        scene_of("brute", (v, t)).compute_distance(points), want.min(axis=1), rtol=1e-5, atol=1e-7
    )
    # The id is the nearest triangle's wherever the nearest is clear of the next.
    srt = np.sort(want, axis=1)
    clear = srt[:, 1] - srt[:, 0] > 1e-5
    np.testing.assert_array_equal(got["primitive_ids"][clear], want.argmin(axis=1)[clear])
    # The uv weights rebuild the closest point.
    a, b, c = (v[t[got["primitive_ids"]]][:, k].astype(np.float64) for k in range(3))
    uv = got["primitive_uvs"].astype(np.float64)
    rebuilt = a + uv[:, :1] * (b - a) + uv[:, 1:] * (c - a)
    np.testing.assert_allclose(rebuilt, got["points"], atol=1e-5)


@pytest.mark.parametrize("case", ["cube", "open_box"])
def test_signs_match_the_exact_winding_number(case):
    v, t = SCENES[case]()
    points = points_for(v, n=3000)
    exact = winding_exact(points, v, t)
    clear = np.abs(exact - 0.5) > 1e-6
    scene = scene_of("bvh", (v, t))
    np.testing.assert_allclose(scene.winding_number(points), exact, atol=1e-8)
    sd = scene.compute_signed_distance(points)
    signed = clear & (sd != 0)  # on the surface the distance is 0, of either sign
    np.testing.assert_array_equal((sd < 0)[signed], (exact > 0.5)[signed])
    np.testing.assert_array_equal(scene.compute_occupancy(points)[clear], (exact > 0.5)[clear])
    assert np.all(np.abs(sd) == scene.compute_distance(points))


def test_cube_answers_by_hand():
    v, t = SCENES["cube"]()
    scene = scene_of("kdtree", (v, t))
    rays = np.array([[0.25, 0.5, 3, 0, 0, -1], [0.25, 0.5, 3, 0, 0, -2], [5, 5, 5, 1, 0, 0]])
    hits = scene.cast_rays(rays)
    np.testing.assert_array_equal(hits["t_hit"], [2.0, 1.0, np.inf])
    np.testing.assert_array_equal(hits["primitive_normals"][0], [0, 0, 1])
    assert hits["geometry_ids"][2] == rt_accel.INVALID_ID
    np.testing.assert_array_equal(scene.count_intersections(rays), [2, 2, 0])
    np.testing.assert_array_equal(scene.test_occlusions(rays, tfar=1.5), [False, True, False])
    # Through the diagonals of the top and bottom faces: both triangles of each face count.
    assert scene.count_intersections(np.array([0.5, 0.5, 3, 0, 0, -1])) == 4
    points = np.array([[0.5, 0.5, 0.5], [0.5, 0.5, 1.25], [2.0, 0.5, 0.5]])
    np.testing.assert_allclose(scene.compute_signed_distance(points), [-0.5, 0.25, 1.0])
    # Open3D's call, with its vote of rays, runs unchanged and answers the same.
    np.testing.assert_array_equal(
        scene.compute_signed_distance(points, nthreads=0, nsamples=5),
        scene.compute_signed_distance(points),
    )
    np.testing.assert_array_equal(scene.compute_occupancy(points), [1, 0, 0])


def test_any_leading_shape_and_dtype():
    v, t = SCENES["cube"]()
    scene = scene_of("grid", (v.astype(np.float64), t.astype(np.int64)))
    rays = rays_for(v, n=24)[:24]
    flat = scene.cast_rays(rays)
    shaped = scene.cast_rays(rays.astype(np.float64).reshape(2, 3, 4, 6))
    assert shaped["t_hit"].shape == (2, 3, 4)
    assert shaped["primitive_uvs"].shape == (2, 3, 4, 2)
    assert shaped["primitive_normals"].shape == (2, 3, 4, 3)
    np.testing.assert_array_equal(shaped["t_hit"].reshape(-1), flat["t_hit"])
    strided = np.zeros((24, 12), dtype=np.float32)
    strided[:, ::2] = rays
    np.testing.assert_array_equal(scene.cast_rays(strided[:, ::2])["t_hit"], flat["t_hit"])
    one = scene.cast_rays(rays[0])
    assert one["t_hit"].shape == () and one["primitive_uvs"].shape == (2,)
    empty = scene.cast_rays(np.zeros((0, 6)))
    assert empty["t_hit"].shape == (0,)
    assert scene.compute_distance(np.zeros((5, 0, 3))).shape == (5, 0)


def test_dtypes_match_open3d():
    v, t = SCENES["cube"]()
    scene = scene_of("octree", (v, t))
    rays = rays_for(v, n=10)[:10]
    hits = scene.cast_rays(rays)
    assert hits["t_hit"].dtype == np.float32
    assert hits["geometry_ids"].dtype == np.uint32
    assert hits["primitive_ids"].dtype == np.uint32
    assert hits["primitive_uvs"].dtype == np.float32
    assert hits["primitive_normals"].dtype == np.float32
    assert scene.test_occlusions(rays).dtype == np.bool_
    assert scene.count_intersections(rays).dtype == np.int32
    points = points_for(v, n=10)
    assert scene.compute_distance(points).dtype == np.float32
    assert scene.compute_signed_distance(points).dtype == np.float32
    assert scene.compute_occupancy(points).dtype == np.float32
    assert scene.winding_number(points).dtype == np.float64


@pytest.mark.parametrize("structure", STRUCTURES)
def test_every_preset_agrees(structure):
    v, t = SCENES["plane_grid"]()
    rays = rays_for(v, n=300)
    want = scene_of("brute", (v, t)).cast_rays(rays)
    for preset in rt_accel.presets(structure):
        assert_same_hits(scene_of(structure, (v, t), preset=preset).cast_rays(rays), want)


def test_bunny_from_the_shared_meshes():
    """A real mesh read by load_mesh: the BVH and the kd-tree answer as brute force on a
    sample of rays and points, and signs follow the exact winding number (the bunny has holes)."""
    v, t = rt_accel.load_mesh(shared_meshes() / "stanford-bunny.obj")
    assert v.dtype == np.float32 and t.dtype == np.uint32 and t.shape[1] == 3
    rays = rays_for(v, n=400)
    points = points_for(v, n=60)
    want = scene_of("brute", (v, t))
    for structure in ("bvh", "kdtree"):
        got = scene_of(structure, (v, t))
        assert_same_hits(got.cast_rays(rays), want.cast_rays(rays))
        np.testing.assert_array_equal(
            got.compute_closest_points(points)["primitive_ids"],
            want.compute_closest_points(points)["primitive_ids"],
        )
    # The float64 reference costs about 60 ns a point and triangle: 64 points, 40 near the
    # surface (where the holes matter) and 24 in the box.
    points = np.vstack([points[60:100], points[:24]])
    exact = np.concatenate([winding_exact(p, v, t) for p in np.split(points, 4)])
    scene = scene_of("bvh", (v, t))
    sd = scene.compute_signed_distance(points)
    clear = (np.abs(exact - 0.5) > 1e-6) & (sd != 0)
    assert clear.sum() > 50
    np.testing.assert_array_equal((sd < 0)[clear], (exact > 0.5)[clear])
    on = np.abs(exact - 0.5) > 1e-6
    np.testing.assert_array_equal(scene.compute_occupancy(points)[on], (exact > 0.5)[on])


def boxes_for(vertices, n=400, seed=13):
    """Boxes of many sizes around the mesh, some flat, some points."""
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(0), vertices.max(0)
    a = lo + rng.random((n, 3)) * (hi - lo)
    size = (hi - lo) * rng.random((n, 1)) ** 3 * rng.random((n, 3))
    size[: n // 10, rng.integers(0, 3)] = 0  # flat boxes
    size[n // 10 : n // 5] = 0  # points
    return np.hstack([a, a + size]).astype(np.float32)


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("structure", STRUCTURES)
def test_list_and_overlap_agree_with_brute_force(structure, case):
    meshes = CASES[case]
    v = all_vertices(meshes)
    rays, boxes = rays_for(v), boxes_for(v)
    got, want = scene_of(structure, *meshes), scene_of("brute", *meshes)
    g, w = got.list_intersections(rays), want.list_intersections(rays)
    for key in ("ray_splits", "ray_ids", "geometry_ids", "primitive_ids"):
        np.testing.assert_array_equal(g[key], w[key])
    np.testing.assert_allclose(g["t_hit"], w["t_hit"], rtol=1e-5)
    g, w = got.overlapping(boxes), want.overlapping(boxes)
    for key in w:
        np.testing.assert_array_equal(g[key], w[key])


def test_list_intersections_by_its_own_rules():
    v, t = soup(200, seed=12)
    scene = scene_of("bvh", (v, t))
    rays = rays_for(v, n=800)
    listed = scene.list_intersections(rays.reshape(4, -1, 6))
    splits = listed["ray_splits"]
    assert splits.dtype == np.uint32 and splits[0] == 0 and len(splits) == len(rays) + 1
    np.testing.assert_array_equal(np.diff(splits), scene.count_intersections(rays))
    np.testing.assert_array_equal(listed["ray_ids"], np.repeat(np.arange(len(rays)), np.diff(splits)))
    for i in range(len(rays)):
        ts = listed["t_hit"][splits[i] : splits[i + 1]]
        assert np.all(np.diff(ts) >= 0)
    # The first hit of each ray is its closest.
    hits = scene.cast_rays(rays)
    some = np.diff(splits) > 0
    np.testing.assert_array_equal(listed["primitive_ids"][splits[:-1][some]], hits["primitive_ids"][some])
    np.testing.assert_array_equal(listed["t_hit"][splits[:-1][some]], hits["t_hit"][some])
    # Against float64: every clear crossing is listed.
    tt, u, w, _ = moller_trumbore(rays, v, t)
    margin = np.minimum.reduce([u, w, 1 - u - w])
    for i in range(0, len(rays), 7):
        clear = np.flatnonzero(np.isfinite(tt[i]) & (margin[i] > 1e-4))
        found = set(listed["primitive_ids"][splits[i] : splits[i + 1]].tolist())
        assert set(clear.tolist()) <= found


def test_overlapping_by_its_own_rules():
    v, t = soup(300, seed=14)
    scene = scene_of("octree", (v, t))
    boxes = boxes_for(v)
    out = scene.overlapping(boxes.reshape(-1, 2, 3))
    splits = out["box_splits"]
    assert len(splits) == len(boxes) + 1
    tri = v[t]  # (m, 3, 3)
    tlo, thi = tri.min(1), tri.max(1)
    for i, b in enumerate(boxes):
        ids = out["primitive_ids"][splits[i] : splits[i + 1]]
        assert np.all(np.diff(ids.astype(np.int64)) > 0)
        # Every triangle listed has its bounding box meeting the box...
        assert np.all((tlo[ids] <= b[3:]) & (thi[ids] >= b[:3]))
        # ...and every triangle with a vertex in the box is listed.
        inside = np.any(np.all((tri >= b[:3]) & (tri <= b[3:]), axis=2), axis=1)
        assert set(np.flatnonzero(inside).tolist()) <= set(ids.tolist())
    # By hand: the unit square's two triangles at z = 0, a box touching only one of them.
    square = scene_of("grid", SCENES["plane_grid"](1))
    out = square.overlapping(np.array([[0.8, 0.0, -1, 1.0, 0.1, 1]]))
    np.testing.assert_array_equal(out["primitive_ids"], [0])
    with pytest.raises(ValueError, match=r"boxes\[1\] is not a box"):
        square.overlapping(np.array([[0, 0, 0, 1, 1, 1], [0, 0, 0, -1, 1, 1]]))

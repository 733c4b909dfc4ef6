"""Meshes, rays and points for the tests, and independent float64 references in numpy."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import rt_accel

STRUCTURES = [s for s in rt_accel.STRUCTURES if s != "brute"]


def shared_meshes() -> Path:
    """``../shared/meshes`` beside the repository (or ``RT_SHARED_MESHES``). Missing, the tests
    that need it fail under ``CI=true`` and are skipped elsewhere, saying why."""
    path = Path(
        os.environ.get("RT_SHARED_MESHES")
        or Path(__file__).resolve().parents[2].parent / "shared" / "meshes"
    )
    if not path.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI=true but the shared meshes are missing: {path}")
        pytest.skip(f"the shared meshes are not at {path} (set RT_SHARED_MESHES)")
    return path


def cube(lo=0.0, hi=1.0):
    """A closed cube, faces turned outwards, 12 triangles sharing edges and vertices."""
    v = np.array(
        [[x, y, z] for x in (lo, hi) for y in (lo, hi) for z in (lo, hi)], dtype=np.float32
    )
    # Vertex k has bits (x, y, z) = (k >> 2 & 1, k >> 1 & 1, k & 1).
    quads = [
        (0, 1, 3, 2),  # x = lo, normal -x
        (4, 6, 7, 5),  # x = hi
        (0, 4, 5, 1),  # y = lo
        (2, 3, 7, 6),  # y = hi
        (0, 2, 6, 4),  # z = lo
        (1, 5, 7, 3),  # z = hi
    ]
    t = []
    for a, b, c, d in quads:
        t += [(a, b, c), (a, c, d)]
    return v, np.array(t, dtype=np.uint32)


def open_box():
    """The cube without its top face (z = 1): a mesh with a hole."""
    v, t = cube()
    return v, t[:10]


def plane_grid(n=4):
    """An n x n grid of unit squares at z = 0, two triangles each: shared edges and vertices
    on lattice coordinates, where rays through them must hit exactly one triangle."""
    xs = np.arange(n + 1, dtype=np.float32)
    v = np.array([[x, y, 0.0] for y in xs for x in xs], dtype=np.float32)
    t = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            b, c, d = a + 1, a + n + 2, a + n + 1
            t += [(a, b, c), (a, c, d)]
    return v, np.array(t, dtype=np.uint32)


def soup(n=300, seed=1):
    """Random small triangles in the unit box."""
    rng = np.random.default_rng(seed)
    centers = rng.random((n, 1, 3))
    v = (centers + 0.15 * (rng.random((n, 3, 3)) - 0.5)).reshape(-1, 3).astype(np.float32)
    return v, np.arange(3 * n, dtype=np.uint32).reshape(n, 3)


def duplicates():
    """Coincident and coplanar overlapping triangles: ties that the smaller id must win."""
    v = np.array(
        [[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 0], [2, 0, 0], [0, 2, 0], [1, 1, 0]],
        dtype=np.float32,
    )
    t = np.array([[3, 4, 5], [0, 1, 2], [0, 1, 6], [2, 1, 0]], dtype=np.uint32)
    return v, t


SCENES = {
    "cube": cube,
    "open_box": open_box,
    "plane_grid": plane_grid,
    "soup": soup,
    "duplicates": duplicates,
}


def scene_of(structure, *meshes, preset=None):
    scene = rt_accel.Scene(structure, preset)
    for v, t in meshes:
        scene.add_triangles(v, t)
    return scene


def rays_for(vertices, n=2000, seed=7):
    """Rays from around the mesh's box through points in it, plus the hard ones: along the
    axes through lattice points (vertices and edges of the grid scenes), grazing rays lying in
    the plane z = 0, and rays starting on the surface."""
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(0), vertices.max(0)
    center, size = (lo + hi) / 2, float(np.max(hi - lo)) + 1e-3
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    origins = center + 1.5 * size * d
    targets = lo + rng.random((n, 3)) * (hi - lo)
    random_rays = np.hstack([origins, targets - origins])
    lattice = np.array(
        [[x, y, 3.0, 0, 0, -1] for x in np.arange(-1, 6, 0.5) for y in np.arange(-1, 6, 0.5)]
    )
    grazing = np.array(
        [[-1, y, 0, 1, s, 0] for y in np.arange(0, 5, 0.5) for s in (0.0, 0.25, -0.0)]
    )
    on_surface = np.hstack([vertices[: min(len(vertices), 50)], np.tile([0.3, -0.2, 1.0], (min(len(vertices), 50), 1))])
    return np.vstack([random_rays, lattice, grazing, on_surface]).astype(np.float32)


def points_for(vertices, n=1500, seed=11):
    """Points in the mesh's box grown by a quarter, and points on and near its vertices."""
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(0), vertices.max(0)
    grow = 0.25 * (hi - lo) + 1e-3
    box = lo - grow + rng.random((n, 3)) * (hi - lo + 2 * grow)
    near = vertices[rng.integers(0, len(vertices), 200)] + 1e-3 * rng.normal(size=(200, 3))
    return np.vstack([box, near, vertices[:50]]).astype(np.float32)


# ---- independent float64 references ------------------------------------------------------


def triangles_of(vertices, triangles):
    t = np.asarray(vertices, dtype=np.float64)[np.asarray(triangles, dtype=np.int64)]
    return t[:, 0], t[:, 1], t[:, 2]


def moller_trumbore(rays, vertices, triangles):
    """Every ray against every triangle in float64: ``t`` (inf where missed), ``u``, ``v`` and
    the plane's ``t`` (NaN for a ray parallel to it), each ``(rays, triangles)``."""
    v0, v1, v2 = triangles_of(vertices, triangles)
    o, d = rays[:, None, :3].astype(np.float64), rays[:, None, 3:].astype(np.float64)
    e1, e2 = v1 - v0, v2 - v0
    p = np.cross(d, e2)
    det = (p * e1).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o - v0
        u = (s * p).sum(-1) * inv
        q = np.cross(s, e1)
        v = (d * q).sum(-1) * inv
        t = (q * e2).sum(-1) * inv
    ok = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0)
    return np.where(ok, t, np.inf), u, v, t


def point_triangle_distance(points, vertices, triangles):
    """The distance from every point to every triangle in float64, ``(points, triangles)``:
    the minimum over the face (when the projection falls inside) and the three edges."""
    a, b, c = triangles_of(vertices, triangles)
    p = points[:, None, :].astype(np.float64)

    def segment(x, y):
        xy = y - x
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.clip(np.einsum("ptk,tk->pt", p - x, xy) / np.einsum("tk,tk->t", xy, xy), 0, 1)
        s = np.nan_to_num(s)
        return np.linalg.norm(p - (x + s[..., None] * xy), axis=-1)

    n = np.cross(b - a, c - a)
    nn = np.einsum("tk,tk->t", n, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.einsum("ptk,tk->pt", p - a, n) / nn
    foot = p - h[..., None] * n
    inside = np.ones(h.shape, dtype=bool)
    for x, y in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ptk,tk->pt", np.cross(y - x, foot - x), n) >= 0
    face = np.where(inside & (nn > 0), np.abs(h) * np.sqrt(nn), np.inf)
    return np.minimum.reduce([face, segment(a, b), segment(b, c), segment(c, a)])


def winding_exact(points, vertices, triangles):
    """The generalised winding number in float64 (Van Oosterom & Strackee's solid angle)."""
    a, b, c = triangles_of(vertices, triangles)
    p = points[:, None, :].astype(np.float64)
    x, y, z = a - p, b - p, c - p
    lx, ly, lz = (np.linalg.norm(w, axis=-1) for w in (x, y, z))
    det = np.einsum("ptk,ptk->pt", x, np.cross(y, z))
    den = (
        lx * ly * lz
        + np.einsum("ptk,ptk->pt", x, y) * lz
        + np.einsum("ptk,ptk->pt", y, z) * lx
        + np.einsum("ptk,ptk->pt", z, x) * ly
    )
    return (2 * np.arctan2(det, den)).sum(axis=1) / (4 * np.pi)

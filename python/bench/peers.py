"""rt_accel beside the Python tools people use today, on the same triangles, rays and points.

    python python/bench/peers.py [--meshes stanford-bunny.obj,spot.obj,...] [--repeats 3]

For each mesh of ``../shared/meshes`` named (or ``RT_SHARED_MESHES``), each query is timed on
every thread (best of ``--repeats`` runs, the crossing from Python included) and its answers are
compared with rt_accel's:

- primary rays from a camera whose image the mesh fills (the hit share is printed beside the
  speed), scattered rays through the mesh's box, and shadow rays from the primary hits to a
  light;
- closest points and distances, signed distances and the signs themselves, on points half in
  the mesh's box grown by a quarter and half near its surface.

Peers, each where it has the query: Open3D's ``RaycastingScene`` (pip package ``open3d``; its
wheel imports only with Debian's ``libusb-1.0-0``): every query. embreex (Embree 4, as trimesh
uses it; one thread): rays. libigl (``libigl``): closest points, and signed distance by its
fast winding number. point-cloud-utils: closest points, and signed distance by fast winding
numbers. fcpw: closest points (its answers are read out of its list after the timing). A
peer that is not installed is skipped, and the table says so. Ratios are the
peer's time over rt_accel's: above 1, rt_accel is faster. Sign differences are counted against
rt_accel's, which are the exact winding number's.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

import rt_accel


def meshes_dir() -> Path:
    env = os.environ.get("RT_SHARED_MESHES")
    return Path(env) if env else Path(__file__).resolve().parents[2].parent / "shared" / "meshes"


def filled_view(v: np.ndarray, width: int, height: int) -> np.ndarray:
    """Rays from a pinhole camera looking at the mesh from (0.3, 0.4, 1), its image plane
    spanning exactly the mesh's projection, so the mesh fills the image."""
    center = (v.min(0) + v.max(0)) / 2
    radius = float(np.linalg.norm(v - center, axis=1).max())
    back = np.array([0.3, 0.4, 1.0]) / np.linalg.norm([0.3, 0.4, 1.0])
    eye = center + back * 2.5 * radius
    right = np.cross([0.0, 1.0, 0.0], back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    rel = v - eye
    depth = rel @ -back
    x, y = (rel @ right) / depth, (rel @ up) / depth
    xs = np.linspace(x.min(), x.max(), width)
    ys = np.linspace(y.max(), y.min(), height)
    gx, gy = np.meshgrid(xs, ys)
    d = gx[..., None] * right + gy[..., None] * up - back
    o = np.broadcast_to(eye, d.shape)
    return np.concatenate([o, d], axis=-1).reshape(-1, 6).astype(np.float32)


def scattered(v: np.ndarray, n: int, rng) -> np.ndarray:
    lo, hi = v.min(0), v.max(0)
    a = lo + rng.random((n, 3)) * (hi - lo)
    b = lo + rng.random((n, 3)) * (hi - lo)
    return np.hstack([a, b - a]).astype(np.float32)


def points(v: np.ndarray, n: int, rng) -> np.ndarray:
    lo, hi = v.min(0), v.max(0)
    grow = 0.25 * (hi - lo)
    box = lo - grow + rng.random((n // 2, 3)) * (hi - lo + 2 * grow)
    near = v[rng.integers(0, len(v), n - n // 2)] + 0.01 * (hi - lo).max() * rng.normal(size=(n - n // 2, 3))
    return np.vstack([box, near]).astype(np.float32)


def best(f, repeats: int):
    times, out = [], None
    for _ in range(repeats):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return min(times), out


def missed_as(ids: np.ndarray, invalid) -> np.ndarray:
    """Triangle ids as int64 with -1 for a miss, whatever a library's value for one."""
    ids = ids.astype(np.int64)
    return np.where(ids == np.int64(invalid), -1, ids)


def peer_open3d(v, t):
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(t.astype(np.uint32)))
    T = o3d.core.Tensor
    return {
        "cast_rays": lambda r: missed_as(
            scene.cast_rays(T(r))["primitive_ids"].numpy(), o3d.t.geometry.RaycastingScene.INVALID_ID),
        "test_occlusions": lambda r: scene.test_occlusions(T(r), tfar=1.0).numpy().astype(bool),
        "count_intersections": lambda r: scene.count_intersections(T(r)).numpy(),
        "closest_points": lambda p: np.linalg.norm(
            scene.compute_closest_points(T(p))["points"].numpy() - p, axis=1),
        "signed_distance": lambda p: scene.compute_signed_distance(T(p)).numpy(),
    }


def peer_embreex(v, t):
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, v.astype(np.float32), t.astype(np.int32))

    def cast(r):
        out = scene.run(np.ascontiguousarray(r[:, :3]), np.ascontiguousarray(r[:, 3:]), output=1)
        return np.where(out["geomID"] < 0, -1, out["primID"]).astype(np.int64)

    def occluded(r):
        dists = np.ones(len(r), dtype=np.float32)
        hit = scene.run(np.ascontiguousarray(r[:, :3]), np.ascontiguousarray(r[:, 3:]),
                        dists=dists, query="OCCLUDED")
        return np.asarray(hit) >= 0

    return {"cast_rays": cast, "test_occlusions": occluded}


def peer_libigl(v, t):
    import igl

    V, F = v.astype(np.float64), t.astype(np.int64)
    fwn = igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER
    return {
        "closest_points": lambda p: np.sqrt(
            igl.point_mesh_squared_distance(p.astype(np.float64), V, F)[0]),
        "signed_distance": lambda p: igl.signed_distance(p.astype(np.float64), V, F,
                                                         sign_type=fwn)[0],
    }


def peer_pcu(v, t):
    import point_cloud_utils as pcu

    V, F = v.astype(np.float64), t.astype(np.int32)
    return {
        "closest_points": lambda p: pcu.closest_points_on_mesh(p.astype(np.float64), V, F)[0],
        "signed_distance": lambda p: pcu.signed_distance_to_mesh(p.astype(np.float64), V, F)[0],
    }


def peer_fcpw(v, t):
    import fcpw

    scene = fcpw.scene_3D()
    scene.set_object_count(1)
    scene.set_object_vertices(np.asfortranarray(v, dtype=np.float32), 0)
    scene.set_object_triangles(np.asfortranarray(t, dtype=np.int32), 0)
    scene.build(fcpw.aggregate_type.bvh_surface_area, True)

    def closest(p):
        found = fcpw.interaction_3D_list()
        scene.find_closest_points(np.asfortranarray(p, dtype=np.float32),
                                  np.full(len(p), np.inf, dtype=np.float32), found)
        return found

    # Reading the answers out of fcpw's list of objects is a Python loop: done after the timing,
    # so that the time is fcpw's query alone.
    return {"closest_points": (closest, lambda found: np.array([i.d for i in found]))}


PEERS = {"open3d": peer_open3d, "embreex": peer_embreex, "libigl": peer_libigl,
         "point-cloud-utils": peer_pcu, "fcpw": peer_fcpw}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default="stanford-bunny.obj,spot.obj,rocker-arm.obj")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--scattered", type=int, default=1_000_000)
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--signed-points", type=int, default=50_000)
    args = ap.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} threads, "
          f"best of {args.repeats}; ratio = peer time / rt_accel time")
    rng = np.random.default_rng(1)
    for name in args.meshes.split(","):
        v, t = rt_accel.load_mesh(meshes_dir() / name)
        ours = rt_accel.Scene("bvh")
        ours.add_triangles(v, t)
        ours.build()
        primary = filled_view(v, args.width, args.height)
        scatter = scattered(v, args.scattered, rng)
        hits = ours.cast_rays(primary)
        hit = np.isfinite(hits["t_hit"])
        light = v.max(0) + (v.max(0) - v.min(0))
        p = primary[hit, :3] + hits["t_hit"][hit, None] * primary[hit, 3:]
        p = p + 1e-4 * hits["primitive_normals"][hit] * np.sign(
            -(primary[hit, 3:] * hits["primitive_normals"][hit]).sum(1, keepdims=True))
        shadow = np.hstack([p, light - p]).astype(np.float32)
        pts = points(v, args.points, rng)
        spts = pts[: args.signed_points]
        print(f"\n### {name}: {len(t)} triangles; primary {len(primary)} rays, "
              f"{hit.mean():.1%} hit; scattered {len(scatter)} rays, "
              f"{np.isfinite(ours.cast_rays(scatter)['t_hit']).mean():.1%} hit; "
              f"shadow {len(shadow)} rays; {len(pts)} points")
        ids = lambda r: ours.cast_rays(r)["primitive_ids"].astype(np.int64)  # noqa: E731
        miss = np.int64(rt_accel.INVALID_ID)
        rows = [
            ("cast_rays, primary", "cast_rays", primary, lambda: ids(primary)),
            ("cast_rays, scattered", "cast_rays", scatter, lambda: ids(scatter)),
            ("test_occlusions, shadow", "test_occlusions", shadow,
             lambda: ours.test_occlusions(shadow, tfar=1.0)),
            ("count_intersections, primary", "count_intersections", primary,
             lambda: ours.count_intersections(primary)),
            ("closest points", "closest_points", pts, lambda: ours.compute_distance(pts)),
            ("signed distance", "signed_distance", spts,
             lambda: ours.compute_signed_distance(spts)),
        ]
        peers = {}
        for peer, make in PEERS.items():
            try:
                peers[peer] = make(v, t)
            except ImportError as e:
                print(f"\n{peer}: skipped: not installed ({e})")
        print("\n| query | rt_accel s | peer | peer s | ratio | answers |")
        print("| --- | ---: | --- | ---: | ---: | --- |")
        for label, query, data, a in rows:
            ta, ra = best(a, args.repeats)
            if query == "cast_rays":
                ra = missed_as(ra, miss)
            for peer, queries in peers.items():
                if query not in queries:
                    continue
                run, post = queries[query] if isinstance(queries[query], tuple) else (
                    queries[query], lambda answer: answer)
                tb, rb = best(lambda: run(data), args.repeats)
                rb = post(rb)
                if query == "cast_rays":
                    note = f"same triangle on {np.mean(ra == rb):.4%}"
                elif query in ("test_occlusions", "count_intersections"):
                    note = f"same answer on {np.mean(ra == rb):.4%}"
                elif query == "closest_points":
                    d = np.abs(ra - rb)
                    note = f"distances within 1e-5: {np.mean(d <= 1e-5 * (1 + np.abs(data).max())):.4%}"
                else:
                    wrong = int(np.sum((ra < 0) != (rb < 0)))
                    note = f"signs differ on {wrong} of {len(data)} points"
                print(f"| {label} | {ta:.4f} | {peer} | {tb:.4f} | {tb / ta:.2f} | {note} |")


if __name__ == "__main__":
    main()

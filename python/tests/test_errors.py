"""Bad input raises an exception that names the problem, and nothing else happens."""

from __future__ import annotations

import numpy as np
import pytest

import rt_accel
from conftest import SCENES, scene_of, shared_meshes


@pytest.fixture
def scene():
    return scene_of("bvh", SCENES["cube"]())


def test_unknown_structure_and_preset():
    with pytest.raises(ValueError, match=r'unknown structure "bhv": one of bvh, kdtree'):
        rt_accel.Scene("bhv")
    with pytest.raises(ValueError, match=r'unknown preset "fast" for structure "grid": one of standard'):
        rt_accel.Scene("grid", "fast")
    with pytest.raises(ValueError, match="unknown structure"):
        rt_accel.presets("tree")


def test_wrong_shapes(scene):
    with pytest.raises(ValueError, match=r"rays must have shape \(\.\.\., 6\); got \(4, 3\)"):
        scene.cast_rays(np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"query_points must have shape \(\.\.\., 3\)"):
        scene.compute_distance(np.zeros((4, 6)))
    with pytest.raises(ValueError, match=r"triangle_indices must have shape \(m, 3\)"):
        scene.add_triangles(np.zeros((3, 3)), np.zeros((2, 4), dtype=np.int32))
    with pytest.raises(ValueError, match=r"vertex_positions must have shape \(\.\.\., 3\)"):
        scene.add_triangles(np.zeros((3, 2)), np.zeros((1, 3), dtype=np.int32))


def test_wrong_dtypes(scene):
    with pytest.raises(TypeError, match="rays must hold numbers"):
        scene.cast_rays(np.array([["a"] * 6]))
    with pytest.raises(TypeError, match="triangle_indices must have an integer dtype"):
        scene.add_triangles(np.zeros((3, 3)), np.zeros((1, 3), dtype=np.float32))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_rays_and_points_name_the_element(scene, bad):
    rays = np.tile([0.5, 0.5, 3, 0, 0, -1], (2, 3, 1)).astype(np.float32)
    rays[1, 2, 4] = bad
    with pytest.raises(ValueError, match=r"rays\[1, 2\] has a non-finite coordinate"):
        scene.cast_rays(rays)
    with pytest.raises(ValueError, match=r"rays\[1, 2\] has a non-finite coordinate"):
        scene.test_occlusions(rays)
    with pytest.raises(ValueError, match=r"rays\[1, 2\] has a non-finite coordinate"):
        scene.count_intersections(rays)
    points = np.zeros((4, 3))
    points[3, 0] = bad
    for query in (
        scene.compute_closest_points,
        scene.compute_distance,
        scene.compute_signed_distance,
        scene.compute_occupancy,
        scene.winding_number,
    ):
        with pytest.raises(ValueError, match=r"query_points\[3\] has a non-finite coordinate"):
            query(points)


def test_rays_out_of_range(scene):
    with pytest.raises(ValueError, match=r"rays\[0\] has a zero direction"):
        scene.cast_rays(np.array([[0, 0, 0, 0, 0, 0]]))
    with pytest.raises(ValueError, match=r"rays\[1\] has an origin coordinate beyond 2\*\*40"):
        scene.cast_rays(np.array([[0, 0, 0, 0, 0, 1], [1e13, 0, 0, 0, 0, 1]]))
    with pytest.raises(ValueError, match=r"direction component beyond 2\*\*40"):
        scene.cast_rays(np.array([[0, 0, 0, 0, 0, 1e13]]))
    with pytest.raises(ValueError, match="0 <= tnear <= tfar"):
        scene.test_occlusions(np.array([[0, 0, 0, 0, 0, 1]]), tnear=2.0, tfar=1.0)
    with pytest.raises(ValueError, match="0 <= tnear <= tfar"):
        scene.test_occlusions(np.array([[0, 0, 0, 0, 0, 1]]), tnear=np.nan)
    with pytest.raises(ValueError, match="nsamples must be positive"):
        scene.compute_signed_distance(np.zeros((1, 3)), nsamples=0)
    with pytest.raises(ValueError, match="nthreads must be 0"):
        scene.cast_rays(np.array([[0, 0, 0, 0, 0, 1]]), nthreads=-1)


def test_bad_meshes():
    scene = rt_accel.Scene()
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
    with pytest.raises(ValueError, match=r"triangle_indices\[1\] refers to vertex 3, but there are 3 vertices"):
        scene.add_triangles(v, np.array([[0, 1, 2], [0, 1, 3]]))
    with pytest.raises(ValueError, match=r"triangle_indices\[0\] has a negative index: \[0, -1, 2\]"):
        scene.add_triangles(v, np.array([[0, -1, 2]]))
    with pytest.raises(ValueError, match=r"refers to vertex 4294967296"):
        scene.add_triangles(v, np.array([[0, 1, 2**32]], dtype=np.int64))
    with pytest.raises(ValueError, match="the mesh has no triangles"):
        scene.add_triangles(v, np.zeros((0, 3), dtype=np.int32))
    bad = v.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"vertex_positions\[2\] \(used by triangle 0\) has a non-finite"):
        scene.add_triangles(bad, np.array([[0, 1, 2]]))
    # An unused non-finite vertex is harmless.
    extra = np.vstack([v, [[np.inf, 0, 0]]]).astype(np.float32)
    assert scene.add_triangles(extra, np.array([[0, 1, 2]])) == 0
    # The failed calls added nothing.
    assert scene._native.triangle_count() == 1


def test_queries_on_an_empty_scene():
    scene = rt_accel.Scene("kdtree")
    with pytest.raises(ValueError, match="the scene has no triangles: add a mesh"):
        scene.cast_rays(np.array([[0, 0, 0, 0, 0, 1]]))
    with pytest.raises(ValueError, match="the scene has no triangles"):
        scene.compute_signed_distance(np.zeros((1, 3)))


def test_missing_and_broken_mesh_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere.obj"):
        rt_accel.load_mesh(tmp_path / "nowhere.obj")
    with pytest.raises(ValueError, match="unknown"):
        (tmp_path / "mesh.xyz").write_text("1 2 3\n")
        rt_accel.load_mesh(tmp_path / "mesh.xyz")
    broken = tmp_path / "broken.obj"
    broken.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    with pytest.raises(ValueError, match=r"broken.obj:4: vertex index 7 out of range"):
        rt_accel.load_mesh(broken)


def test_every_broken_shared_mesh_loads_or_raises():
    """Each file of the shared meshes' bad/ folder gives a valid mesh or an exception naming
    the file; the broken ones name the line too."""
    bad = shared_meshes() / "bad"
    read = 0
    for path in sorted(bad.iterdir()):
        try:
            v, t = rt_accel.load_mesh(path)
        except (ValueError, OSError) as e:
            assert str(path) in str(e)
        else:
            assert len(t) > 0 and np.isfinite(v).all() and t.max() < len(v)
        read += 1
    assert read >= 10, f"only {read} files in {bad}"
    with pytest.raises(ValueError, match=r"malformed.obj:23: vertex index 12 out of range"):
        rt_accel.load_mesh(bad / "malformed.obj")

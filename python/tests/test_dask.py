"""Queries spread over Dask worker processes answer exactly as the scene does here."""

from __future__ import annotations

import numpy as np
import pytest
import dask.array as da
from dask.distributed import Client, LocalCluster

import rt_accel
from conftest import cube


@pytest.fixture(scope="module")
def client():
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            yield client


def cast(block, scene):
    return scene.cast_rays(block)["t_hit"]


def signed(block, scene):
    return scene.compute_signed_distance(block)


@pytest.mark.parametrize("structure", ["bvh", "kdtree", "grid"])
def test_blocks_on_workers_answer_as_here(client, structure):
    v, t = cube()
    scene = rt_accel.Scene(structure)
    scene.add_triangles(v, t)
    scene.build()
    rng = np.random.default_rng(4)
    points = (rng.random((4000, 3)) * 3 - 1).astype(np.float32)
    rays = np.hstack([points, rng.normal(size=(4000, 3))]).astype(np.float32)
    remote = client.scatter(scene, broadcast=True)
    sdf = da.from_array(points, chunks=(1000, 3)).map_blocks(
        signed, remote, drop_axis=1, dtype=np.float32).compute()
    hits = da.from_array(rays, chunks=(1000, 6)).map_blocks(
        cast, remote, drop_axis=1, dtype=np.float32).compute()
    assert np.array_equal(sdf, scene.compute_signed_distance(points))
    assert np.array_equal(hits, scene.cast_rays(rays)["t_hit"])
    # Both signs and both hits and misses occur, so the comparison means something.
    assert (sdf < 0).any() and (sdf > 0).any()
    assert np.isfinite(hits).any() and np.isinf(hits).any()
    # The workers are processes of their own.
    ran = client.run(lambda: __import__("os").getpid())
    assert len(ran) == 2 and __import__("os").getpid() not in ran.values()

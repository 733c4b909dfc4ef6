"""Threads: the same answers on one thread as on all, and the GIL released during a query."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from conftest import STRUCTURES, points_for, rays_for, scene_of, soup


@pytest.mark.parametrize("structure", STRUCTURES)
def test_one_thread_answers_as_all(structure):
    v, t = soup(400, seed=4)
    scene = scene_of(structure, (v, t))
    rays, points = rays_for(v, n=3000), points_for(v, n=2000)
    for nthreads in (1, 3):
        a, b = scene.cast_rays(rays, nthreads=nthreads), scene.cast_rays(rays)
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])
        np.testing.assert_array_equal(
            scene.count_intersections(rays, nthreads=nthreads), scene.count_intersections(rays)
        )
        np.testing.assert_array_equal(
            scene.compute_signed_distance(points, nthreads=nthreads),
            scene.compute_signed_distance(points),
        )


def test_the_gil_is_released_during_a_query():
    """While one Python thread runs a long query, another keeps running Python code."""
    v, t = soup(3000, seed=6)
    scene = scene_of("brute", (v, t))
    rays = rays_for(v, n=20000)
    scene.build()
    ticks = []
    done = threading.Event()

    def query():
        scene.cast_rays(rays, nthreads=1)
        done.set()

    worker = threading.Thread(target=query)
    start = time.perf_counter()
    worker.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    elapsed = time.perf_counter() - start
    assert elapsed > 0.05, "the query was too short to show anything"
    # With the GIL held for the whole query, this loop could not run until it ended.
    assert len(ticks) > 10 and ticks[-1] - ticks[0] > 0.5 * elapsed

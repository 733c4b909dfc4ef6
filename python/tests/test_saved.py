"""Saved scenes and pickling: the same answers after a round trip, and damaged bytes refused."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import rt_accel
from conftest import SCENES, STRUCTURES, points_for, rays_for, scene_of, soup


def answers(scene, rays, points):
    hits = scene.cast_rays(rays)
    return [hits[k] for k in sorted(hits)] + [
        scene.count_intersections(rays),
        scene.compute_signed_distance(points),
        scene.compute_closest_points(points)["primitive_ids"],
    ]


@pytest.mark.parametrize("structure", STRUCTURES + ["brute"])
def test_round_trips_answer_bit_for_bit(structure, tmp_path):
    meshes = [SCENES["cube"](), soup(80, seed=8)]
    scene = scene_of(structure, *meshes)
    v = np.vstack([m[0] for m in meshes])
    rays, points = rays_for(v, n=500), points_for(v, n=300)
    want = answers(scene, rays, points)
    scene.save(tmp_path / "scene.rtp")
    for copy in (
        rt_accel.Scene.load(tmp_path / "scene.rtp"),
        pickle.loads(pickle.dumps(scene)),
        rt_accel.Scene.from_bytes(scene.to_bytes()),
    ):
        assert (copy.structure, copy.preset) == (scene.structure, scene.preset)
        for a, b in zip(answers(copy, rays, points), want):
            np.testing.assert_array_equal(a, b)
    # A loaded scene takes more meshes and rebuilds with the same preset.
    loaded = rt_accel.Scene.from_bytes(scene.to_bytes())
    assert loaded.add_triangles(*SCENES["plane_grid"]()) == 2


def test_a_preset_survives_the_round_trip():
    scene = scene_of("kdtree", SCENES["cube"](), preset="restart")
    assert pickle.loads(pickle.dumps(scene)).preset == "restart"


def test_damaged_bytes_are_refused(tmp_path):
    data = bytearray(scene_of("bvh", SCENES["cube"]()).to_bytes())
    with pytest.raises(ValueError, match="not a valid saved scene"):
        rt_accel.Scene.from_bytes(b"hello")
    with pytest.raises(ValueError, match="not a valid saved scene"):
        rt_accel.Scene.from_bytes(bytes(data[: len(data) // 2]))
    # Every byte flipped in turn (a sample of positions): refused or, where the byte is not
    # checked (none should be), answering as before; never a crash.
    refused = 0
    for i in range(0, len(data), max(1, len(data) // 97)):
        bad = bytearray(data)
        bad[i] ^= 0x5A
        try:
            rt_accel.Scene.from_bytes(bytes(bad))
        except ValueError:
            refused += 1
    assert refused == len(range(0, len(data), max(1, len(data) // 97)))
    path = tmp_path / "bad.rtp"
    path.write_bytes(b"\0" * 200)
    with pytest.raises(ValueError, match="bad.rtp: not a valid saved scene"):
        rt_accel.Scene.load(path)
    with pytest.raises(FileNotFoundError):
        rt_accel.Scene.load(tmp_path / "missing.rtp")

"""Build parameters by keyword: every parameter of every structure, at the ends of its range,
builds a structure that answers as brute force does; values out of range or of the wrong kind
raise; a saved scene keeps them."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import rt_accel
from conftest import SCENES, points_for, rays_for

# Each structure's parameters with values at the ends of their ranges (and every choice).
EXTREMES = {
    "bvh": {
        "layout": ["wide", "binary"],
        "split": ["sah", "median", "middle"],
        "bins": [2, 32],
        "traversal_cost": [1e-6, 1e6],
        "intersection_cost": [1e-6, 1e6],
        "max_leaf_size": [1, 255],
        "reinsertion_passes": [0, 100],
        "parallel": [False, True],
    },
    "kdtree": {
        "traversal_cost": [1e-6, 1e6],
        "intersection_cost": [1e-6, 1e6],
        "empty_bonus": [0.0, 1.0],
        "perfect_splits": [False, True],
        "empty_cut": [0.0, 1.0],
        "max_depth": [None, 1, 64],
        "depth_base": [0.0, 64.0],
        "max_bad_refines": [0, 64],
        "leaf_size": [0, 1 << 20],
        "parallel": [False, True],
        "traversal": ["stack", "restart"],
    },
    "grid": {
        "density": [1e-6, 64],
        "max_cells": [1, 1 << 28],
        "exact_insertion": [False, True],
        "mailbox": [False, True],
        "parallel": [False, True],
    },
    "hgrid": {
        "top_density": [1e-6, 64.0],
        "density": [1e-6, 64.0],
        "split_min": [1, 1 << 20],
        "max_levels": [1, 4],
        "max_cells": [1, 1 << 28],
        "mailbox": [False, True],
        "parallel": [False, True],
    },
    "octree": {
        "max_prims": [1, 1 << 20],
        "max_depth": [0, 20],
        "max_refs_per_prim": [1.0, 1024.0],
        "mailbox": [False, True],
        "parallel": [False, True],
    },
}


def scene(structure, v, t, **params):
    s = rt_accel.Scene(structure, **params)
    s.add_triangles(v, t)
    return s


@pytest.mark.parametrize("structure", sorted(EXTREMES))
def test_every_parameter_at_its_extremes_answers_as_brute_force(structure):
    v, t = SCENES["soup"](n=120)
    rays, points = rays_for(v, n=200), points_for(v, n=100)
    brute = scene("brute", v, t)
    want_ids = brute.cast_rays(rays)["primitive_ids"]
    want_d = brute.compute_distance(points)
    assert (want_ids != rt_accel.INVALID_ID).any() and (want_ids == rt_accel.INVALID_ID).any()
    for key, values in EXTREMES[structure].items():
        for value in values:
            s = scene(structure, v, t, **{key: value})
            assert s.params == {key: value}
            got = s.cast_rays(rays)["primitive_ids"]
            np.testing.assert_array_equal(got, want_ids, err_msg=f"{structure} {key}={value}")
            np.testing.assert_allclose(s.compute_distance(points), want_d, rtol=1e-6)


def test_the_ranges_are_the_documented_ones():
    """Every parameter the structures take is in EXTREMES, so the test above covers them: an
    unknown one names the known ones."""
    for structure, params in EXTREMES.items():
        with pytest.raises(ValueError, match='unknown parameter "speed"') as e:
            rt_accel.Scene(structure, speed=1)
        assert str(e.value).split(": one of ")[1].split(", ") == list(params)


@pytest.mark.parametrize(
    "structure, params, error, message",
    [
        ("bvh", {"bins": 1}, ValueError, r"bins = 1 is outside \[2, 32\]"),
        ("bvh", {"bins": 2.5}, TypeError, "bins: expected an integer, not 2.5"),
        ("bvh", {"max_leaf_size": 10**30}, ValueError, "max_leaf_size"),
        ("bvh", {"traversal_cost": 0}, ValueError, r"traversal_cost = 0 is outside \(0, 1000000\]"),
        ("bvh", {"traversal_cost": float("nan")}, ValueError, "traversal_cost = NaN"),
        ("bvh", {"intersection_cost": float("inf")}, ValueError, "intersection_cost = inf"),
        ("bvh", {"split": "best"}, ValueError, 'split = "best": one of sah, median, middle'),
        ("bvh", {"layout": 8}, TypeError, "layout: expected one of wide, binary, not 8"),
        ("bvh", {"parallel": 1}, TypeError, "parallel: expected a bool, not 1"),
        ("kdtree", {"max_depth": True}, TypeError, "max_depth: expected an integer, not True"),
        ("grid", {"density": "dense"}, TypeError, "density: expected a number, not \"dense\""),
        ("bvh", {"bins": [4]}, TypeError, "bins: expected a number, a bool or a name, not list"),
        ("kdtree", {"empty_bonus": 1.5}, ValueError, r"empty_bonus = 1.5 is outside \[0"),
        ("kdtree", {"max_depth": 65}, ValueError, "max_depth = 65"),
        ("grid", {"density": -1}, ValueError, r"density = -1 is outside \(0, 64\]"),
        ("grid", {"max_cells": 1 << 40}, ValueError, "max_cells"),
        ("hgrid", {"max_levels": 5}, ValueError, r"max_levels = 5 is outside \[1, 4\]"),
        ("octree", {"max_depth": 21}, ValueError, r"max_depth = 21 is outside \[0, 20\]"),
        ("brute", {"bins": 4}, ValueError, "brute force takes none"),
    ],
)
def test_bad_values_raise(structure, params, error, message):
    with pytest.raises(error, match=message):
        rt_accel.Scene(structure, **params)


def test_a_saved_scene_keeps_its_parameters():
    v, t = SCENES["cube"]()
    s = scene("kdtree", v, t, preset="restart", max_depth=None, empty_bonus=0.25, leaf_size=3)
    copy = pickle.loads(pickle.dumps(s))
    assert (copy.structure, copy.preset) == ("kdtree", "restart")
    assert copy.params == {"empty_bonus": 0.25, "leaf_size": 3, "max_depth": None}
    assert "empty_bonus=0.25" in repr(copy)
    # Rebuilt after another mesh, with the same parameters.
    copy.add_triangles(v + 2, t)
    brute = scene("brute", v, t)
    brute.add_triangles(v + 2, t)
    rays = rays_for(np.vstack([v, v + 2]), n=200)
    got, want = copy.cast_rays(rays), brute.cast_rays(rays)
    for key in ("geometry_ids", "primitive_ids"):
        np.testing.assert_array_equal(got[key], want[key])
    assert (want["geometry_ids"] == 1).any()
    bvh = pickle.loads(pickle.dumps(scene("bvh", v, t, layout="binary", traversal_cost=0.5)))
    assert bvh.params == {"layout": "binary", "traversal_cost": 0.5}

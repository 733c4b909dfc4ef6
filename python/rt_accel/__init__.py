"""Exact ray casting, closest points and signed distance on triangle meshes, from numpy.

``rt_accel`` puts the structures of the rt-accel Rust crates behind one class, :class:`Scene`,
whose queries take the names, arguments, shapes, dtypes and result keys of Open3D's
``open3d.t.geometry.RaycastingScene``: code written for Open3D changes the line that makes the
scene. Every answer is exact in the sense the Rust crates promise: each structure returns what
brute force returns (the closest triangle, ties broken by the smaller ``t`` and then the smaller
id), and signs come from the generalised winding number, which is right on closed meshes and
well defined on meshes with holes.

Every query releases the GIL and runs on all cores unless ``nthreads`` says otherwise.

>>> import numpy as np, rt_accel
>>> scene = rt_accel.Scene()
>>> vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
>>> scene.add_triangles(vertices, np.array([[0, 1, 2]], dtype=np.uint32))
0
>>> hits = scene.cast_rays(np.array([[0.2, 0.2, 1, 0, 0, -1]], dtype=np.float32))
>>> float(hits["t_hit"][0]), int(hits["primitive_ids"][0])
(1.0, 0)
"""

from __future__ import annotations

import math
from typing import Dict, List, Optional, Tuple, Union

import numpy as np

from . import _native

__all__ = ["Scene", "INVALID_ID", "STRUCTURES", "load_mesh", "presets"]

#: The id of "no geometry" and "no primitive" in query results, as Open3D's
#: ``RaycastingScene.INVALID_ID``.
INVALID_ID: int = _native.INVALID_ID

#: The structures a :class:`Scene` can use. ``"brute"`` tests every triangle: the reference.
STRUCTURES: Tuple[str, ...] = ("bvh", "kdtree", "grid", "hgrid", "octree", "brute")


def presets(structure: str) -> List[str]:
    """The preset names of ``structure``; the first is its default.

    >>> presets("kdtree")[0]
    'sah'
    """
    return list(_native.presets(structure))


def load_mesh(path) -> Tuple[np.ndarray, np.ndarray]:
    """Reads an OBJ, PLY or glTF (``.gltf``, ``.glb``) file, chosen by its extension.

    Returns ``(vertex_positions, triangle_indices)``: float32 ``(n, 3)`` and uint32 ``(m, 3)``,
    ready for :meth:`Scene.add_triangles`. Polygons are split into triangles and every mesh of
    the file is merged into one.

    Raises
    ------
    FileNotFoundError
        When the file does not exist.
    OSError
        When it cannot be read.
    ValueError
        When it is not a valid mesh (a syntax error, an index out of range, a non-finite
        coordinate, no triangles, an unknown extension): the message names the file and the
        line or element.
    """
    return _native.load_mesh(str(path))


def _rows(array, width: int, name: str) -> Tuple[np.ndarray, Tuple[int, ...]]:
    """``array`` as C-contiguous float32 rows of ``width``, and its leading shape."""
    a = np.asarray(array)
    if a.dtype.kind not in "fiu":
        raise TypeError(f"{name} must hold numbers, not {a.dtype}")
    if a.ndim < 1 or a.shape[-1] != width:
        raise ValueError(f"{name} must have shape (..., {width}); got {a.shape}")
    lead = a.shape[:-1]
    rows = np.ascontiguousarray(a.reshape(-1, width), dtype=np.float32)
    return rows, lead


def _nthreads(nthreads: int) -> int:
    n = int(nthreads)
    if n < 0:
        raise ValueError(f"nthreads must be 0 (every core) or positive; got {nthreads}")
    return n


def _nsamples(nsamples: int) -> None:
    if int(nsamples) < 1:
        raise ValueError(f"nsamples must be positive; got {nsamples}")


class Scene:
    """Triangle meshes and one acceleration structure over them.

    Parameters
    ----------
    structure:
        ``"bvh"`` (the default: an 8-wide bounding volume hierarchy with SIMD kernels),
        ``"kdtree"``, ``"grid"``, ``"hgrid"`` (hierarchical grid), ``"octree"`` or ``"brute"``
        (no structure: every triangle tested, the reference). All give the same answers.
    preset:
        One of :func:`presets` ``(structure)``; ``None`` is the structure's default.
    **params:
        Build parameters set over the preset's, by the names of the structure's Rust
        parameters (``rt_bvh::BvhParams`` and so on), each checked: a value out of range
        raises ``ValueError`` naming the range, one of the wrong kind ``TypeError``.

        - ``"bvh"``: ``layout`` (``"wide"``, ``"binary"``), ``split`` (``"sah"``,
          ``"median"``, ``"middle"``), ``bins`` (2 to 32), ``traversal_cost`` and
          ``intersection_cost`` (above 0), ``max_leaf_size`` (1 to 255),
          ``reinsertion_passes`` (0 to 100), ``parallel``.
        - ``"kdtree"``: ``traversal_cost``, ``intersection_cost``, ``empty_bonus`` and
          ``empty_cut`` (0 to 1), ``perfect_splits``, ``max_depth`` (1 to 64, or ``None`` for
          the automatic limit), ``depth_base`` (0 to 64), ``max_bad_refines`` (0 to 64),
          ``leaf_size``, ``parallel``, ``traversal`` (``"stack"``, ``"restart"``).
        - ``"grid"``: ``density`` (cells per triangle, above 0 to 64), ``max_cells`` (1 to
          2**28), ``exact_insertion``, ``mailbox``, ``parallel``.
        - ``"hgrid"``: ``top_density``, ``density``, ``split_min``, ``max_levels`` (1 to 4),
          ``max_cells``, ``mailbox``, ``parallel``.
        - ``"octree"``: ``max_prims``, ``max_depth`` (0 to 20), ``max_refs_per_prim`` (1 to
          1024), ``mailbox``, ``parallel``.

        Every setting gives the same answers; they change speed and memory. A saved scene
        keeps them.

    The structure is built on the first query after meshes are added, as Open3D's
    ``RaycastingScene`` does, or when :meth:`build` is called. ``structure``, ``preset`` and
    ``params`` (a dict of the parameters given) say what it is.
    """

    def __init__(
        self,
        structure: str = "bvh",
        preset: Optional[str] = None,
        **params: Union[bool, int, float, str, None],
    ) -> None:
        self._native = _native.NativeScene(structure, preset, params)
        self.structure, self.preset, self.params = self._native.describe()

    @classmethod
    def _of(cls, native) -> "Scene":
        scene = cls.__new__(cls)
        scene._native = native
        scene.structure, scene.preset, scene.params = native.describe()
        return scene

    def to_bytes(self) -> bytes:
        """The scene as bytes: its meshes and its built structure (built now if need be).

        :meth:`from_bytes` reads them back without rebuilding anything; pickling goes through
        these bytes, so a scene crosses to worker processes (``multiprocessing``, Dask) built.
        """
        return self._native.save()

    @classmethod
    def from_bytes(cls, data: bytes) -> "Scene":
        """The scene :meth:`to_bytes` wrote, checked (framing, checksum, every triangle and
        the structure's invariants) and ready to query.

        Raises
        ------
        ValueError
            When ``data`` is not a saved scene, was written by another version, or is damaged:
            the message says what is wrong.
        """
        return cls._of(_native.NativeScene.load(bytes(data)))

    def save(self, path) -> None:
        """Writes :meth:`to_bytes` to the file ``path``."""
        data = self.to_bytes()
        with open(path, "wb") as f:
            f.write(data)

    @classmethod
    def load(cls, path) -> "Scene":
        """The scene saved in the file ``path`` (see :meth:`from_bytes`).

        Raises
        ------
        FileNotFoundError, OSError
            When the file cannot be read.
        ValueError
            When it is not a valid saved scene; the message names the file.
        """
        with open(path, "rb") as f:
            data = f.read()
        try:
            return cls.from_bytes(data)
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None

    def __reduce__(self):
        return (Scene.from_bytes, (self.to_bytes(),))

    def __repr__(self) -> str:
        params = "".join(f", {k}={v!r}" for k, v in self.params.items())
        return (
            f"rt_accel.Scene(structure={self.structure!r}, preset={self.preset!r}{params}) "
            f"with {self._native.geometry_count()} geometries, "
            f"{self._native.triangle_count()} triangles"
        )

    def add_triangles(self, vertex_positions, triangle_indices) -> int:
        """Adds a triangle mesh and returns its geometry id (0, 1, ... in the order added).

        Parameters
        ----------
        vertex_positions:
            ``(n, 3)`` array of vertex coordinates (any float or integer dtype; computed in
            float32). A vertex used by a triangle must be finite.
        triangle_indices:
            ``(m, 3)`` array of vertex indices, of an integer dtype, each in ``0 .. n-1``.
            ``m`` must be at least 1. Degenerate (zero-area) triangles are kept: no ray hits
            them, but a closest point may lie on one.

        Raises
        ------
        ValueError
            On a wrong shape, an index out of range or negative, a non-finite vertex used by a
            triangle, or an empty mesh; the message names the element. ``TypeError`` on a
            non-integer ``triangle_indices``.
        """
        vertices, _ = _rows(vertex_positions, 3, "vertex_positions")
        t = np.asarray(triangle_indices)
        if t.dtype.kind not in "iu":
            raise TypeError(f"triangle_indices must have an integer dtype, not {t.dtype}")
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"triangle_indices must have shape (m, 3); got {t.shape}")
        if vertices.shape[0] == 0 and t.shape[0] > 0:
            raise ValueError("vertex_positions is empty but triangle_indices is not")
        if t.size and t.dtype.kind == "i" and t.min() < 0:
            k = int(np.argwhere(t < 0)[0][0])
            raise ValueError(f"triangle_indices[{k}] has a negative index: {t[k].tolist()}")
        if t.size and t.max() > np.iinfo(np.uint32).max:
            k = int(np.argwhere(t > np.iinfo(np.uint32).max)[0][0])
            raise ValueError(
                f"triangle_indices[{k}] refers to vertex {int(t[k].max())}, "
                f"but there are {vertices.shape[0]} vertices"
            )
        triangles = np.ascontiguousarray(t, dtype=np.uint32)
        return int(self._native.add_triangles(vertices, triangles))

    def build(self) -> None:
        """Builds the structure now (the first query would otherwise), with the GIL released."""
        self._native.build()

    def cast_rays(self, rays, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """The closest hit of each ray.

        Parameters
        ----------
        rays:
            ``(..., 6)`` array: origin ``x, y, z`` then direction ``x, y, z``. The direction
            need not be unit length: ``t_hit`` is measured in its units. Hits at ``t >= 0``
            count.
        nthreads:
            Threads to use; 0 uses every core.

        Returns
        -------
        dict
            ``t_hit`` float32 ``(...)``, ``inf`` where the ray hits nothing; ``geometry_ids``
            and ``primitive_ids`` uint32 ``(...)``, :data:`INVALID_ID` on a miss;
            ``primitive_uvs`` float32 ``(..., 2)``, the hit point's weights of the triangle's
            second and third vertices; ``primitive_normals`` float32 ``(..., 3)``, the unit
            normal ``(v1 - v0) x (v2 - v0)`` of the triangle hit (zeros on a miss).

        Raises
        ------
        ValueError
            When ``rays`` is not ``(..., 6)``, or a ray has a non-finite coordinate or a zero
            direction (the message gives its index).
        """
        rows, lead = _rows(rays, 6, "rays")
        t, g, p, uv, n = self._native.cast_rays(rows, list(lead), _nthreads(nthreads))
        return {
            "t_hit": t.reshape(lead),
            "geometry_ids": g.reshape(lead),
            "primitive_ids": p.reshape(lead),
            "primitive_uvs": uv.reshape(lead + (2,)),
            "primitive_normals": n.reshape(lead + (3,)),
        }

    def test_occlusions(
        self, rays, tnear: float = 0.0, tfar: float = math.inf, nthreads: int = 0
    ) -> np.ndarray:
        """Whether each ray hits anything with ``tnear <= t <= tfar``: bool ``(...)``.

        ``rays`` and ``nthreads`` are as for :meth:`cast_rays`. The walk stops at the first
        triangle found, so this is faster than :meth:`cast_rays` (shadow rays).
        """
        rows, lead = _rows(rays, 6, "rays")
        out = self._native.test_occlusions(
            rows, list(lead), float(tnear), float(tfar), _nthreads(nthreads)
        )
        return out.reshape(lead)

    def count_intersections(self, rays, nthreads: int = 0) -> np.ndarray:
        """How many triangles each ray crosses at ``t >= 0``, each once: int32 ``(...)``.

        A ray through an edge or a vertex shared by several triangles counts each of them
        whose watertight test it passes. ``rays`` and ``nthreads`` are as for
        :meth:`cast_rays`.
        """
        rows, lead = _rows(rays, 6, "rays")
        return self._native.count_intersections(rows, list(lead), _nthreads(nthreads)).reshape(
            lead
        )

    def list_intersections(self, rays, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """Every triangle each ray crosses at ``t >= 0``, each once, in order of ``t`` (ties
        by geometry, then primitive id).

        The answer is ragged: the hits of ray ``i`` (in the flattened order of the leading
        shape) are ``ray_splits[i]:ray_splits[i + 1]`` of the other arrays.

        Returns
        -------
        dict
            ``ray_splits`` uint32 ``(n + 1,)``; ``ray_ids``, ``geometry_ids`` and
            ``primitive_ids`` uint32 ``(k,)``; ``t_hit`` float32 ``(k,)``; ``primitive_uvs``
            float32 ``(k, 2)``, for ``n`` rays with ``k`` hits in all.
        """
        rows, lead = _rows(rays, 6, "rays")
        splits, ray, t, g, p, uv = self._native.list_intersections(
            rows, list(lead), _nthreads(nthreads)
        )
        return {
            "ray_splits": splits,
            "ray_ids": ray,
            "geometry_ids": g,
            "primitive_ids": p,
            "primitive_uvs": uv.reshape(-1, 2),
            "t_hit": t,
        }

    def overlapping(self, boxes, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """Every triangle that meets each closed axis-aligned box (not only its bounding box),
        in ascending order of geometry and primitive id.

        Parameters
        ----------
        boxes:
            ``(..., 6)`` array of ``min x, y, z, max x, y, z``, or ``(..., 2, 3)`` of the two
            corners; finite, with ``min <= max``.

        Returns
        -------
        dict
            ``box_splits`` uint32 ``(n + 1,)``; ``geometry_ids`` and ``primitive_ids`` uint32
            ``(k,)``: the triangles meeting box ``i`` are ``box_splits[i]:box_splits[i + 1]``.
        """
        b = np.asarray(boxes)
        if b.ndim >= 2 and b.shape[-2:] == (2, 3):
            b = b.reshape(b.shape[:-2] + (6,))
        rows, lead = _rows(b, 6, "boxes")
        splits, g, p = self._native.overlapping(rows, list(lead), _nthreads(nthreads))
        return {"box_splits": splits, "geometry_ids": g, "primitive_ids": p}

    def _closest(self, query_points, signed: bool, nthreads: int):
        rows, lead = _rows(query_points, 3, "query_points")
        out = self._native.closest_points(rows, list(lead), signed, _nthreads(nthreads))
        return out, lead

    def compute_closest_points(self, query_points, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """The nearest point of the scene to each query point.

        Parameters
        ----------
        query_points:
            ``(..., 3)`` array of finite points.
        nthreads:
            Threads to use; 0 uses every core.

        Returns
        -------
        dict
            ``points`` float32 ``(..., 3)``; ``geometry_ids`` and ``primitive_ids`` uint32
            ``(...)`` of the nearest triangle (ties to the smaller id); ``primitive_uvs``
            float32 ``(..., 2)``, the point's weights of the triangle's second and third
            vertices; ``primitive_normals`` float32 ``(..., 3)``, that triangle's unit normal.
        """
        (pts, g, p, uv, n, _, _), lead = self._closest(query_points, False, nthreads)
        return {
            "points": pts.reshape(lead + (3,)),
            "geometry_ids": g.reshape(lead),
            "primitive_ids": p.reshape(lead),
            "primitive_uvs": uv.reshape(lead + (2,)),
            "primitive_normals": n.reshape(lead + (3,)),
        }

    def compute_distance(self, query_points, nthreads: int = 0) -> np.ndarray:
        """The distance from each point to the scene: float32 ``(...)``."""
        (_, _, _, _, _, d, _), lead = self._closest(query_points, False, nthreads)
        return d.reshape(lead)

    def compute_signed_distance(
        self, query_points, nthreads: int = 0, nsamples: int = 1
    ) -> np.ndarray:
        """The distance from each point to the scene, negative inside: float32 ``(...)``.

        Inside means a generalised winding number of the scene's triangles above one half
        (Jacobson et al. 2013), counted exactly by the crossings of one ray with the mesh and
        caps over its holes (less the caps' own winding number), and where no ray can be
        counted, computed by Barill et al.'s fast expansion where its error bound decides the
        side and exactly where it does not. On a closed, consistently oriented mesh
        that is the mesh's inside; on a mesh with holes it is still well defined, where Open3D's
        sign (the parity of one ray's crossings) depends on where that ray leaves.

        ``nsamples`` is taken so that Open3D's calls run unchanged, and must be positive, but
        changes nothing: Open3D votes with ``nsamples`` rays, the winding number needs no vote.
        """
        _nsamples(nsamples)
        (_, _, _, _, _, d, inside), lead = self._closest(query_points, True, nthreads)
        return np.where(inside, -d, d).reshape(lead)

    def compute_occupancy(self, query_points, nthreads: int = 0, nsamples: int = 1) -> np.ndarray:
        """1.0 where a point is inside (as :meth:`compute_signed_distance` decides), else 0.0:
        float32 ``(...)``. ``nsamples`` is as for :meth:`compute_signed_distance`."""
        _nsamples(nsamples)
        rows, lead = _rows(query_points, 3, "query_points")
        inside = self._native.inside(rows, list(lead), _nthreads(nthreads))
        return inside.astype(np.float32).reshape(lead)

    def winding_number(self, query_points, nthreads: int = 0) -> np.ndarray:
        """The generalised winding number of the scene's triangles at each point: float64
        ``(...)``, within ``1e-9`` of the exact sum (1 inside a closed outward-facing mesh, 0
        outside, fractional near holes)."""
        rows, lead = _rows(query_points, 3, "query_points")
        return self._native.winding_number(rows, list(lead), _nthreads(nthreads)).reshape(lead)

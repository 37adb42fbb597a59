"""The metric shape of the paper: N samples with their distance matrix, diameter 1.

``MetricShape.D`` is an (M, M) matrix over a point set Y whose first N points are
the samples X (DESIGN.md section 1).  With ``target="samples"`` (the paper) M = N
and maps are bijections of X; with ``target="dense"`` (issue 4) Y holds
M = factor x N farthest-point samples with X as its prefix, so that the mirror
image of a sample can be matched to a nearby target instead of another sample.

Building a metric shape from a mesh is the slow step (one geodesic solve per
point of Y), so results are cached on disk, keyed by a hash of the geometry and
of every parameter; ``cache=False`` disables it.  The cache folder is
``$SHAPECOND_CACHE`` or ``~/.cache/shapecond``.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import InputError
from .geodesics import BACKENDS, DistanceSolver
from .geometry import Geometry
from .sampling import farthest_point_sampling
from .validate import check_distance_matrix

CACHE_VERSION = "2"  # 2: heat distances from shapes.heat (blocks), same as potpourri3d to round-off
TARGETS = ("samples", "dense")


@dataclass(frozen=True, eq=False)
class MetricShape:
    """N samples X inside a target set Y (M points) with distances scaled to diameter 1.

    Attributes
    ----------
    D : (M, M) float64, symmetric, zero diagonal, ``max D = 1`` over Y.
    n_samples : int, N; the samples X are the first N points of Y.
    samples : (M,) int64 internal vertex index of each point of Y (row index for a matrix).
    geometry : Geometry or None (a distance-matrix input).
    metric : "geodesic", "euclidean" or "given".
    backend : geodesic backend name, or None.
    target : "samples" (M = N, the paper's bijections) or "dense".
    scale : raw diameter of Y; ``D = raw / scale``.
    nearest : (n,) index into Y of every vertex's closest point of Y, or None.
    covering_radius : max distance of a vertex to Y, in units of ``scale``, or None.
    """

    D: np.ndarray
    n_samples: int
    samples: np.ndarray
    geometry: Geometry | None
    metric: str
    backend: str | None
    target: str
    scale: float
    nearest: np.ndarray | None = None
    covering_radius: float | None = None

    @property
    def n_points(self) -> int:
        return self.n_samples

    @property
    def n_targets(self) -> int:
        return int(self.D.shape[0])

    @property
    def target_ids(self) -> np.ndarray:
        """The input's own id (file vertex id, or matrix row) of every point of Y."""
        return self.samples if self.geometry is None else self.geometry.ids[self.samples]

    @property
    def sample_ids(self) -> np.ndarray:
        return self.target_ids[: self.n_samples]

    def landmark_indices(self, ids) -> np.ndarray:
        """Sample indices of the input ids ``ids``; InputError if one is not a sample."""
        where = {int(v): k for k, v in enumerate(self.sample_ids)}
        out = []
        for v in ids:
            if int(v) not in where:
                raise InputError(f"id {int(v)} is not one of the samples")
            out.append(where[int(v)])
        return np.asarray(out, dtype=np.int64)


def metric_shape(geometry: Geometry, n_points: int = 400, metric: str = "geodesic", backend: str = "heat",
                 seed: int = 0, landmarks=(), target: str = "samples", target_factor: int = 8,
                 cache: bool = True, progress: bool = False) -> MetricShape:
    """Sample a mesh or point cloud into a ``MetricShape`` (landmarks first, FPS order).

    Parameters
    ----------
    geometry : Geometry; its ``symmetry`` map, when set, makes the sampling
        symmetry-consistent (X and Y closed under the map).
    n_points : N, the number of samples.
    metric : "geodesic" or "euclidean" (the latter forces ``backend="euclidean"``).
    backend : geodesic backend, see ``shapecond.shapes.geodesics``.
    landmarks : internal vertex indices placed first.
    target : "samples" or "dense"; ``target_factor`` gives M = factor x N for dense
        targets (capped at the vertex count).
    """
    if metric not in ("geodesic", "euclidean"):
        raise InputError(f"unknown metric {metric!r}; choose geodesic or euclidean")
    if metric == "euclidean":
        backend = "euclidean"
    elif backend not in BACKENDS or backend == "euclidean":
        raise InputError(f"unknown geodesic backend {backend!r}; choose heat, fmm or exact")
    if target not in TARGETS:
        raise InputError(f"unknown target {target!r}; choose samples or dense")
    if n_points < 3:
        raise InputError(f"at least 3 points are needed, got {n_points}")
    if n_points > geometry.n_vertices:
        raise InputError(f"{geometry.name} has {geometry.n_vertices} vertices, fewer than the "
                         f"{n_points} samples requested")
    if target_factor < 1:
        raise InputError("--target-factor must be at least 1")
    m = n_points if target == "samples" else min(n_points * int(target_factor), geometry.n_vertices)
    landmarks = tuple(int(v) for v in landmarks)
    key = _cache_key(geometry, n_points, m, backend, seed, landmarks)
    path = _cache_path(key) if cache else None
    if path is not None and path.exists():
        try:
            with np.load(path) as z:
                return MetricShape(z["D"], n_points, z["samples"], geometry, metric, backend, target,
                                   float(z["scale"]), z["nearest"], float(z["covering_radius"]))
        except Exception:
            path.unlink(missing_ok=True)  # a damaged cache entry is recomputed
    solver = DistanceSolver(geometry, backend)
    fps = farthest_point_sampling(solver, m, landmarks=landmarks, seed=seed, symmetry=geometry.symmetry,
                                  stops=(n_points,), progress=progress)
    scale = float(fps.D.max())
    if not scale > 0:
        raise InputError(f"{geometry.name}: zero diameter")
    shape = MetricShape(fps.D / scale, n_points, fps.samples, geometry, metric, backend, target, scale,
                        fps.nearest, float(fps.min_dist.max() / scale))
    if path is not None:
        _save(path, shape)
    return shape


def from_distance_matrix(D: np.ndarray, landmarks=(), name: str = "matrix") -> MetricShape:
    """A ``MetricShape`` over all rows of a given distance matrix (``target="samples"``).

    Landmarks (row indices) are moved to the front; the other rows keep their order.
    """
    D = check_distance_matrix(D, name)
    n = D.shape[0]
    landmarks = [int(v) for v in landmarks]
    order = np.asarray(landmarks + [i for i in range(n) if i not in set(landmarks)], dtype=np.int64)
    scale = float(D.max())
    return MetricShape(D[np.ix_(order, order)] / scale, n, order, None, "given", None, "samples", scale)


def restrict_targets(shape: MetricShape, n_targets: int) -> MetricShape:
    """The same samples with only the first ``n_targets`` points of Y as targets.

    FPS is prefix-consistent, so this equals sampling with fewer targets; the
    covering radius is then unknown (None) and D keeps the scale of the full Y.
    """
    k = max(shape.n_samples, min(int(n_targets), shape.n_targets))
    return replace(shape, D=shape.D[:k, :k], samples=shape.samples[:k], nearest=None, covering_radius=None,
                   target="samples" if k == shape.n_samples else shape.target)


def _cache_key(geometry: Geometry, n_points: int, m: int, backend: str, seed: int, landmarks) -> str:
    h = hashlib.sha256()
    for arr in (geometry.vertices, geometry.faces, geometry.ids, geometry.symmetry):
        h.update(b"none" if arr is None else np.ascontiguousarray(arr).tobytes())
    h.update(repr((CACHE_VERSION, n_points, m, backend, seed, landmarks)).encode())
    return h.hexdigest()[:32]


def cache_dir() -> Path:
    return Path(os.environ.get("SHAPECOND_CACHE", Path.home() / ".cache" / "shapecond"))


def _cache_path(key: str) -> Path:
    return cache_dir() / f"metric-{key}.npz"


def _save(path: Path, shape: MetricShape) -> None:
    from .io import atomic_write

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_write(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, D=shape.D, samples=shape.samples, scale=shape.scale, nearest=shape.nearest,
                         covering_radius=shape.covering_radius)
    except OSError:
        pass  # an unwritable cache only costs time

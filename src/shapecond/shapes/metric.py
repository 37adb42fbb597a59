"""The metric shape of the paper: N samples with their distance matrix, diameter 1.

``MetricShape.D`` is an (M, M) matrix over a point set Y whose first N points are
the samples X.  With ``target="samples"`` (the paper) M = N and maps are
bijections of X; with ``target="dense"`` Y holds M = factor x N farthest-point
samples with X as its prefix, so that the mirror image of a sample can be
matched to a nearby target instead of another sample.

Building a metric shape from a mesh is the slow step (one geodesic solve per
point of Y), so results are cached on disk (``shapecond.cache``), keyed by a
hash of the geometry and of every parameter, and checked when read;
``cache=False`` disables it.  The cost is estimated first
(``shapecond.limits``): work beyond the limits needs ``force=True``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import cache as disk
from ..checks import check_distance_matrix, check_int, check_seed
from ..errors import InputError
from ..limits import check_cost, geodesic_seconds, metric_bytes
from .geodesics import BACKENDS, DistanceSolver
from .geometry import Geometry
from .sampling import farthest_point_sampling

CACHE_VERSION = "3"  # 2: checked entries; 3: heat distances from shapes.heat (blocks), as potpourri3d to round-off
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

    def __repr__(self) -> str:
        name = self.geometry.name if self.geometry is not None else "a distance matrix"
        return (f"MetricShape({name!r}, N={self.n_samples}, M={self.n_targets}, {self.metric}"
                f"{f' ({self.backend})' if self.backend else ''}, target={self.target}, diameter={self.scale:.4g})")

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


@dataclass(frozen=True)
class Sampling:
    """How a geometry is sampled into a metric shape (``build_metric_shape``); each field checked here.

    Attributes
    ----------
    metric : "geodesic" or "euclidean" (the latter forces ``backend="euclidean"``).
    backend : geodesic backend, see ``shapecond.shapes.geodesics``.
    seed : seed of the farthest-point sampling's start.
    target : "samples" or "dense"; ``target_factor`` gives M = factor x N for dense
        targets (capped at the vertex count).
    cache : read and write the on-disk cache.
    progress : a progress bar on stderr.
    force : run even when the estimated time or memory is beyond ``shapecond.limits``.
    """

    metric: str = "geodesic"
    backend: str = "heat"
    seed: int = 0
    target: str = "samples"
    target_factor: int = 8
    cache: bool = True
    progress: bool = False
    force: bool = False

    def __post_init__(self):
        if self.metric not in ("geodesic", "euclidean"):
            raise InputError(f"unknown metric {self.metric!r}; choose geodesic or euclidean")
        if self.metric == "euclidean":
            object.__setattr__(self, "backend", "euclidean")
        elif self.backend not in BACKENDS or self.backend == "euclidean":
            raise InputError(f"unknown geodesic backend {self.backend!r}; choose heat, fmm or exact")
        if self.target not in TARGETS:
            raise InputError(f"unknown target {self.target!r}; choose samples or dense")
        object.__setattr__(self, "target_factor", check_int(self.target_factor, "target_factor", lo=1, hi=1000))
        object.__setattr__(self, "seed", check_seed(self.seed))


def build_metric_shape(geometry: Geometry, n_points: int = 400, landmarks=(),
                       sampling: Sampling = Sampling()) -> MetricShape:
    """Sample a mesh or point cloud into a ``MetricShape`` (landmarks first, FPS order).

    Parameters
    ----------
    geometry : Geometry; its ``symmetry`` map, when set, makes the sampling
        symmetry-consistent (X and Y closed under the map).
    n_points : N, the number of samples.
    landmarks : internal vertex indices placed first.
    sampling : how (``Sampling``: ``metric``, ``backend``, ``seed``, ``target``, ``target_factor``,
        ``cache``, ``progress``, ``force``).
    """
    s = sampling
    n_points = check_int(n_points, "n_points", lo=3)
    if n_points > geometry.n_vertices:
        raise InputError(f"{geometry.name} has {geometry.n_vertices} vertices, fewer than the "
                         f"{n_points} samples requested")
    metric, backend, seed, target, cache = s.metric, s.backend, s.seed, s.target, s.cache
    m = n_points if target == "samples" else min(n_points * s.target_factor, geometry.n_vertices)
    landmarks = tuple(int(v) for v in landmarks)
    key = disk.key_of(CACHE_VERSION, geometry.vertices, geometry.faces, geometry.ids, geometry.symmetry,
                      n_points, m, backend, seed, landmarks)
    shapes = {"D": (m, m), "samples": (m,), "scale": (), "nearest": (geometry.n_vertices,), "covering_radius": ()}
    z = disk.load_arrays("metric", key, shapes, lambda a: _check_entry(a, geometry, landmarks)) if cache else None
    if z is not None:
        return MetricShape(check_distance_matrix(z["D"]), n_points, z["samples"].astype(np.int64), geometry,
                           metric, backend, target, float(z["scale"]), z["nearest"].astype(np.int64),
                           float(z["covering_radius"]))
    check_cost(f"sampling {m} points of {geometry.name} ({geometry.n_vertices} vertices, {backend} distances)",
               geodesic_seconds(geometry.n_vertices, m, backend), metric_bytes(m, geometry.n_vertices), s.force)
    solver = DistanceSolver(geometry, backend)
    fps = farthest_point_sampling(solver, m, landmarks=landmarks, seed=seed, symmetry=geometry.symmetry,
                                  stops=(n_points,), progress=s.progress)
    scale = float(fps.D.max())
    if not scale > 0:
        raise InputError(f"{geometry.name}: zero diameter")
    D = check_distance_matrix(fps.D / scale, geometry.name)
    shape = MetricShape(D, n_points, fps.samples, geometry, metric, backend, target, scale,
                        fps.nearest, float(fps.min_dist.max() / scale))
    if cache:
        disk.save_arrays("metric", key, {"D": shape.D, "samples": shape.samples, "scale": shape.scale,
                                         "nearest": shape.nearest, "covering_radius": shape.covering_radius})
    return shape


def _check_entry(a: dict, geometry: Geometry, landmarks) -> None:
    """Refuse a cache entry whose content cannot be this shape's (checked on every read)."""
    samples, n = a["samples"], geometry.n_vertices
    if samples.size and (samples.min() < 0 or samples.max() >= n or np.unique(samples).size != samples.size):
        raise InputError("its samples are not distinct vertices of the shape")
    if tuple(int(v) for v in samples[:len(landmarks)]) != tuple(landmarks):
        raise InputError("its samples do not start with the landmarks")
    if not (np.isfinite(a["scale"]) and a["scale"] > 0 and abs(float(np.max(a["D"])) - 1.0) < 1e-9):
        raise InputError("its distances are not scaled to diameter 1")
    if a["nearest"].size and (a["nearest"].min() < 0 or a["nearest"].max() >= samples.size):
        raise InputError("its nearest-point map is out of range")
    a["D"] = check_distance_matrix(a["D"])  # the checked copy: validated once per read, not twice


def from_distance_matrix(D: np.ndarray, landmarks=(), name: str = "matrix") -> MetricShape:
    """A ``MetricShape`` over all rows of a given distance matrix (``target="samples"``).

    Landmarks (row indices) are moved to the front; the other rows keep their order.
    """
    D = check_distance_matrix(D, name, min_points=3, distinct=True)
    n = D.shape[0]
    landmarks = [int(v) for v in landmarks]
    order = np.asarray(landmarks + [i for i in range(n) if i not in set(landmarks)], dtype=np.int64)
    scale = float(D.max())
    return MetricShape(check_distance_matrix(D[np.ix_(order, order)] / scale, name), n, order, None, "given",
                       None, "samples", scale)



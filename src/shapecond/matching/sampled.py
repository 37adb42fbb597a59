"""A sampled surface for matching: FPS samples with their full distance rows.

Matching works on the N × N sample distances ``D``, but the dense extension
(``dense.py``) and the error metrics (``metrics.py``) also need the distance
from every sample to every vertex: the ``(N, n)`` *rows*.  Farthest-point
sampling computes exactly these rows, so ``sample_surface`` has
``shapecond.shapes.sampling.farthest_point_sampling`` keep them (same samples as
``metric_shape`` with the same arguments, hence the same samples the landmark
methods see) and caches them on disk beside the metric-shape cache.

Units.  Matching compares distances *across* two shapes, so both must be in
the same units.  Scaling each shape to diameter 1 (as ``MetricShape`` does)
injects an error whenever a pose changes the diameter (a cat curling its
tail); area is preserved by isometries, so ``D`` here is raw distance divided
by ``sqrt(area)`` for meshes (the Princeton benchmark's normaliser) and by the
raw sample diameter for point clouds.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from shapecond import cache as disk
from shapecond.errors import InputError
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.geometry import Geometry
from shapecond.shapes.sampling import farthest_point_sampling
from shapecond.shapes.validate import face_areas, unit_length

CACHE_VERSION = "matching-rows-2"


@dataclass(frozen=True, eq=False)
class SampledSurface:
    """Samples of one shape with the distances from each sample to every vertex.

    Attributes
    ----------
    geometry : Geometry
    samples : (N,) int64 internal vertex indices (landmarks first when given).
    rows : (N, n) float32 raw distances from each sample to every vertex.
    unit : float, ``sqrt(area)`` (mesh) or the raw sample diameter (point cloud).
    backend : str, the geodesic backend that produced ``rows``.
    """

    geometry: Geometry
    samples: np.ndarray
    rows: np.ndarray
    unit: float
    backend: str

    @property
    def n_samples(self) -> int:
        return int(self.samples.size)

    @property
    def D(self) -> np.ndarray:
        """(N, N) symmetrised sample distances in units of ``unit``."""
        R = self.rows[:, self.samples].astype(np.float64)
        R = 0.5 * (R + R.T)
        np.fill_diagonal(R, 0.0)
        return R / self.unit

    @property
    def diameter(self) -> float:
        """Raw geodesic diameter estimate: the largest sample-to-vertex distance."""
        return float(self.rows.max())

    @property
    def nearest(self) -> np.ndarray:
        """(n,) index of every vertex's nearest sample (the first one on a tie).  Row by row, the
        result of ``np.argmin(rows, axis=0)`` on finite rows without its transposed copy of them,
        whose fresh pages cost 0.35 s CPU at 400 × 52,565 (0.05 s here)."""
        best = self.rows[0].copy()
        out = np.zeros(best.size, dtype=np.int64)
        for i in range(1, self.rows.shape[0]):
            closer = self.rows[i] < best
            best[closer] = self.rows[i][closer]
            out[closer] = i
        return out


def surface_unit(geometry: Geometry, raw_diameter: float) -> float:
    """``sqrt(total area)`` for a mesh, ``raw_diameter`` for a point cloud."""
    if geometry.faces is not None:  # area of the shape scaled to unit size: no overflow at any scale
        size = unit_length(geometry.vertices)
        area = float(face_areas(geometry.vertices / size, geometry.faces).sum()) if size > 0 else 0.0
        if area > 0:
            return float(np.sqrt(area)) * size
    if not raw_diameter > 0:
        raise InputError(f"{geometry.name}: zero diameter")
    return float(raw_diameter)


class CachedSolver:
    """A DistanceSolver built on first use that remembers every row it computed.

    Used when many landmark sets are inserted into the same shape: the heat
    method's factorisation is made once and shared landmarks are solved once.
    """

    def __init__(self, geometry: Geometry, backend: str = "heat", known: "SampledSurface | None" = None):
        self.geometry, self.backend, self.n = geometry, backend, geometry.n_vertices
        self._solver, self._rows = None, {}
        if known is not None:
            self.remember(known)

    def remember(self, known: "SampledSurface") -> None:
        """Keep the rows of ``known`` (a sampled surface of the same geometry), already computed."""
        self._rows.update({int(s): r for s, r in zip(known.samples, known.rows)})

    @property
    def solver(self) -> DistanceSolver:
        """The distance solver, built on first use (``sample_surface`` samples with it)."""
        if self._solver is None:
            self._solver = DistanceSolver(self.geometry, self.backend)
        return self._solver

    def distances(self, sources):
        sources = [int(s) for s in np.atleast_1d(sources)]
        todo = [s for s in dict.fromkeys(sources) if s not in self._rows]
        if todo:
            for s, row in zip(todo, self.solver.distances(todo)):
                self._rows[s] = row
        return np.stack([self._rows[s] for s in sources]) if sources else np.empty((0, self.n))


def sample_surface(geometry: Geometry, n_points: int = 400, backend: str = "heat", seed: int = 0,
                   landmarks=(), cache: bool = True, solver: DistanceSolver | CachedSolver | None = None
                   ) -> SampledSurface:
    """FPS-sample ``geometry`` (landmarks first) and keep the distance rows.

    Parameters
    ----------
    geometry : Geometry
    n_points : int
        N, the number of samples (the paper's 400).
    backend : str
        Geodesic backend (``shapecond.shapes.geodesics``).
    seed : int
        Seed of FPS's random start.
    landmarks : sequence of int
        Internal vertex indices placed first.
    cache : bool
        Read/write ``<cache_dir>/matching-<key>.npz``.
    solver : the geometry's distance solver (a ``CachedSolver``'s is built only if sampling needs it,
        and kept for later rows of that geometry), or None for a new one.
    """
    if n_points > geometry.n_vertices:
        raise InputError(f"{geometry.name} has {geometry.n_vertices} vertices, fewer than the "
                         f"{n_points} samples requested")
    landmarks = tuple(int(v) for v in landmarks)
    key = disk.key_of(CACHE_VERSION, geometry.vertices, geometry.faces, geometry.ids, n_points, backend, seed,
                      landmarks)
    n = geometry.n_vertices
    z = disk.load_arrays("matching", key, {"samples": (n_points,), "rows": (n_points, n), "unit": ()},
                         lambda a: _check_entry(a, n, landmarks)) if cache else None
    if z is not None:
        return SampledSurface(geometry, z["samples"].astype(np.int64), z["rows"], float(z["unit"]), backend)
    solver = solver.solver if isinstance(solver, CachedSolver) else solver or DistanceSolver(geometry, backend)
    fps = farthest_point_sampling(solver, n_points, landmarks=landmarks, seed=seed, keep_rows=True)
    surf = SampledSurface(geometry, fps.samples, fps.rows, surface_unit(geometry, float(fps.rows.max())),
                          backend)
    if cache:
        disk.save_arrays("matching", key, {"samples": surf.samples, "rows": surf.rows, "unit": surf.unit})
    return surf


def surface_at(geometry: Geometry, vertices, backend: str = "heat", cache: bool = True,
               solver: DistanceSolver | None = None) -> SampledSurface:
    """The surface sampled at given vertices (in that order), with their distance rows.

    No FPS: one geodesic solve per vertex, cached on disk like ``sample_surface``
    (the key holds the vertices).  Used to carry one shape's samples to another
    shape with the same vertex order (``carry_samples``).
    """
    vertices = np.asarray(vertices, dtype=np.int64).reshape(-1)
    if vertices.size and (vertices.min() < 0 or vertices.max() >= geometry.n_vertices):
        raise InputError(f"sample vertex out of range 0..{geometry.n_vertices - 1} on {geometry.name}")
    key = disk.key_of(CACHE_VERSION, geometry.vertices, geometry.faces, geometry.ids, backend, "at", vertices)
    k, n = int(vertices.size), geometry.n_vertices

    def check(a):
        if not np.array_equal(a["samples"], vertices):
            raise InputError("its samples are not these vertices")
        _check_entry(a, n, ())

    z = disk.load_arrays("matching", key, {"samples": (k,), "rows": (k, n), "unit": ()}, check) if cache else None
    if z is not None:
        return SampledSurface(geometry, vertices, z["rows"], float(z["unit"]), backend)
    solver = solver if solver is not None else DistanceSolver(geometry, backend)
    rows = solver.distances(vertices).astype(np.float32)
    surf = SampledSurface(geometry, vertices, rows, surface_unit(geometry, float(rows.max())), backend)
    if cache:
        disk.save_arrays("matching", key, {"samples": surf.samples, "rows": surf.rows, "unit": surf.unit})
    return surf


def carry_samples(source: SampledSurface, target: Geometry, solver=None, seed: int = 0,
                  shuffle: bool = True):
    """The source's samples carried to ``target`` by vertex id: the *corresponding* protocol.

    The condition number (paper Eq. 4) compares a shape X with a perturbation X̃ of
    the same points, so matching the samples of ``source`` to the same vertices of a
    deformed ``target`` (same vertex count and ids) measures exactly that: the true
    map is known sample by sample and no discretisation error enters.  The target's
    samples are put in a seeded random order so that no matcher can profit from the
    sample order.

    Parameters
    ----------
    source : SampledSurface
    target : Geometry with the same vertex ids as ``source.geometry``.
    solver : optional distance solver of ``target`` (e.g. a ``CachedSolver``).
    seed : seed of the shuffle.
    shuffle : False keeps the source's order (truth = identity).

    Returns
    -------
    (SampledSurface, truth) with ``truth[x]`` the target sample holding source sample
    ``x``'s vertex.
    """
    g = source.geometry
    if not g.shares_vertex_order(target):
        raise InputError(f"{target.name} ({target.n_vertices} vertices) and {g.name} ({g.n_vertices}) "
                         "do not share their vertex order (vertex ids and triangles): corresponding samples "
                         "need one mesh deformed, not two meshes of one vertex count")
    n = source.n_samples
    perm = np.random.default_rng(seed).permutation(n) if shuffle else np.arange(n)
    vertices = source.samples[perm]
    solver = solver if solver is not None else DistanceSolver(target, source.backend)
    rows = np.asarray(solver.distances(vertices), dtype=np.float32)
    surf = SampledSurface(target, vertices, rows, surface_unit(target, float(rows.max())), source.backend)
    truth = np.empty(n, dtype=np.int64)
    truth[perm] = np.arange(n)
    return surf, truth


def _check_entry(a: dict, n: int, landmarks) -> None:
    """Refuse cached rows that cannot belong to this shape (checked on every read)."""
    s, rows = a["samples"], a["rows"]
    if s.min() < 0 or s.max() >= n or np.unique(s).size != s.size or tuple(s[:len(landmarks)]) != landmarks:
        raise InputError("its samples are not distinct vertices starting with the landmarks")
    if not (np.all(np.isfinite(rows)) and rows.min() >= 0 and np.isfinite(a["unit"]) and a["unit"] > 0):
        raise InputError("its distances are not finite and non-negative")
    if np.any(rows[np.arange(s.size), s] != 0):
        raise InputError("its rows do not start at their samples")


def insert_landmarks(surface: SampledSurface, landmarks, solver: DistanceSolver | None = None):
    """Make the landmark vertices samples, placed first; N stays the same.

    Each landmark that is not yet a sample replaces the non-landmark sample
    nearest to it (one geodesic solve per such landmark), so the sampling stays
    nearly uniform and both shapes keep N samples (FAQ needs equal sizes).

    Returns
    -------
    (SampledSurface, landmark sample indices ``arange(L)``)
    """
    lm = np.asarray(landmarks, dtype=np.int64).reshape(-1)
    n = surface.geometry.n_vertices
    if lm.size and (lm.min() < 0 or lm.max() >= n):
        raise InputError(f"landmark vertex out of range 0..{n - 1} on {surface.geometry.name}")
    if np.unique(lm).size != lm.size:
        raise InputError(f"repeated landmarks on {surface.geometry.name}")
    if lm.size > surface.n_samples:
        raise InputError(f"{lm.size} landmarks but only {surface.n_samples} samples")
    samples = surface.samples.copy()
    rows = surface.rows
    pos = {int(v): i for i, v in enumerate(samples)}
    missing = [v for v in lm.tolist() if v not in pos]
    if missing:
        rows = rows.copy()
        solver = solver if solver is not None else DistanceSolver(surface.geometry, surface.backend)
        new_rows = solver.distances(missing).astype(np.float32)
        protected = np.zeros(samples.size, dtype=bool)
        protected[[pos[v] for v in lm.tolist() if v in pos]] = True
        for v, row in zip(missing, new_rows):
            d = np.where(protected, np.inf, row[samples])
            i = int(np.argmin(d))
            samples[i], rows[i], protected[i] = v, row, True
    where = {int(v): i for i, v in enumerate(samples)}
    first = np.array([where[v] for v in lm.tolist()], dtype=np.int64)
    order = np.concatenate([first, np.setdiff1d(np.arange(samples.size), first)])
    if not np.array_equal(order, np.arange(samples.size)):  # already first (sample_surface's order): the
        samples, rows = samples[order], rows[order]            # same rows, no copy (336 MB at 210k vertices)
    return replace(surface, samples=samples, rows=rows), np.arange(lm.size, dtype=np.int64)

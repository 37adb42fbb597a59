"""Geodesic (and Euclidean) distances from sets of source vertices.

Backends:

``heat``       the heat method (Crane et al. 2013) on the intrinsic Delaunay
               triangulation of the tufted cover (the "robust" Laplacian); the
               default.  On meshes it runs in ``shapes.heat``, blocks of sources
               per solve, with the operators of potpourri3d's heat solver (same
               distances, several times faster per source); a mesh with an edge
               shared by three or more faces goes to potpourri3d one source at a
               time, as do point clouds (its point-cloud heat solver).  The
               factorisations are made once per shape and reused for every source.
``fmm``        potpourri3d's fast marching on the mesh.
``exact``      exact polyhedral geodesics (MMP) through ``tvb-gdist`` (the
               ``exact`` extra); seconds per source, for small meshes and tests.
``euclidean``  straight-line distances in R^3.

Every result records the backend that produced it (``DistanceSolver.backend``).
Solvers work on the shape scaled to a unit bounding-box diagonal and scale the
distances back, so the same mesh in any unit gives the same (scaled) result.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .geometry import Geometry
from .validate import unit_length

BACKENDS = ("heat", "fmm", "exact", "euclidean")
#: potpourri3d's point-cloud solver builds a 30-nearest-neighbour graph.
MIN_CLOUD_POINTS = 31


class DistanceSolver:
    """Distances from any set of source vertices to all vertices of one shape.

    Parameters
    ----------
    geometry : Geometry
    backend : {"heat", "fmm", "exact", "euclidean"}

    Notes
    -----
    The solver is built once (factorisations, acceleration structures) and
    ``distances`` reuses it for every source: never re-factorised per source.
    ``block`` is the number of sources worth solving together (1 when every
    source is a solve of its own); ``guess`` is a cheap stand-in for a row that
    lets farthest-point sampling guess which rows it will ask for next.
    """

    block: int = 1

    def __init__(self, geometry: Geometry, backend: str = "heat"):
        if backend not in BACKENDS:
            raise InputError(f"unknown geodesic backend {backend!r}; choose from {', '.join(BACKENDS)}")
        self.geometry = geometry
        self.backend = backend
        self.n = geometry.n_vertices
        self.unit = unit_length(geometry.vertices) or 1.0
        V = (geometry.vertices - geometry.vertices.mean(axis=0)) / self.unit
        V = np.ascontiguousarray(V, dtype=np.float64)
        F = None if geometry.faces is None else np.ascontiguousarray(geometry.faces, dtype=np.int64)
        self._V, self._sqnorm = V, np.einsum("ij,ij->i", V, V)
        self._rows = None  # a function computing many rows at once, when the backend has one
        if backend == "heat" and F is not None:
            from .heat import BLOCK, HeatMethod
            from .helper import SplitRows, helper_allowed
            from .intrinsic import intrinsic_delaunay_cover

            tri = intrinsic_delaunay_cover(V, F)
            if tri is not None:
                self._rows = HeatMethod(tri, self.n).distances
                self.block = BLOCK
                if helper_allowed():  # the other core computes half of every block
                    self._rows = SplitRows(self._rows, self.n, BLOCK)
                    self.block = 2 * BLOCK
                return
        if backend == "euclidean":
            self._one = lambda s: np.linalg.norm(V - V[s], axis=1)
            return
        import potpourri3d as pp3d

        if F is None:
            if backend != "heat":
                raise InputError(f"the {backend} backend needs a mesh; point clouds use the heat backend")
            if self.n < MIN_CLOUD_POINTS:
                raise InputError(f"{geometry.name}: geodesics on a point cloud need at least {MIN_CLOUD_POINTS} "
                                 f"points, got {self.n} (use --metric euclidean)")
            try:
                solver = pp3d.PointCloudHeatSolver(V)
            except RuntimeError as exc:  # geometry-central refuses clouds it cannot mesh locally
                raise InputError(f"{geometry.name}: the point cloud has no usable local surface "
                                 f"({str(exc).splitlines()[0][-80:]})") from None
            self._one = lambda s: np.asarray(solver.compute_distance(int(s)), dtype=np.float64)
        elif backend == "heat":
            solver = pp3d.MeshHeatMethodDistanceSolver(V, F)
            self._one = lambda s: np.asarray(solver.compute_distance(int(s)), dtype=np.float64)
        elif backend == "fmm":
            solver = pp3d.MeshFastMarchingDistanceSolver(V, F)
            self._one = lambda s: np.asarray(solver.compute_distance([[(int(s), [])]]), dtype=np.float64).ravel()
        else:
            self._one = _exact_solver(V, F)

    def distances(self, sources) -> np.ndarray:
        """Distances from each source to every vertex, shape (len(sources), n), raw units.

        Negative values from the heat method's round-off at the source are clipped
        to 0 and the source's own distance is set to exactly 0.
        """
        sources = np.atleast_1d(np.asarray(sources, dtype=np.int64))
        if sources.size and (sources.min() < 0 or sources.max() >= self.n):
            raise InputError(f"source vertex out of range 0..{self.n - 1}")
        if self._rows is not None:
            out = self._rows(sources)
        else:
            out = np.empty((sources.size, self.n), dtype=np.float64)
            for k, s in enumerate(sources):
                out[k] = self._one(s)
        if not np.all(np.isfinite(out)):
            raise InputError(f"{self.geometry.name}: the {self.backend} backend returned non-finite "
                             "distances (is the mesh broken or disconnected?)")
        out *= self.unit  # computed on the shape scaled to unit size
        np.maximum(out, 0.0, out=out)
        out[np.arange(sources.size), sources] = 0.0
        return out

    def guess(self, source: int) -> np.ndarray:
        """Straight-line distances from ``source`` (a lower bound of the geodesic ones), shape (n),
        in the units of ``distances``."""
        s = int(source)
        d2 = self._sqnorm + self._sqnorm[s] - 2.0 * (self._V @ self._V[s])
        return self.unit * np.sqrt(np.maximum(d2, 0.0, out=d2), out=d2)


def _exact_solver(V: np.ndarray, F: np.ndarray):
    try:
        import gdist
    except ImportError:
        raise InputError("the exact backend needs tvb-gdist: pip install 'shapecond[exact]'") from None
    Vd = np.ascontiguousarray(V, dtype=np.float64)
    Fi = np.ascontiguousarray(F, dtype=np.int32)  # tvb-gdist wants int32 faces
    targets = np.arange(V.shape[0], dtype=np.int32)

    def one(s):
        return np.asarray(gdist.compute_gdist(Vd, Fi, np.array([s], dtype=np.int32), targets), dtype=np.float64)

    return one


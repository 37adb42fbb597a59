"""Local symmetry score sigma_inf for deformation-based matching (paper Section 5).

A deformation-based matcher started at the
identity finds the displacement ``P`` minimising ``E(P)`` (``energy.py``); near
the minimum ``E(P) ~ 1/2 P^T H P``.  The local score is the largest
displacement per unit of energy,

    sigma_inf = sup_P |P|_M / sqrt(E(P)) = sqrt(2 / lambda_min),

with ``lambda_min`` the smallest eigenvalue of ``H v = lambda M v`` and ``M`` the
lumped area mass matrix.  **The paper writes 2 / sqrt(lambda_min); with
E ~ 1/2 P^T H P the supremum is sqrt(2 / lambda_min), which is what we compute**
(the paper's value is always sqrt(2) times larger).  The mass matrix makes ``|P|_M`` an area integral, so the
score of the same surface does not drift with the resolution of its mesh
(without it, lambda_min fell 4x from 10k to 41k vertices).

Zero modes.  A displacement the energy cannot see (rotating a sphere) gives
``lambda = 0`` and ``sigma_inf = inf``.  Discretely such eigenvalues are not
exactly 0 (the icosphere's rotations give 2e-4 at 162 vertices, 1e-6 at 10k,
because discrete normals are not exactly radial), so an eigenvalue counts as
zero when ``lambda < zero_tol * LAMBDA_REF``, where ``LAMBDA_REF = 2`` is the
eigenvalue of a pure normal displacement of the unit-area mesh (the proximity
stiffness), and ``zero_tol = 1e-3`` by default: scores above
``sqrt(1 / zero_tol) ~ 31.6`` are reported as ``inf``.  The zero modes are
returned and named (``rigid.py``).

Landmarks fix vertices: their three coordinates are removed (paper Section 6).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..jsonable import jsonable
from ..checks import check_float, check_ids
from ..errors import InputError, TooLargeError
from .energy import ALPHA_RANGE, DEFAULT_ALPHA, hessian, mass_diagonal, normalized_mesh
from .rigid import name_zero_modes
from .solver import SHIFT, ShiftInvertSolver

LAMBDA_REF = 2.0
ZERO_TOL = 1e-3
MAX_VERTICES = 300_000  # measured: 1 GB and ~10 s at 111k vertices (the project's benchmarks)


@dataclass(frozen=True, eq=False)
class LocalScore:
    """Result of ``local_symmetry_score``.

    Attributes
    ----------
    score : float, sqrt(2 / lambda_min), ``math.inf`` when there are zero modes
    lambda_min : float, smallest eigenvalue of ``H v = lambda M v`` (>= 0)
    zero_modes : tuple of str, names of the zero modes (empty when the score is finite)
    n_vertices : int
    landmarks : tuple of int, the fixed vertices as the file's vertex ids
    seconds : float, wall time
    eigenvalues : (k,) the smallest eigenvalues computed (ascending)
    modes : (3n, z) the zero modes (M-orthonormal; zero on fixed coordinates)
    """

    score: float
    lambda_min: float
    zero_modes: tuple
    n_vertices: int
    landmarks: tuple
    seconds: float
    eigenvalues: np.ndarray = field(repr=False, default=None)
    modes: np.ndarray = field(repr=False, default=None)

    def to_dict(self) -> dict:
        """JSON-ready summary with exactly the keys of ``shapecond local --json``."""
        return jsonable({
            "score": self.score,
            "lambda_min": self.lambda_min,
            "zero_modes": list(self.zero_modes),
            "n_vertices": self.n_vertices,
            "landmarks": [int(v) for v in self.landmarks],
            "seconds": self.seconds,
        })


def score_from_lambda(lam: float, zero_tol: float = ZERO_TOL) -> float:
    """``sqrt(2 / lambda)``, or ``inf`` below the zero-mode tolerance (module docstring)."""
    return math.inf if lam < zero_tol * LAMBDA_REF else math.sqrt(2.0 / lam)


class LocalProblem:
    """The energy Hessian of one mesh, its mass matrix and a reusable factorisation.

    Build it once and ask for scores with different landmark sets; each new
    fixed vertex costs three solves, not a new factorisation (``solver.py``).

    Parameters
    ----------
    vertices : (n, 3), faces : (m, 3) -- faces ``None`` (a point cloud) is refused.
    alpha : float, weight of the stretching term (``energy.py``; default 1)
    energy : "springs" (default) or "arap"
    backend : linear solver, "cholmod" (default when cholespy is installed) or "superlu" (``solver.py``)
    """

    def __init__(self, vertices, faces, alpha: float = DEFAULT_ALPHA, energy: str = "springs",
                 shift: float = SHIFT, backend: str | None = None):
        t0 = time.perf_counter()
        alpha = check_float(alpha, "alpha", lo=ALPHA_RANGE[0], hi=ALPHA_RANGE[1])
        if faces is not None and np.asarray(vertices).shape[0] > MAX_VERTICES:
            raise TooLargeError(f"the local score is limited to {MAX_VERTICES} vertices (it factorises a "
                                "3n x 3n matrix); simplify the mesh first")
        V, F, scale, self.centroid = normalized_mesh(vertices, faces)
        self.V, self.F, self.scale = V, F, scale
        self.alpha, self.energy = float(alpha), energy
        self.H = hessian(V, F, alpha=alpha, energy=energy)
        self.mass = mass_diagonal(V, F)
        self.solver = ShiftInvertSolver(self.H, self.mass, V, shift=shift, backend=backend)
        self.setup_seconds = time.perf_counter() - t0

    @property
    def n_vertices(self) -> int:
        return int(self.V.shape[0])

    def check_fixed(self, fixed) -> np.ndarray:
        """Distinct vertex indices in range, in the caller's order (``InputError`` otherwise)."""
        fixed = np.asarray(check_ids(fixed, "landmarks"), dtype=np.int64)
        if fixed.size and fixed.max() >= self.n_vertices:
            raise InputError(f"landmark index out of range 0..{self.n_vertices - 1}")
        return fixed

    def spectrum(self, fixed=(), zero_tol: float = ZERO_TOL, k: int = 4, max_k: int = 32):
        """Smallest eigenpairs with ``fixed`` vertices, enough to see every zero mode.

        ``k`` eigenpairs are computed first; while all of them are zero modes,
        ``k`` doubles (up to ``max_k``).  Returns ``(eigenvalues, vectors, n_zero)``.
        """
        problem = self.solver.constrained(self.check_fixed(fixed))
        while True:
            w, X = problem.eigenpairs(k)
            n_zero = int(np.sum(w < zero_tol * LAMBDA_REF))
            if n_zero < len(w) or k >= max_k or len(w) < k:
                return w, X, n_zero
            k = min(2 * k, max_k)

    def score(self, fixed=(), zero_tol: float = ZERO_TOL, ids=None) -> LocalScore:
        """``LocalScore`` with the internal vertex indices ``fixed`` held in place."""
        t0 = time.perf_counter()
        zero_tol = check_float(zero_tol, "zero_tol", lo=0.0, hi=1.0, lo_open=True, hi_open=True)
        fixed = self.check_fixed(fixed)
        w, X, n_zero = self.spectrum(fixed, zero_tol)
        Z = X[:, :n_zero]
        names = name_zero_modes(Z, self.V, self.mass, (3 * fixed[:, None] + np.arange(3)).ravel(),
                                self.scale, self.centroid) if n_zero else []
        lam = float(w[0])
        ids = np.arange(self.n_vertices) if ids is None else np.asarray(ids)
        return LocalScore(
            score=math.inf if n_zero else math.sqrt(2.0 / lam),
            lambda_min=lam,
            zero_modes=tuple(names),
            n_vertices=self.n_vertices,
            landmarks=tuple(int(ids[v]) for v in fixed),
            seconds=time.perf_counter() - t0,
            eigenvalues=w,
            modes=Z,
        )


def local_symmetry_score(vertices, faces, landmarks=(), alpha: float = DEFAULT_ALPHA,
                         energy: str = "springs", zero_tol: float = ZERO_TOL, ids=None) -> LocalScore:
    """Local symmetry score sigma_inf = sqrt(2 / lambda_min) of a mesh (paper Section 5).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int; ``None`` (point cloud) raises ``InputError``: the
        energy needs tangent planes and edges.
    landmarks : indices into ``vertices`` of the vertices to fix.
    alpha : weight of the stretching term (default 1, dimensionless; ``energy.py``).
    energy : "springs" (default) or "arap".
    zero_tol : relative zero-mode tolerance (module docstring).
    ids : optional (n,) file vertex ids, used to report the landmarks.

    Returns
    -------
    LocalScore ; ``seconds`` includes building and factorising the Hessian.
    """
    t0 = time.perf_counter()
    problem = LocalProblem(vertices, faces, alpha=alpha, energy=energy)
    result = problem.score(landmarks, zero_tol=zero_tol, ids=ids)
    return LocalScore(result.score, result.lambda_min, result.zero_modes, result.n_vertices,
                      result.landmarks, time.perf_counter() - t0, result.eigenvalues, result.modes)


def local_score_of_geometry(geometry, landmark_ids=(), alpha: float = DEFAULT_ALPHA, energy: str = "springs",
                            zero_tol: float = ZERO_TOL) -> LocalScore:
    """``local_symmetry_score`` of a ``Geometry`` with landmarks given as the file's vertex ids."""
    if not geometry.is_mesh:
        raise InputError(f"{geometry.name} is a point cloud; the local score needs a triangle mesh")
    fixed = geometry.to_internal(landmark_ids)
    return local_symmetry_score(geometry.vertices, geometry.faces, fixed, alpha, energy, zero_tol, geometry.ids)

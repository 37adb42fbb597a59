"""The Laplace–Beltrami basis of a shape: one per shape, cached, shared by ZoomOut and the HKS.

Operator: ``robust_laplacian`` (Sharp and Crane, "A Laplacian for nonmanifold
triangle meshes", SGP 2020): the cotangent Laplacian of the intrinsic Delaunay
triangulation of the mesh's tufted cover, and for a point cloud the same built
on local triangulations of its 30 nearest neighbours.  Both give a positive
semi-definite stiffness ``L`` and a lumped (diagonal) mass ``M``, so meshes with
bad triangles, non-manifold edges or no faces at all get a usable basis.

The mass is scaled to total area 1, which makes the basis scale-free: the
eigenvalues of ``L φ = λ M φ`` grow like ``4πk`` (Weyl's law) whatever the unit
of the file, and every eigenvector has unit ``L²(M)`` norm, hence mean square 1
over the surface.  The ``k`` smallest eigenpairs come from shift-invert Lanczos
(``scipy.sparse.linalg.eigsh`` around a small negative shift, as ``L`` is
singular), in ascending order, with each eigenvector's sign fixed (largest
entry in magnitude positive) so that the basis is reproducible.

``DEFAULT_EIGENPAIRS``: ZoomOut's last level (``matching.zoomout``) and the
prefix the heat kernel signature reads (``selection.hks``) come from this one
basis.  150: the vertex-to-vertex map recovered from the *true* functional map
of two independently remeshed 5–8k-vertex shapes of one class by nearest
neighbours in the spectral embedding reaches the vertex-quantisation floor
(about 0.01 sqrt(area), half an edge) at about 150 eigenpairs and not at 100
(0.017); a shape with fewer vertices gets ``n − 2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, eigsh

from .. import cache as disk
from ..cholesky import NotPositiveDefinite, SparseCholesky
from ..errors import InputError
from .geometry import Geometry

DEFAULT_EIGENPAIRS = 150
CACHE_VERSION = "laplace-2"  # 2: the shift-invert through a Cholesky factor (round-off differs from LU)
#: Shift of the shift-invert Lanczos iteration (below the zero eigenvalue of the area-1 operator).
SHIFT = -1e-8


@dataclass(frozen=True, eq=False)
class LaplaceBasis:
    """The first ``k`` eigenpairs of ``L φ = λ M φ`` on a shape of total area 1.

    Attributes
    ----------
    evals : (k,) float64, ascending, the first one 0 (up to round-off).
    evecs : (n, k) float64, ``M``-orthonormal columns.
    mass : (n,) float64, lumped vertex areas, summing to 1.
    """

    evals: np.ndarray
    evecs: np.ndarray
    mass: np.ndarray

    @property
    def n_vertices(self) -> int:
        return int(self.evecs.shape[0])

    @property
    def k(self) -> int:
        return int(self.evals.size)

    def __repr__(self) -> str:
        return f"LaplaceBasis(n={self.n_vertices}, k={self.k}, λ_1={self.evals[min(1, self.k - 1)]:.4g})"


def operators(geometry: Geometry) -> tuple[sp.csc_matrix, np.ndarray]:
    """The stiffness ``L`` (cotangent weights, scale-free) and the lumped mass of the area-1 shape
    (module docstring): the operators the basis is computed from, and the landmarks' harmonic
    coordinates (``matching.harmonic``) solved with."""
    import robust_laplacian

    V = np.asarray(geometry.vertices, dtype=np.float64)
    V = V - V.mean(axis=0)
    size = float(np.abs(V).max())
    if not size > 0:
        raise InputError(f"{geometry.name}: all vertices coincide; no Laplace–Beltrami basis")
    V = V / size  # the operator of a unit-size copy: no overflow or underflow at any file scale
    if geometry.faces is not None:
        L, M = robust_laplacian.mesh_laplacian(V, np.asarray(geometry.faces, dtype=np.int64))
    else:
        L, M = robust_laplacian.point_cloud_laplacian(V)
    mass = np.asarray(M.diagonal(), dtype=np.float64)
    if not (np.all(np.isfinite(mass)) and mass.sum() > 0):
        raise InputError(f"{geometry.name}: the Laplace–Beltrami operator has no positive area")
    # L φ = λ M φ with M divided by the area A is L φ = (λ A)(M / A) φ: the eigenvalues of the
    # area-1 shape; the cotangent weights of L do not depend on the scale
    mass = np.maximum(mass, 1e-12 * mass.max()) / mass.sum()
    return sp.csc_matrix(L, dtype=np.float64), mass


def _eigenpairs(L: sp.csc_matrix, mass: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Shift-invert Lanczos (module docstring).  ``L − σM`` is symmetric positive definite, so its
    inverse is applied through a sparse Cholesky factor (CHOLMOD, ``cholesky.SparseCholesky``)
    rather than scipy's default LU: the same eigenpairs (eigenvectors agreeing to 1e-6 in
    ``L²(M)``), 14.4 → 11.3 s CPU for 150 pairs at 52,565 vertices and 0.9 → 0.7 s at 5,000.  Where
    CHOLMOD finds the shifted matrix not positive definite in floating point, scipy's LU is used."""
    n = mass.size
    start = np.full(n, 1.0 / np.sqrt(n))  # a fixed start vector: the same basis on every run
    M = sp.diags(mass).tocsc()
    try:
        factor = SparseCholesky((L - SHIFT * M).tocsc())
        inverse = LinearOperator((n, n), matvec=factor.solve, dtype=np.float64)
    except NotPositiveDefinite:
        inverse = None
    evals, evecs = eigsh(L, k=k, M=M, sigma=SHIFT, which="LM", v0=start, OPinv=inverse)
    order = np.argsort(evals, kind="stable")
    evals, evecs = np.clip(evals[order], 0.0, None), evecs[:, order]
    big = np.argmax(np.abs(evecs), axis=0)
    evecs = evecs * np.where(evecs[big, np.arange(k)] < 0, -1.0, 1.0)
    return evals, evecs


def laplace_basis(geometry: Geometry, k: int = DEFAULT_EIGENPAIRS, cache: bool = True) -> LaplaceBasis:
    """The first ``k`` Laplace–Beltrami eigenpairs of ``geometry`` (module docstring), cached on disk.

    Parameters
    ----------
    geometry : Geometry, a mesh or a point cloud.
    k : eigenpairs wanted; a shape of ``n`` vertices gives at most ``n − 2``.
    cache : read and write the on-disk cache (``shapecond.cache``).

    Returns
    -------
    LaplaceBasis

    Examples
    --------
    >>> from shapecond.shapes.synthetic import sphere
    >>> basis = laplace_basis(sphere(subdivisions=2), k=10, cache=False)
    >>> basis.k, round(float(basis.evals[0]), 6), round(float(basis.mass.sum()), 6)
    (10, 0.0, 1.0)
    """
    n = geometry.n_vertices
    if n < 4:
        raise InputError(f"{geometry.name}: a Laplace–Beltrami basis needs at least 4 vertices, got {n}")
    k = int(min(k, n - 2))
    if k < 1:
        raise InputError(f"the number of eigenpairs must be at least 1, got {k}")
    key = disk.key_of(CACHE_VERSION, geometry.vertices, geometry.faces, k)
    if cache:
        z = disk.load_arrays("laplace", key, {"evals": (k,), "evecs": (n, k), "mass": (n,)}, _check_entry)
        if z is not None:
            return LaplaceBasis(z["evals"], z["evecs"], z["mass"])
    L, mass = operators(geometry)
    try:
        evals, evecs = _eigenpairs(L, mass, k)
    except (RuntimeError, ValueError) as exc:  # ARPACK's failures on a degenerate operator
        raise InputError(f"{geometry.name}: no Laplace–Beltrami basis ({exc})") from None
    basis = LaplaceBasis(evals, evecs, mass)
    if cache:
        disk.save_arrays("laplace", key, {"evals": evals, "evecs": evecs, "mass": mass})
    return basis


def _check_entry(a: dict) -> None:
    if not (np.all(np.isfinite(a["evecs"])) and np.all(np.diff(a["evals"]) >= 0) and np.all(a["mass"] > 0)):
        raise InputError("its eigenpairs are not finite and ascending")

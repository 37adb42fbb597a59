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
around the shift ``SHIFT`` (``L`` is singular), in ascending order, with each
eigenvector's sign fixed (largest entry in magnitude positive) so that the
basis is reproducible.  The Lanczos process is a block one (``_block_lanczos``,
blocks of ``BLOCK`` vectors, full reorthogonalisation, no restart), with
``scipy.sparse.linalg.eigsh`` (ARPACK) where it does not apply (module
``_eigenpairs``).

``DEFAULT_EIGENPAIRS``: ZoomOut's last level (``matching.zoomout``) and the
prefix the heat kernel signature reads (``selection.hks``) come from this one
basis.  150: the vertex-to-vertex map recovered from the *true* functional map
of two independently remeshed 5–8k-vertex shapes of one class by nearest
neighbours in the spectral embedding reaches the vertex-quantisation floor
(about 0.01 sqrt(area), half an edge) at about 150 eigenpairs and not at 100
(0.017); a shape with fewer vertices gets ``n − 2``.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.linalg import eig_banded, qr
from scipy.sparse.linalg import LinearOperator, eigsh

from .. import cache as disk
from ..cholesky import NotPositiveDefinite, SparseCholesky
from ..errors import InputError
from .geometry import Geometry

DEFAULT_EIGENPAIRS = 150
CACHE_VERSION = "laplace-4"  # 4: BLOCK_TOL 1e-3; 3: block Lanczos around σ = −1; 2: CHOLMOD shift-invert
#: Shift of the shift-invert Lanczos iteration, below the zero eigenvalue of the area-1 operator and
#: about a tenth of its first non-zero one (8π on a sphere); −1e-8 before, which made ``1/(λ − σ)`` span
#: 10⁸ and the block recurrence's round-off (10⁻⁸ of the largest entry) an eigenvalue error of 2e-5.
SHIFT = -1.0
#: Block width of the block Lanczos process: 8 columns solve through CHOLMOD at 1.9 ms a column at
#: 52,565 vertices (4.7 ms one at a time) and converged in the fewest columns of 8, 12 and 16.
BLOCK = 8
#: Convergence of a Ritz pair ``(θ, y)`` of the shift-inverted operator: ``‖Ty − θy‖ ≤ BLOCK_TOL θ``.
#: At 52,565 vertices (TOSCA david0, k = 150), against eigsh with tol 0: 1e-4 took 416 columns, the
#: largest principal angle between the spans has sine 3.7e-6 and the eigenvalues agree to 3e-12; 1e-3
#: took 376 (10 % less CPU), sine 8.1e-4, eigenvalues to 9.5e-8; 1e-2 took 336, sine 0.042 (not
#: taken).  The maps with 1e-3 (FAQ, 6 landmarks, against main's eigsh bases): mean error over 8
#: TOSCA_r test pairs +0.02 % (worst pair +0.30 %), over 4 SMAL_r pairs +0.00 %; TOSCA david0 →
#: david1 at 52k vertices 4.932e-3 → 4.947e-3 sqrt(area) at 300 random vertices (+0.3 %).
BLOCK_TOL = 1e-3
#: ``operators`` of the geometries alive in this process.
_OPERATORS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


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
    coordinates (``matching.harmonic``) solved with.

    Built once per ``Geometry`` object while it lives (a geometry is never changed in place): a cold
    match asks for them twice per shape, 0.65 s CPU each at 52,565 vertices.  Shared: read only."""
    known = _OPERATORS.get(geometry)
    if known is None:
        known = _OPERATORS[geometry] = _build_operators(geometry)
    return known


def _build_operators(geometry: Geometry) -> tuple[sp.csc_matrix, np.ndarray]:
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
    inverse is applied through a sparse Cholesky factor (CHOLMOD, ``cholesky.SparseCholesky``) in
    ``_block_lanczos``.  ARPACK (``eigsh``) through the same factor where the block process does not
    apply (fewer than twice ``_columns(k)`` vertices, a breakdown, no convergence in ``_columns(k)``
    columns), and through scipy's LU where CHOLMOD finds the shifted matrix not positive definite in
    floating point."""
    n = mass.size
    M = sp.diags(mass).tocsc()
    try:
        factor = SparseCholesky((L - SHIFT * M).tocsc())
    except NotPositiveDefinite:
        factor = None
    found = _block_lanczos(factor.solve, mass, k) if factor is not None and 2 * _columns(k) <= n else None
    if found is None:
        start = np.full(n, 1.0 / np.sqrt(n))  # a fixed start vector: the same basis on every run
        inverse = None if factor is None else LinearOperator((n, n), matvec=factor.solve, dtype=np.float64)
        found = eigsh(L, k=k, M=M, sigma=SHIFT, which="LM", v0=start, OPinv=inverse)
    evals, evecs = found
    order = np.argsort(evals, kind="stable")
    evals, evecs = np.clip(evals[order], 0.0, None), evecs[:, order]
    big = np.argmax(np.abs(evecs), axis=0)
    evecs = evecs * np.where(evecs[big, np.arange(k)] < 0, -1.0, 1.0)
    return evals, evecs


def _columns(k: int) -> int:
    """The most columns the block Lanczos process keeps for ``k`` pairs, its last block included:
    converged (``BLOCK_TOL`` 1e-4) at 72, 128, 200–224 and 376–416 columns for k = 10, 30, 60 and
    150 on blobs of 642 to 10,242 vertices and at 416 for k = 150 at 52,565 vertices (TOSCA david0)."""
    return -(-(3 * k + 13 * BLOCK) // BLOCK) * BLOCK


def _block_lanczos(solve, mass: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The ``k`` largest eigenpairs of ``T = M^½ (L − σM)⁻¹ M^½`` by block Lanczos, as ``L φ = λ M φ``
    pairs (``λ = σ + 1/θ``, ``φ = M^-½ y``); None on a breakdown or without convergence in ``_columns(k)``
    columns.

    Hand-written rather than ARPACK's ``eigsh``: at 52,565 vertices and k = 150, eigsh spent 11.1 s
    CPU, of which 1.8 s in the 378 solves and about 8 s in ARPACK's one-vector reorthogonalisation and
    Ritz vectors (level-2 BLAS over an n × 301 basis, bound by memory bandwidth).  Here the solves
    come in blocks of ``BLOCK`` (2.5× cheaper a column) and the reorthogonalisation is one full
    classical Gram–Schmidt pass of matrix products after the three-term recurrence: 4.0–4.8 s CPU
    against eigsh's 12.8–13.2 s in one run (load 4.7), 376 columns; accuracy: ``BLOCK_TOL``.  Tried:
    eigsh's ``tol`` (1e-10, 1e-8, 1e-6: the same 378 solves, 10.4–11.5 s) and ``ncv`` (200:
    9.2 s, 351 solves; 160: 19.6 s; 400: 12.5 s); scipy's ``lobpcg`` with the factor
    as preconditioner stopped at its first iteration (its Gram matrices lost definiteness).

    Parameters
    ----------
    solve : ``x ↦ (L − σM)⁻¹ x`` for (n, b) blocks.
    mass : (n,) lumped masses.
    k : eigenpairs wanted.
    """
    n, b = mass.size, BLOCK
    root = np.sqrt(mass)[:, None]
    most = _columns(k) - b
    Q = np.empty((n, most + b), order="F")  # columns touched only as the space grows
    band = np.zeros((b + 1, most))  # the block tridiagonal projection Qᵀ T Q, lower band storage
    Q[:, :b] = qr(np.random.default_rng(0).standard_normal((n, b)), mode="economic")[0]
    rows = np.arange(b)[None, :] + np.arange(b + 1)[:, None]  # band[d, i] = H[i + d, i] in a block column
    below, check = None, k + b
    for m in range(b, most + 1, b):
        block = Q[:, m - b:m]
        W = root * solve(root * block)
        if below is not None:
            W -= Q[:, m - 2 * b:m - b] @ below.T
        A = block.T @ W
        A = (A + A.T) / 2
        W -= block @ A
        W -= Q[:, :m] @ (Q[:, :m].T @ W)  # full reorthogonalisation: against round-off
        Q[:, m:m + b], below = qr(W, mode="economic", check_finite=False)  # numpy's: 7× the CPU
        if np.abs(np.diag(below)).min() < 1e-10:  # an invariant subspace (T's norm is 1 / (0 − σ) = 1)
            return None
        band[:, m - b:m] = np.vstack([A, below])[rows, np.arange(b)[None, :]]
        if m >= check or m == most:
            theta, S = eig_banded(band[:, :m], lower=True, select="i", select_range=(m - k, m - 1))
            if np.all(np.linalg.norm(below @ S[m - b:], axis=0) <= BLOCK_TOL * theta):
                return SHIFT + 1.0 / theta, (Q[:, :m] @ S) / root
            check = int(1.1 * m)
    return None


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

"""Smallest eigenpairs of ``H v = lambda M v`` with fixed vertices, one factorisation for all.

Paper Sections 5 and 6 (landmarks remove the
rows and columns of their coordinates).

``A = H + s M`` (``s = SHIFT``, small, so A is positive definite even with
zero modes) is factorised once.  Fixing a set S of coordinates is a bordered
system: ``[A E; E^T 0][x; mu] = [b; 0]`` solved with the same factor and
``W = A^{-1} E`` (one block solve of 3 columns per fixed vertex), so adding a
landmark or trying a candidate costs three solves instead of a new
factorisation.  The eigenpairs come from ARPACK in shift-invert mode (k = 4,
ncv = 30, tol = 1e-8: ~31 solves).

Backends (``backend=``), picked by measurement (the table of factorisation and
solve times per backend and mesh size, and the alternatives tried, are in
the project's benchmark results, not shipped with the package):

* ``cholmod`` (default): CHOLMOD through ``cholespy``, a sub-1 MB wheel, 2.7x faster
  than SuperLU to factorise at 53k vertices and 2.2x per solve, about half the memory;
* ``superlu``: LU without pivoting in a geometric **nested-dissection ordering of the
  vertex graph** (``nested_dissection``; each vertex's three coordinates kept
  together; SciPy's own orderings are far slower here), used when CHOLMOD finds ``A``
  not positive definite in floating point, and as an independent check in the tests.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from .. import cholesky
from ..errors import InputError
from ..threads import one_blas_thread

SHIFT = 1e-5  # relative to the proximity stiffness 2 of the unit-area mesh
BACKENDS = ("cholmod", "superlu")


def default_backend() -> str:
    """``"cholmod"``: sparse Cholesky through cholespy (``"superlu"`` on request)."""
    return "cholmod"


def vertex_graph(H: sp.spmatrix) -> sp.csr_matrix:
    """Vertex adjacency of a (3n, 3n) matrix: i ~ j when any block (i, j) is stored."""
    C = H.tocoo()
    n = H.shape[0] // 3
    G = sp.csr_matrix((np.ones(C.nnz), (C.row // 3, C.col // 3)), shape=(n, n))
    G.data[:] = 1.0
    return G


def nested_dissection(V: np.ndarray, adj: sp.csr_matrix, leaf: int = 48) -> np.ndarray:
    """Fill-reducing vertex order: recursive median cuts across the principal axes.

    At each level the three median cuts (one per principal axis of the part)
    are tried and the one with the smallest separator kept (on david0 this cut
    the factor from 31.7M to 26.6M entries and its time by a third).

    Each cut's separator (vertices of one half adjacent, in the matrix graph
    ``adj``, to the other half) is numbered after both halves, as in George's
    nested dissection; on surface meshes the separators are short curves, so
    the factor stays small.  ``adj`` must be the graph of the matrix (for ARAP,
    whose Hessian couples 2-ring neighbours, the mesh edges would not separate).
    """
    n = V.shape[0]
    out: list[np.ndarray] = []
    stack = [(np.arange(n), False)]
    while stack:  # iterative post-order: children first, then the separator
        idx, is_sep = stack.pop()
        if is_sep or len(idx) <= leaf:
            out.append(idx)
            continue
        X = V[idx] - V[idx].mean(axis=0)
        _, _, vt = np.linalg.svd(X[:: max(1, len(idx) // 2000)], full_matrices=False)
        rows = adj[idx]
        best = None
        for axis in vt:  # the median cut across each principal axis; keep the smallest separator
            c = X @ axis
            left = c <= np.median(c)
            if left.all() or not left.any():
                continue
            in_right = np.zeros(n)
            in_right[idx[~left]] = 1.0
            touches = (rows @ in_right)[left] > 0
            if best is None or touches.sum() < best[0]:
                best = (touches.sum(), left, touches)
        if best is None:
            out.append(idx)
            continue
        _, left, touches = best
        a = idx[left]
        # pushed in reverse: left part, right part, then separator are emitted in that order
        stack.append((a[touches], True))
        stack.append((idx[~left], False))
        stack.append((a[~touches], False))
    order = np.concatenate(out) if out else np.zeros(0, dtype=np.int64)
    return order.astype(np.int64)


class ShiftInvertSolver:
    """Factor of ``A = H + SHIFT * M``, with fixed-vertex solves.

    Parameters
    ----------
    H : (3n, 3n) sparse symmetric positive semi-definite
    mass : (3n,) positive lumped mass diagonal
    V : (n, 3) vertex positions (for the SuperLU ordering)
    backend : "cholmod" (Cholesky, default when cholespy is installed) or "superlu"
        (LU without pivoting in a nested-dissection order); module docstring.
    """

    def __init__(self, H: sp.spmatrix, mass: np.ndarray, V: np.ndarray, shift: float = SHIFT,
                 backend: str | None = None):
        self.H = H.tocsr()
        self.mass = np.asarray(mass, dtype=np.float64)
        self.shift = float(shift)
        self.n_dof = self.H.shape[0]
        backend = default_backend() if backend is None else backend
        if backend not in BACKENDS:
            raise InputError(f"unknown solver backend {backend!r}; choose one of {', '.join(BACKENDS)}")
        A = self.H + sp.diags(self.shift * self.mass)
        self._chol = self.lu = None
        if backend == "cholmod":
            try:
                self._chol = cholesky.SparseCholesky(A)
            except cholesky.NotPositiveDefinite:  # LU does not need it
                backend = "superlu"
        if backend == "superlu":
            order = nested_dissection(V, vertex_graph(self.H))
            self.perm = (3 * order[:, None] + np.arange(3)).ravel()
            self.iperm = np.empty_like(self.perm)
            self.iperm[self.perm] = np.arange(self.n_dof)
            Ap = A.tocsc()[self.perm][:, self.perm].tocsc()
            self.lu = sla.splu(Ap, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                               options=dict(SymmetricMode=True))
        self.backend = backend
        self.n_solves = 0
        self._W: dict[int, np.ndarray] = {}  # dof -> column of A^{-1} e_dof

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``A^{-1} b`` for a vector or (3n, k) block."""
        self.n_solves += 1 if b.ndim == 1 else b.shape[1]
        if self._chol is not None:
            return self._chol.solve(b)
        return self.lu.solve(np.ascontiguousarray(b[self.perm]))[self.iperm]

    def _columns(self, dofs: np.ndarray) -> np.ndarray:
        missing = [int(d) for d in dofs if int(d) not in self._W]
        if missing:
            E = np.zeros((self.n_dof, len(missing)))
            E[missing, np.arange(len(missing))] = 1.0
            X = self.solve(E)
            for k, d in enumerate(missing):
                self._W[d] = X[:, k]
        return np.column_stack([self._W[int(d)] for d in dofs]) if len(dofs) else np.zeros((self.n_dof, 0))

    def constrained(self, fixed_vertices) -> "ConstrainedProblem":
        """The problem with the three coordinates of each vertex in ``fixed_vertices`` removed."""
        return ConstrainedProblem(self, np.asarray(sorted(set(int(v) for v in fixed_vertices)), dtype=np.int64))


class ConstrainedProblem:
    """``H_ff v = lambda M_ff v`` on the free coordinates, solved with the parent's factor."""

    def __init__(self, parent: ShiftInvertSolver, fixed: np.ndarray):
        self.parent = parent
        self.fixed = fixed
        self.fixed_dofs = (3 * fixed[:, None] + np.arange(3)).ravel()
        free = np.ones(parent.n_dof, dtype=bool)
        free[self.fixed_dofs] = False
        self.free = np.flatnonzero(free)
        self.W = parent._columns(self.fixed_dofs)           # A^{-1} E
        self.G = self.W[self.fixed_dofs] if len(self.fixed_dofs) else np.zeros((0, 0))  # E^T A^{-1} E

    def solve_free(self, b_free: np.ndarray) -> np.ndarray:
        """``(A_ff)^{-1} b`` through the bordered system (no refactorisation)."""
        b = np.zeros(self.parent.n_dof)
        b[self.free] = b_free
        x = self.parent.solve(b)
        if len(self.fixed_dofs):
            x -= self.W @ np.linalg.solve(self.G, x[self.fixed_dofs])
        return x[self.free]

    def eigenpairs(self, k: int, tol: float = 1e-8, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """The ``k`` smallest eigenpairs, ascending; vectors are M-orthonormal, (3n, k) with zeros on fixed dofs."""
        p = self.parent
        n_free = len(self.free)
        k = min(k, n_free - 1)
        H_ff = p.H[self.free][:, self.free]
        M_ff = sp.diags(p.mass[self.free]).tocsr()
        op = sla.LinearOperator((n_free, n_free), matvec=self.solve_free, dtype=np.float64)
        v0 = np.random.default_rng(seed).normal(size=n_free)
        with one_blas_thread():  # ARPACK's small BLAS calls thrash when threaded (20x measured)
            w, X = sla.eigsh(H_ff, k=k, M=M_ff, sigma=-p.shift, OPinv=op, which="LM", v0=v0,
                             tol=tol, ncv=min(n_free, max(2 * k + 1, 30)))
        order = np.argsort(w)
        w, X = w[order], X[:, order]
        full = np.zeros((p.n_dof, len(w)))
        full[self.free] = X
        # M-normalise (ARPACK returns M-orthonormal vectors already; make it exact)
        full /= np.sqrt(np.einsum("ik,i,ik->k", full, p.mass, full))[None, :]
        return np.maximum(w, 0.0), full

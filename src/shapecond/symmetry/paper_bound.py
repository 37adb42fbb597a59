"""DIAGNOSTIC ONLY: the paper's eigenvalue "bound" of Section 4.2 (not a bound).

The paper writes the symmetry score as a generalised Rayleigh quotient over
assignment indicators ``v`` (one entry per candidate assignment ``x -> y``):

    A[(x→y), (x'→y')] = (D[x,x'] − D[y,y'])²,      B = diag(D[x,y]²),

so that for the indicator ``v`` of a map T, ``vᵀ A v = Dist²(T)`` and
``vᵀ B v = d²(T)``, and proposes ``σ <= 1/sqrt(λ_0)`` with ``λ_0`` the smallest
generalised eigenvalue of ``A v = λ B v``.

Why this is NOT a bound: ``A`` has a zero diagonal (``x = x'``
and ``y = y'`` give ``(0 − 0)²``) and non-negative off-diagonal entries, so its
trace is 0 and, unless ``A = 0``, it has a negative eigenvalue.  ``B`` is
singular on the identity assignments ``x -> x``; on the remaining assignments
(where ``B`` is positive definite, which is where we solve) the restriction of
``A`` still has zero trace, so ``λ_0 < 0`` and ``1/sqrt(λ_0)`` is not even a real
number.  The relaxation drops the sign and 0/1 structure of ``v`` that makes
``vᵀ A v`` a distortion.  No cheap spectral upper bound is known: any relaxation
admitting orthogonal matrices admits ``V S Vᵀ`` (eigenvectors of D, signs S),
which commute with D and have zero distortion.  Use ``relax.lp_upper_bound``
for a valid upper bound.

This module computes the paper's quantities for small N so that users can see
this for themselves; ``paper_value`` is ``None`` whenever ``λ_0 <= 0``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.linalg import eigh

from ..jsonable import jsonable
from ..errors import TooLargeError
from .objective import check_instance

#: Largest N for the dense (N·M)-square eigenproblem of this diagnostic.
MAX_PAPER_POINTS = 20


@dataclass(frozen=True)
class PaperDiagnostic:
    """The paper's Section 4.2 quantities (diagnostic, not a bound).

    Attributes
    ----------
    lambda_0 : float
        Smallest generalised eigenvalue of ``A v = λ B v`` on the assignments
        with ``B > 0`` (all ``x -> y`` with ``D[x,y] > 0``).
    paper_value : float or None
        The paper's ``1/sqrt(λ_0)``; ``None`` when ``λ_0 <= 0`` (always, in
        practice).
    n_negative : int
        Number of negative generalised eigenvalues.
    trace_A : float
        Trace of ``A`` (zero by construction).
    n_assignments : int
    seconds : float
    is_bound : bool
        Always False: this is not an upper bound on σ.
    """

    lambda_0: float
    paper_value: float | None
    n_negative: int
    trace_A: float
    n_assignments: int
    seconds: float
    is_bound: bool = False

    def to_dict(self) -> dict:
        return jsonable({
            "diagnostic": "paper Section 4.2 eigenvalue quantity; NOT an upper bound",
            "lambda_0": self.lambda_0,
            "paper_value": self.paper_value,
            "n_negative": self.n_negative,
            "trace_A": self.trace_A,
            "n_assignments": self.n_assignments,
            "seconds": self.seconds,
            "is_bound": self.is_bound,
        })


def paper_matrices(D: np.ndarray, n: int):
    """(A, B diagonal, assignment list) over all ``x -> y`` (x < n, y < M)."""
    M = D.shape[0]
    xs, ys = np.divmod(np.arange(n * M), M)
    A = (D[np.ix_(xs, xs)] - D[np.ix_(ys, ys)]) ** 2
    b = D[xs, ys] ** 2
    return A, b, np.stack([xs, ys], axis=1)


def paper_eigen_diagnostic(D, n_samples=None) -> PaperDiagnostic:
    """The paper's λ_0 and 1/sqrt(λ_0) for a small instance (see module docstring).

    Raises
    ------
    TooLargeError
        Above ``MAX_PAPER_POINTS`` samples (the eigenproblem is dense, size N·M).
    """
    t0 = time.perf_counter()
    D, n, _ = check_instance(D, n_samples, ())
    if n > MAX_PAPER_POINTS or D.shape[0] > 4 * MAX_PAPER_POINTS:
        raise TooLargeError(
            f"the paper's eigenvalue diagnostic is a dense {n}x{D.shape[0]}-assignment eigenproblem; "
            f"limited to {MAX_PAPER_POINTS} samples"
        )
    A, b, _ = paper_matrices(D, n)
    keep = b > 0
    Ak, bk = A[np.ix_(keep, keep)], b[keep]
    # A v = λ B v with B = diag(b) > 0  <=>  B^{-1/2} A B^{-1/2} w = λ w.
    s = 1.0 / np.sqrt(bk)
    lam = eigh(Ak * s[:, None] * s[None, :], eigvals_only=True)
    lam0 = float(lam[0])
    value = 1.0 / math.sqrt(lam0) if lam0 > 0 else None
    return PaperDiagnostic(lam0, value, int(np.sum(lam < 0)), float(np.trace(A)), int(keep.sum()),
                           time.perf_counter() - t0)


__all__ = ["paper_eigen_diagnostic", "PaperDiagnostic", "paper_matrices", "MAX_PAPER_POINTS"]

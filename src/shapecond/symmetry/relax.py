"""LP upper bound on the global symmetry score (paper Section 4.2; DESIGN.md 2.2).

σ(X)² = max_{T ≠ Id} d²(T) / Dist²(T) is a quadratic fractional assignment
problem.  We relax it to the Adams–Johnson / RLT-1 linear program (the local
marginal polytope) the paper solves, over

- assignment variables ``x[i, a]`` (free sample i goes to free target a), and
- pair variables ``y[(i,a),(j,b)]`` for ``i < j``, ``a != b`` (both happen),

with constraints

- rows ``Σ_a x[i,a] = 1``; columns ``Σ_i x[i,a] = 1`` (``<= 1`` when there are
  more targets than samples, issue 4's injective maps);
- pair marginals over rows: ``Σ_a y[(i,a),(j,b)] = x[j,b]`` for every ordered
  ``i != j`` and every ``b``;
- pair marginals over columns: ``Σ_{i != j} y[(i,a),(j,b)] = x[j,b]`` (``<=``
  for injective maps) for every ``(j, b)`` and ``a != b``.  Without them the
  bound is 1.1–1.7× loose (DESIGN.md 2.2);
- the identity cut ``Σ_i x[i,i] <= f − 2`` (``f`` free samples; ``f − 1`` for
  injective maps, where moving one sample to a non-sample target is allowed),
  which removes the identity from the relaxation as Eq. 5 removes it from the
  sup.  Landmarks are fixed to themselves and eliminated: their pairs with a
  free sample give a linear term.

Every non-identity map is a 0/1 point of this polytope with ``y = x ⊗ x``, on
which d² is linear in ``x`` and Dist² linear in ``(x, y)``.  The ratio is
maximised with one Charnes–Cooper LP: with ``τ = 1 / Dist²`` and ``(X, Y) =
τ (x, y)``, maximise ``d²(X)`` subject to ``Dist²(X, Y) = 1`` and the
constraints above with right-hand sides multiplied by ``τ``.  This equals the
paper's bisection on the ratio and costs one solve instead of ~10.  The LP is
unbounded exactly when the relaxation contains a point with Dist² = 0 and
d² > 0 (an isometry): the bound is then ``inf``, consistent with
``exact_sigma``.  The LP value is an upper bound on σ²; we report its square
root, enlarged by the relative solver tolerance ``SAFETY`` (HiGHS works to
feasibility tolerances of 1e-9, so the computed optimum may sit that far below
the true one).  An LP value so large that a map attaining it could be an
isometry within ``objective.ISOMETRY_RTOL`` is reported as ``inf``.

Size: ``f·r + C(f,2)·r(r−1)`` variables (29 057 for 16 points); HiGHS took
<= 0.1 s at N = 8, 0.2–4 s at N = 12 and 5–90 s at N = 16 in DESIGN.md.
``MAX_LP_POINTS`` is set from the measurements in ``benchmarks/bench_exact_lp.py``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from ..errors import TooLargeError
from . import objective
from .exact import check_instance

#: Largest number of free points (bijection case) the LP is built for unless forced.
MAX_LP_POINTS = 16
#: Relative enlargement of the reported bound covering HiGHS's tolerances.
SAFETY = 1e-7


@dataclass(frozen=True)
class LPResult:
    """Outcome of ``lp_upper_bound``: ``upper`` >= σ(X) (``math.inf`` possible)."""

    upper: float
    seconds: float
    n_variables: int
    status: str
    n_constraints: int = 0

    def to_dict(self) -> dict:
        return {
            "upper": self.upper,
            "seconds": self.seconds,
            "n_variables": self.n_variables,
            "n_constraints": self.n_constraints,
            "status": self.status,
        }


def lp_size(n_free: int, n_targets: int) -> int:
    """Number of LP variables for ``n_free`` samples into ``n_targets`` targets."""
    f, r = n_free, n_targets
    return f * r + (f * (f - 1) // 2) * r * (r - 1) + 1


def build_lp(D: np.ndarray, n: int, landmarks=()):
    """Charnes–Cooper form of the RLT-1 relaxation.

    Returns ``(c, A_eq, b_eq, A_ub, b_ub)`` for ``linprog`` (minimise ``c·z``,
    ``z >= 0``); the last variable is ``τ``.
    """
    M = D.shape[0]
    L = np.asarray(list(landmarks), dtype=np.int64)
    F = np.setdiff1d(np.arange(n), L)
    R = np.setdiff1d(np.arange(M), L)
    f, r = F.size, R.size
    inj = r > f
    nx = f * r
    # Pair variables (i, a, j, b) with i < j, a != b, flattened.
    ii, jj = np.triu_indices(f, 1)
    aa, bb = np.nonzero(~np.eye(r, dtype=bool))
    I = np.repeat(ii, aa.size)
    J = np.repeat(jj, aa.size)
    A_ = np.tile(aa, ii.size)
    B_ = np.tile(bb, ii.size)
    ny = I.size
    yid = nx + np.arange(ny)
    tau = nx + ny
    nvar = nx + ny + 1
    xid = lambda i, a: i * r + a  # noqa: E731

    # Objective: maximise d²(X)  ->  minimise −d².
    c = np.zeros(nvar)
    c[:nx] = -(D[np.ix_(F, R)] ** 2).ravel()
    # Normalisation Dist²(X, Y) = 1 (ordered pairs: factor 2).
    q = np.zeros(nvar)
    if L.size:
        q[:nx] = 2.0 * ((D[np.ix_(L, F)][:, :, None] - D[np.ix_(L, R)][:, None, :]) ** 2).sum(0).ravel()
    q[yid] = 2.0 * (D[F[I], F[J]] - D[R[A_], R[B_]]) ** 2

    eq_rows, eq_cols, eq_vals = [], [], []
    ub_rows, ub_cols, ub_vals = [], [], []
    n_eq = 0
    n_ub = 0

    def add(rows, cols, vals, equality):
        (eq_rows if equality else ub_rows).append(rows)
        (eq_cols if equality else ub_cols).append(cols)
        (eq_vals if equality else ub_vals).append(np.broadcast_to(vals, np.shape(rows)).astype(float))

    # Normalisation row (equality 0).
    nz = np.flatnonzero(q)
    add(np.zeros(nz.size, dtype=np.int64), nz, q[nz], True)
    n_eq = 1
    # Rows: Σ_a X[i,a] − τ = 0.
    i_, a_ = np.divmod(np.arange(nx), r)
    add(n_eq + i_, xid(i_, a_), 1.0, True)
    add(n_eq + np.arange(f), np.full(f, tau), -1.0, True)
    n_eq += f
    # Columns: Σ_i X[i,a] − τ (= or <=) 0.
    if inj:
        add(n_ub + a_, xid(i_, a_), 1.0, False)
        add(n_ub + np.arange(r), np.full(r, tau), -1.0, False)
        n_ub += r
    else:
        add(n_eq + a_, xid(i_, a_), 1.0, True)
        add(n_eq + np.arange(r), np.full(r, tau), -1.0, True)
        n_eq += r
    # Row marginals rm(i, j, b): Σ_a Y[(i,a),(j,b)] − X[j,b] = 0 for ordered i != j.
    rm = lambda i, j, b: (i * f + j) * r + b  # noqa: E731
    oi, oj = np.nonzero(~np.eye(f, dtype=bool))
    ob = np.tile(np.arange(r), oi.size)
    oi_r, oj_r = np.repeat(oi, r), np.repeat(oj, r)
    rows_rm = np.concatenate([rm(I, J, B_), rm(J, I, A_), rm(oi_r, oj_r, ob)])
    cols_rm = np.concatenate([yid, yid, xid(oj_r, ob)])
    vals_rm = np.concatenate([np.ones(2 * ny), -np.ones(oi_r.size)])
    uniq, inv = np.unique(rows_rm, return_inverse=True)
    add(n_eq + inv, cols_rm, vals_rm, True)
    n_eq += uniq.size
    # Column marginals cm(j, b, a), a != b: Σ_{i != j} Y[(i,a),(j,b)] − X[j,b] (= or <=) 0.
    cm = lambda j, b, a: (j * r + b) * r + a  # noqa: E731
    cj = np.repeat(np.arange(f), aa.size)
    cb, ca = np.tile(bb, f), np.tile(aa, f)
    rows_cm = np.concatenate([cm(J, B_, A_), cm(I, A_, B_), cm(cj, cb, ca)])
    cols_cm = np.concatenate([yid, yid, xid(cj, cb)])
    vals_cm = np.concatenate([np.ones(2 * ny), -np.ones(cj.size)])
    uniq, inv = np.unique(rows_cm, return_inverse=True)
    if inj:
        add(n_ub + inv, cols_cm, vals_cm, False)
        n_ub += uniq.size
    else:
        add(n_eq + inv, cols_cm, vals_cm, True)
        n_eq += uniq.size
    # Identity cut: Σ_i X[i, pos(F_i)] − (f − 2 or f − 1) τ <= 0.
    pos = np.searchsorted(R, F)
    add(np.full(f, n_ub), xid(np.arange(f), pos), 1.0, False)
    add(np.array([n_ub]), np.array([tau]), -float(f - (1 if inj else 2)), False)
    n_ub += 1

    def mat(rows, cols, vals, nrow):
        return sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(nrow, nvar)
        )

    A_eq = mat(eq_rows, eq_cols, eq_vals, n_eq)
    b_eq = np.zeros(n_eq)
    b_eq[0] = 1.0
    A_ub = mat(ub_rows, ub_cols, ub_vals, n_ub)
    b_ub = np.zeros(n_ub)
    return c, A_eq, b_eq, A_ub, b_ub


def lp_upper_bound(D, n_samples=None, landmarks=(), force=False, time_limit=None) -> LPResult:
    """Upper bound on σ(X) from the RLT-1 LP relaxation (see module docstring).

    Parameters
    ----------
    D : (M, M) array_like
        Distance matrix; the first ``n_samples`` points are the samples.
    n_samples : int, optional
        N (default M).
    landmarks : sequence of int
        Samples fixed by every map.
    force : bool
        Build the LP even above ``MAX_LP_POINTS``.
    time_limit : float, optional
        Seconds for HiGHS; when hit the bound is ``inf`` (status ``"time-limit"``).

    Raises
    ------
    TooLargeError
        When the LP has more variables than for ``MAX_LP_POINTS`` points and
        ``force`` is False.
    """
    t0 = time.perf_counter()
    D, n, L = check_instance(D, n_samples, landmarks)
    M = D.shape[0]
    f, r = n - len(L), M - len(L)
    nvar = lp_size(f, r)
    if not force and nvar > lp_size(MAX_LP_POINTS, MAX_LP_POINTS):
        raise TooLargeError(
            f"LP relaxation for {f} free samples into {r} targets has {nvar} variables, "
            f"above the limit for {MAX_LP_POINTS} points; use --force (force=True) to run it anyway"
        )
    if f == 0 or (f < 2 and r == f):
        return LPResult(0.0, time.perf_counter() - t0, 0, "no-map")
    c, A_eq, b_eq, A_ub, b_ub = build_lp(D, n, L)
    options = {"primal_feasibility_tolerance": 1e-9, "dual_feasibility_tolerance": 1e-9}
    if time_limit is not None:
        options["time_limit"] = float(time_limit)
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=(0, None),
                  method="highs", options=options)
    ncon = A_eq.shape[0] + A_ub.shape[0]
    seconds = time.perf_counter() - t0
    if res.status == 3:
        return LPResult(math.inf, seconds, nvar, "unbounded (isometry in the relaxation)", ncon)
    if res.status != 0:
        status = "time-limit" if res.status == 1 else f"solver failed: {res.message}"
        return LPResult(math.inf, seconds, nvar, status, ncon)
    value = max(-float(res.fun), 0.0)
    if value >= _isometry_ratio(D, n):
        return LPResult(math.inf, seconds, nvar, "optimal (ratio at isometry level)", ncon)
    return LPResult(math.sqrt(value) * (1.0 + SAFETY), seconds, nvar, "optimal", ncon)


def _isometry_ratio(D: np.ndarray, n: int) -> float:
    """σ² above which a map could be an isometry within ``ISOMETRY_RTOL``.

    A map with ``d² >= dmin²`` (``dmin`` the smallest nonzero sample-target
    distance) and ``Dist² <= RTOL² ‖D_XX‖²`` has ratio ``>= dmin² / (RTOL² ‖D_XX‖²)``.
    """
    rows = D[:n, :]
    pos = rows[rows > 0]
    if pos.size == 0:
        return math.inf
    return float(pos.min()) ** 2 / ((objective.ISOMETRY_RTOL**2) * float(np.sum(D[:n, :n] ** 2)))


__all__ = ["LPResult", "lp_upper_bound", "MAX_LP_POINTS", "build_lp", "lp_size"]

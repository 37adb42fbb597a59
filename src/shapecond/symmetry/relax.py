"""LP upper bound on the global symmetry score (paper Section 4.2).

σ(X)² = max_{T ≠ Id} d²(T) / Dist²(T) is a quadratic fractional assignment
problem.  We relax it to the Adams–Johnson / RLT-1 linear program (the local
marginal polytope) the paper solves, over

- assignment variables ``x[i, a]`` (free sample i goes to free target a), and
- pair variables ``y[(i,a),(j,b)]`` for ``i < j``, ``a != b`` (both happen),

with constraints

- rows ``Σ_a x[i,a] = 1``; columns ``Σ_i x[i,a] = 1`` (``<= 1`` when there are
  more targets than samples, injective maps);
- pair marginals over rows: ``Σ_a y[(i,a),(j,b)] = x[j,b]`` for every ordered
  ``i != j`` and every ``b``;
- pair marginals over columns: ``Σ_{i != j} y[(i,a),(j,b)] = x[j,b]`` (``<=``
  for injective maps) for every ``(j, b)`` and ``a != b``.  Without them the
  bound is 1.1–1.7× loose;
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

Triangle cuts (beyond the paper).  The local marginal polytope admits
"frustrated" points: three blocks of samples, each a 50/50 mixture of two
sub-maps, whose pair variables couple the blocks pairwise in a way no joint
distribution over maps can (the odd-cycle defect of pairwise relaxations).  On
200 random and near-symmetric N = 8 instances this made the plain RLT-1 bound
up to 1.14× loose (4 instances above 1.01), against 1.0065 measured on other
instances by the first prototype.  We therefore add, in rounds until none is
violated, the triangle inequalities of the boolean quadric polytope for
assignments ``u, v, w`` of three distinct samples to three distinct targets::

    x_u + x_v + x_w − y_uv − y_uw − y_vw <= 1,     y_uv + y_uw − y_vw <= x_u,

valid for every 0/1 point with ``y = x ⊗ x`` (homogenised by ``τ``), separated
on the support of the current solution and re-solved warm-started in HiGHS.
They remove the defect (worst ratio 1.000001 on the same 200 instances);
``cuts=False`` gives the paper's LP.

Size: ``f·r + C(f,2)·r(r−1)`` variables (29 057 for 16 points); HiGHS took
<= 0.1 s at N = 8, 0.2–4 s at N = 12 and 5–90 s at N = 16 in the prototype.
Measured by the project's benchmarks (2 shared cores, three runs): 0.03–0.05 s
at N = 8, 0.2–3.8 s at N = 12, 0.6–16.5 s at N = 14, 1.3–251 s at N = 16 (uniform
random point sets are the slow case; near-symmetric ones take ~2 s), peak memory
~330 MB at N = 16; the variable count doubles every two points, so ``MAX_LP_POINTS = 16``.
"""

from __future__ import annotations

import itertools
import math
import os
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import highspy

from ..errors import TooLargeError
from ..output import stdout_fd_diverted
from . import objective
from ._result import FieldsToDict
from .objective import check_instance

#: Largest number of free points (bijection case) the LP is built for unless forced.
MAX_LP_POINTS = 16
#: Relative enlargement of the reported bound covering HiGHS's tolerances.
SAFETY = 1e-7


@dataclass(frozen=True)
class LPResult(FieldsToDict):
    """Outcome of ``lp_upper_bound``: ``upper`` >= σ(X) (``math.inf`` possible)."""

    upper: float
    seconds: float
    n_variables: int
    status: str
    n_constraints: int = 0
    n_cuts: int = 0


def lp_size(n_free: int, n_targets: int) -> int:
    """Number of LP variables for ``n_free`` samples into ``n_targets`` targets."""
    f, r = n_free, n_targets
    return f * r + (f * (f - 1) // 2) * r * (r - 1) + 1


class _Variables:
    """The LP's variables (module docstring): ``X[i, a]`` (free sample i to free target a) at
    ``xid(i, a)``, then the pair variables ``Y[(i,a),(j,b)]``, i < j, a != b, at ``yid`` (in the
    order of ``I, J, A, B``), then ``τ``."""

    def __init__(self, f, r):
        self.f, self.r = f, r
        self.nx = f * r
        ii, jj = np.triu_indices(f, 1)
        self.aa, self.bb = np.nonzero(~np.eye(r, dtype=bool))
        self.I, self.J = np.repeat(ii, self.aa.size), np.repeat(jj, self.aa.size)
        self.A, self.B = np.tile(self.aa, ii.size), np.tile(self.bb, ii.size)
        self.ny = self.I.size
        self.yid = self.nx + np.arange(self.ny)
        self.tau = self.nx + self.ny
        self.nvar = self.nx + self.ny + 1

    def xid(self, i, a):
        return i * self.r + a


class _Rows:
    """Constraint rows being assembled: equalities (``True``) and inequalities ``<= 0`` (``False``),
    each kind numbered in the order its rows are added."""

    def __init__(self):
        self.parts = {True: ([], [], []), False: ([], [], [])}
        self.count = {True: 0, False: 0}

    def add(self, equality, n_rows, *entries):
        """``n_rows`` more rows of a kind; each entry ``(row, column, value)`` (arrays, or a scalar
        value), rows numbered from 0 within the new ones."""
        rows, cols, vals = self.parts[equality]
        for r, c, v in entries:
            rows.append(self.count[equality] + r)
            cols.append(c)
            vals.append(np.broadcast_to(v, np.shape(r)).astype(float))
        self.count[equality] += n_rows

    def matrix(self, equality, nvar):
        rows, cols, vals = self.parts[equality]
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(self.count[equality], nvar))


def _normalisation(D, L, F, R, v):
    """Coefficients of Dist²(X, Y) (Eq. 3, ordered pairs: factor 2); a landmark's pairs with a free
    sample give a linear term in X."""
    q = np.zeros(v.nvar)
    if L.size:
        q[:v.nx] = 2.0 * ((D[np.ix_(L, F)][:, :, None] - D[np.ix_(L, R)][:, None, :]) ** 2).sum(0).ravel()
    q[v.yid] = 2.0 * (D[F[v.I], F[v.J]] - D[R[v.A], R[v.B]]) ** 2
    return q


def _marginals(v, key_first, key_second, key_x, x_cols):
    """Marginal rows ``Σ Y − X[j,b]``, one per key: each pair variable enters the row keyed by
    ``key_first`` and the one keyed by ``key_second`` (one per end of the pair), each ``X`` (columns
    ``x_cols``) the row of ``key_x`` with coefficient −1; rows numbered by increasing key.
    Returns ``(n_rows, entry)`` for ``_Rows.add``."""
    keys = np.concatenate([key_first, key_second, key_x])
    cols = np.concatenate([v.yid, v.yid, x_cols])
    vals = np.concatenate([np.ones(2 * v.ny), -np.ones(key_x.size)])
    uniq, inv = np.unique(keys, return_inverse=True)
    return uniq.size, (inv, cols, vals)


def _row_marginals(v):
    """Rows rm(i, j, b) = (i f + j) r + b: Σ_a Y[(i,a),(j,b)] − X[j,b] = 0 for ordered i != j."""
    f, r = v.f, v.r
    oi, oj = np.nonzero(~np.eye(f, dtype=bool))
    ob = np.tile(np.arange(r), oi.size)
    oi_r, oj_r = np.repeat(oi, r), np.repeat(oj, r)
    return _marginals(v, (v.I * f + v.J) * r + v.B, (v.J * f + v.I) * r + v.A, (oi_r * f + oj_r) * r + ob,
                      v.xid(oj_r, ob))


def _column_marginals(v):
    """Rows cm(j, b, a) = (j r + b) r + a, a != b: Σ_{i != j} Y[(i,a),(j,b)] − X[j,b] (= or <=) 0."""
    f, r = v.f, v.r
    cj = np.repeat(np.arange(f), v.aa.size)
    cb, ca = np.tile(v.bb, f), np.tile(v.aa, f)
    return _marginals(v, (v.J * r + v.B) * r + v.A, (v.I * r + v.A) * r + v.B, (cj * r + cb) * r + ca,
                      v.xid(cj, cb))


def build_lp(D: np.ndarray, n: int, landmarks=()):
    """Charnes–Cooper form of the RLT-1 relaxation (module docstring).

    Returns ``(c, A_eq, b_eq, A_ub, b_ub)`` for ``linprog`` (minimise ``c·z``,
    ``z >= 0``); the last variable is ``τ``.
    """
    M = D.shape[0]
    L = np.asarray(list(landmarks), dtype=np.int64)
    F = np.setdiff1d(np.arange(n), L)
    R = np.setdiff1d(np.arange(M), L)
    v = _Variables(F.size, R.size)
    f, r, tau = v.f, v.r, v.tau
    inj = r > f
    # Objective: maximise d²(X)  ->  minimise −d².
    c = np.zeros(v.nvar)
    c[:v.nx] = -(D[np.ix_(F, R)] ** 2).ravel()
    rows = _Rows()
    # Normalisation Dist²(X, Y) = 1 (equality 0).
    q = _normalisation(D, L, F, R, v)
    nz = np.flatnonzero(q)
    rows.add(True, 1, (np.zeros(nz.size, dtype=np.int64), nz, q[nz]))
    # Rows Σ_a X[i,a] − τ = 0; columns Σ_i X[i,a] − τ (= or, injective maps, <=) 0.
    i_, a_ = np.divmod(np.arange(v.nx), r)
    rows.add(True, f, (i_, v.xid(i_, a_), 1.0), (np.arange(f), np.full(f, tau), -1.0))
    rows.add(not inj, r, (a_, v.xid(i_, a_), 1.0), (np.arange(r), np.full(r, tau), -1.0))
    rows.add(True, *_row_marginals(v))
    rows.add(not inj, *_column_marginals(v))
    # Identity cut: Σ_i X[i, pos(F_i)] − (f − 2 or f − 1) τ <= 0.
    pos = np.searchsorted(R, F)
    rows.add(False, 1, (np.zeros(f, dtype=np.int64), v.xid(np.arange(f), pos), 1.0),
             (np.array([0]), np.array([tau]), -float(f - (1 if inj else 2))))
    b_eq = np.zeros(rows.count[True])
    b_eq[0] = 1.0
    return c, rows.matrix(True, v.nvar), b_eq, rows.matrix(False, v.nvar), np.zeros(rows.count[False])


def lp_upper_bound(D, n_samples=None, landmarks=(), force=False, time_limit=None, cuts=True) -> LPResult:
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
        Seconds for HiGHS (all rounds).  When hit during the first solve the
        bound is ``inf`` (status ``"time-limit"``); during a cut round, the
        previous round's optimum (a valid, slightly looser bound) is returned.
    cuts : bool
        Add violated triangle inequalities (module docstring) in rounds.

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
    h, n_rows = _highs_model(*build_lp(D, n, L))
    ceiling = _isometry_ratio(D, n)
    separate = _TriangleSeparator(n, M, L) if cuts else None
    value, status, n_cuts = _solve_in_rounds(h, separate, ceiling, t0, time_limit)
    ncon = n_rows + n_cuts
    if status == "unbounded":
        return LPResult(math.inf, time.perf_counter() - t0, nvar, "unbounded (isometry in the relaxation)", ncon,
                        n_cuts)
    if value is None:  # not even the first round finished
        return LPResult(math.inf, time.perf_counter() - t0, nvar, "time-limit" if status == "optimal" else status,
                        ncon, n_cuts)
    if status != "optimal":
        status = f"optimal before the last cut round ({status})"
    seconds = time.perf_counter() - t0
    if value >= ceiling:
        return LPResult(math.inf, seconds, nvar, "optimal (ratio at isometry level)", ncon, n_cuts)
    return LPResult(math.sqrt(value) * (1.0 + SAFETY), seconds, nvar, status, ncon, n_cuts)


def _highs_model(c, A_eq, b_eq, A_ub, b_ub):
    """A HiGHS instance holding the LP ``min c·z, A_eq z = b_eq, A_ub z <= b_ub, z >= 0`` at the
    tolerances of the module docstring; returns it with its number of rows."""
    A = sp.vstack([A_eq, A_ub]).tocsc()
    with stdout_fd_diverted(os.devnull):  # highspy 1.16 prints its banner on fd 1 when the instance is made
        h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("log_to_console", False)
    h.setOptionValue("primal_feasibility_tolerance", 1e-9)
    h.setOptionValue("dual_feasibility_tolerance", 1e-9)
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = int(c.size), int(A.shape[0])
    lp.col_cost_ = c
    lp.col_lower_ = np.zeros(c.size)
    lp.col_upper_ = np.full(c.size, highspy.kHighsInf)
    lp.row_lower_ = np.concatenate([b_eq, np.full(b_ub.size, -highspy.kHighsInf)])
    lp.row_upper_ = np.concatenate([b_eq, b_ub])
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_ = A.indptr
    lp.a_matrix_.index_ = A.indices
    lp.a_matrix_.value_ = A.data
    h.passModel(lp)
    return h, A.shape[0]


def _solve_in_rounds(h, separate, ceiling, t0, time_limit):
    """Solve, then, with a ``separate``-or, add the violated triangle inequalities and solve again
    until none is violated or the value reaches ``ceiling`` (an isometry's ratio).

    Returns ``(value, status, n_cuts)``: the optimum of the last round solved (None when not
    even the first finished; an upper bound whatever follows) and "optimal", "unbounded",
    "time-limit" or the solver's status of the round that did not finish.
    """
    n_cuts, value = 0, None
    while True:
        if time_limit is not None:
            left = float(time_limit) - (time.perf_counter() - t0)
            if left <= 0:
                return value, "optimal", n_cuts
            h.setOptionValue("time_limit", left)
        h.run()
        status = h.getModelStatus()
        if status in (highspy.HighsModelStatus.kUnbounded, highspy.HighsModelStatus.kUnboundedOrInfeasible):
            return value, "unbounded", n_cuts
        if status != highspy.HighsModelStatus.kOptimal:
            return value, ("time-limit" if status == highspy.HighsModelStatus.kTimeLimit
                           else f"solver: {h.modelStatusToString(status)}"), n_cuts
        value = max(-float(h.getInfo().objective_function_value), 0.0)
        if separate is None or value >= ceiling:
            return value, "optimal", n_cuts
        rows = separate(np.asarray(h.getSolution().col_value))
        if rows is None:
            return value, "optimal", n_cuts
        h.addRows(rows.shape[0], np.full(rows.shape[0], -highspy.kHighsInf), np.zeros(rows.shape[0]),
                  rows.nnz, rows.indptr.astype(np.int32), rows.indices.astype(np.int32), rows.data)
        n_cuts += rows.shape[0]


class _TriangleSeparator:
    """Most violated triangle inequalities of the current LP point (module docstring).

    For assignments u = (i,a), v = (j,b), w = (k,c) with distinct samples and
    distinct targets, in Charnes–Cooper variables:

        X_u + X_v + X_w − Y_uv − Y_uw − Y_vw − τ <= 0
        Y_uv + Y_uw − Y_vw − X_u <= 0      (and its two rotations)
    """

    MAX_ROWS = 400
    TOL = 1e-7

    def __init__(self, n, M, L):
        Ls = set(L)
        self.F = np.asarray([x for x in range(n) if x not in Ls])
        self.R = np.asarray([y for y in range(M) if y not in Ls])
        self.f, self.r = self.F.size, self.R.size
        self.nx = self.f * self.r
        self.tau = lp_size(self.f, self.r) - 1

    def yid(self, i, a, j, b):
        """Variable index of Y[(i,a),(j,b)] (i != j, a != b), vectorised."""
        swap = i > j
        i, j, a, b = np.where(swap, j, i), np.where(swap, i, j), np.where(swap, b, a), np.where(swap, a, b)
        f, r = self.f, self.r
        pair = i * f - i * (i + 1) // 2 + (j - i - 1)
        off = a * (r - 1) + np.where(b < a, b, b - 1)
        return self.nx + pair * (r * (r - 1)) + off

    def __call__(self, z):
        tau = z[self.tau]
        if tau <= 0:
            return None
        x = z[: self.nx] / tau
        sup = np.flatnonzero(x > 1e-6)
        if sup.size < 3:
            return None
        si, sa = np.divmod(sup, self.r)
        T = np.array(list(itertools.combinations(range(sup.size), 3)), dtype=np.int64)
        p, q, s_ = T[:, 0], T[:, 1], T[:, 2]
        ok = ((si[p] != si[q]) & (si[p] != si[s_]) & (si[q] != si[s_])
              & (sa[p] != sa[q]) & (sa[p] != sa[s_]) & (sa[q] != sa[s_]))
        p, q, s_ = p[ok], q[ok], s_[ok]
        if p.size == 0:
            return None
        ypq = self.yid(si[p], sa[p], si[q], sa[q])
        yps = self.yid(si[p], sa[p], si[s_], sa[s_])
        yqs = self.yid(si[q], sa[q], si[s_], sa[s_])
        xp, xq, xs = sup[p], sup[q], sup[s_]
        v = z / tau
        cands = [  # (violation, columns, coefficients)
            (v[xp] + v[xq] + v[xs] - v[ypq] - v[yps] - v[yqs] - 1.0,
             [xp, xq, xs, ypq, yps, yqs], [1, 1, 1, -1, -1, -1], True),
            (v[ypq] + v[yps] - v[yqs] - v[xp], [ypq, yps, yqs, xp], [1, 1, -1, -1], False),
            (v[ypq] + v[yqs] - v[yps] - v[xq], [ypq, yqs, yps, xq], [1, 1, -1, -1], False),
            (v[yps] + v[yqs] - v[ypq] - v[xs], [yps, yqs, ypq, xs], [1, 1, -1, -1], False),
        ]
        viol = np.concatenate([cnd[0] for cnd in cands])
        order = np.argsort(-viol)
        order = order[viol[order] > self.TOL][: self.MAX_ROWS]
        if order.size == 0:
            return None
        rows, cols, vals = [], [], []
        m = p.size
        for k_out, g in enumerate(order):
            kind, t = divmod(int(g), m)
            _, colset, coefs, with_tau = cands[kind]
            cs = [int(col[t]) for col in colset]
            cf = list(coefs)
            if with_tau:
                cs.append(self.tau)
                cf.append(-1)
            rows += [k_out] * len(cs)
            cols += cs
            vals += cf
        return sp.csr_matrix((np.asarray(vals, float), (rows, cols)), shape=(order.size, self.tau + 1))


def _isometry_ratio(D: np.ndarray, n: int) -> float:
    """σ² above which a map could be an isometry within ``ISOMETRY_RTOL``.

    A map with ``d² >= dmin²`` (``dmin`` the smallest nonzero sample-target
    distance) and ``Dist² <= RTOL² ‖D_XX‖²`` has ratio ``>= dmin² / (RTOL² ‖D_XX‖²)``.
    """
    rows = D[:n, :]
    pos = rows[rows > 0]
    if pos.size == 0:
        return math.inf
    return float(pos.min()) ** 2 / objective.isometry_floor(D, n)


__all__ = ["LPResult", "lp_upper_bound", "MAX_LP_POINTS", "build_lp", "lp_size"]

"""Branch and bound for the exact global symmetry score (DESIGN.md section 3).

We maximise the ratio ``r(T) = d²(T) / Dist²(T)`` (σ² of Eq. 5) over injective
maps ``T`` of the samples into the targets that fix every landmark and are not
the identity.  One depth-first tree is searched with a *moving* Dinkelbach
parameter ``s``: the incumbent ratio.  A map beats the incumbent iff

    F_s(T) = d²(T) − s · Dist²(T) > 0,

so a node is pruned as soon as an upper bound of ``F_s`` over its completions is
``<= 0``.  ``s`` only grows during the search, and ``F_s`` is non-increasing in
``s`` (``Dist² >= 0``), so a node pruned with an older ``s`` stays pruned: when
the tree is exhausted the incumbent is optimal.  The identity has ``F_s = 0``
and is never accepted, which excludes it from the sup as Eq. 5 requires.

Node bound (validity argument)
------------------------------
At a node the samples split into assigned ``A`` (landmarks included, with their
images ``T a``) and unassigned ``U``; ``R`` are the targets not yet used.  For
any completion ``T`` of the node, splitting the ordered pairs of Eq. 3 into
``A×A``, ``A×U`` plus ``U×A`` (equal by symmetry of ``D``), and ``U×U``::

    F_s(T) = [Σ_A D[a,Ta]² − s Σ_{A×A} (D[a,a'] − D[Ta,Ta'])²]          (constant)
           + Σ_{u∈U} (D[u,Tu]² − 2 s C1[u,Tu])                          (linear)
           − s Σ_{u∈U} Σ_{u'∈U} (D[u,u'] − D[Tu,Tu'])²                  (quadratic)

with ``C1[u,y] = Σ_{a∈A} (D[u,a] − D[y,Ta])²``.  For fixed ``u`` and ``y = Tu``
the inner sum of the quadratic part pairs the multiset ``a = D[u,U]`` with
``|U|`` distinct entries of ``b = D[y,R]``.  By the rearrangement inequality,

    Σ_i (a_i − b_π(i))² >= Σ a_i² + (sum of the |U| smallest b_j²)
                          − 2 · ⟨sort(a), sort(largest |U| entries of b)⟩ =: GL[u,y]

(the Gilmore–Lawler sorted-row bound; with ``|R| == |U|`` it is the exact
minimum over bijections, sorted against sorted).  Hence, since ``s >= 0``,

    F_s(T) <= const + Σ_u P[u, Tu],   P = W − s (2 C1 + GL),   W[u,y] = D[u,y]²,

and ``T`` restricted to ``U`` is an injective assignment ``U → R``, so the
linear assignment maximum of ``P`` (``scipy.optimize.linear_sum_assignment``)
bounds ``F_s`` over every completion.  The LAP solution is itself a complete
map and is evaluated as a primal candidate at every node.  A child ``T u = y``
is discarded before it is visited when ``const + P[u, y]`` plus the assignment
maximum of ``P`` without row ``u`` and column ``y`` is ``<= tol``: the same
bound restricted to the completions with ``T u = y``.

Floating point: a node is pruned when its bound is ``<= tol`` with
``tol = 1e-12 · N``; a pruned map can beat the result only by a relative
``tol / d²(T)``, far below the accuracy of the distances themselves.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.optimize import linear_sum_assignment

from . import objective


def ratio_of(D: np.ndarray, t: np.ndarray) -> float:
    """σ_T² of one map (``inf`` for an isometry, 0 for d² = 0)."""
    num = objective.d2(D, t)
    if num == 0.0:
        return 0.0
    den = objective.dist2(D, t)
    if objective.is_isometry(D, den, t.size):
        return math.inf
    return num / den


def swap_search(D: np.ndarray, n: int, landmarks, rng: np.random.Generator, restarts: int = 4):
    """Warm start: steepest ascent of σ_T² over swaps and reassignments.

    Starts from the best single swap (or single reassignment to a free target
    when ``M > N``) and from ``restarts`` random maps of the free samples.
    Returns ``(ratio², t)``; a lower bound with its witness, never the identity.
    """
    M = D.shape[0]
    free = np.setdiff1d(np.arange(n), np.asarray(landmarks, dtype=np.int64))
    tfree = np.setdiff1d(np.arange(M), np.asarray(landmarks, dtype=np.int64))
    ident = np.arange(n)
    starts = [ident]
    for _ in range(restarts):
        t = ident.copy()
        t[free] = rng.permutation(tfree)[: free.size]
        starts.append(t)
    best = (0.0, None)
    for t0 in starts:
        r, t = _ascend(D, n, free, t0)
        if t is not None and r > best[0]:
            best = (r, t)
        if best[0] == math.inf:
            break
    return best


def _move_ratios(D, n, free, t, d2c, dist2c):
    """σ² after every swap (a, b) and every reassignment (a, y); two arrays."""
    M = D.shape[0]
    Dx = D[:n, :n]
    G = Dx @ D[t, :]
    g = G[np.arange(n), t]
    Gt = G[:, t]
    Da = D[np.arange(n), t] ** 2
    Dcross = D[np.ix_(np.arange(n), t)] ** 2
    dd2 = Dcross + Dcross.T - Da[:, None] - Da[None, :]
    dS = 2.0 * (Gt + Gt.T - g[:, None] - g[None, :] + 2.0 * Dx * D[np.ix_(t, t)])
    sw_num = d2c + dd2
    sw_den = dist2c - 2.0 * dS
    mask = np.zeros((n, n), dtype=bool)
    mask[np.ix_(free, free)] = True
    np.fill_diagonal(mask, False)
    swaps = _safe_ratio(D, n, sw_num, sw_den, mask)
    if M == n:
        return swaps, None
    H = np.sum(D[t, :] ** 2, axis=0)
    unused = np.ones(M, dtype=bool)
    unused[t] = False
    re_num = d2c + D[:n, :] ** 2 - Da[:, None]
    dSr = 2.0 * (G - g[:, None])
    dC = 2.0 * (H[None, :] - D[t, :] ** 2 - H[t][:, None])
    re_den = dist2c + dC - 2.0 * dSr
    rmask = np.zeros((n, M), dtype=bool)
    rmask[np.ix_(free, np.flatnonzero(unused))] = True
    return swaps, _safe_ratio(D, n, re_num, re_den, rmask)


def _safe_ratio(D, n, num, den, mask):
    scale2 = float(np.sum(D[:n, :n] ** 2))
    iso = den <= (objective.ISOMETRY_RTOL**2) * scale2
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(iso, np.inf, num / np.where(iso, 1.0, den))
    r = np.where(num <= 0.0, 0.0, r)
    return np.where(mask, r, -1.0)


def _ascend(D, n, free, t):
    t = t.copy()
    cur = ratio_of(D, t) if np.any(t != np.arange(n)) else 0.0
    while cur < math.inf:
        d2c, dist2c = objective.d2(D, t), objective.dist2(D, t)
        swaps, reas = _move_ratios(D, n, free, t, d2c, dist2c)
        k = int(np.argmax(swaps))
        best, move = swaps.flat[k], ("s", k)
        if reas is not None:
            j = int(np.argmax(reas))
            if reas.flat[j] > best:
                best, move = reas.flat[j], ("r", j)
        if not best > cur * (1.0 + 1e-12):
            break
        if move[0] == "s":
            a, b = divmod(move[1], n)
            t[a], t[b] = t[b], t[a]
        else:
            a, y = divmod(move[1], D.shape[0])
            t[a] = y
        cur = ratio_of(D, t)
    if cur <= 0.0:
        return 0.0, None
    return cur, t


def branch_and_bound(D, n, landmarks, r0, t0, deadline):
    """Exact max of σ_T² by the tree search described in the module docstring.

    Parameters
    ----------
    D : (M, M) distance matrix, samples first.
    n : number of samples N.
    landmarks : fixed samples (T(l) = l).
    r0, t0 : warm-start ratio² and map (a valid non-identity map, or 0/None).
    deadline : ``time.perf_counter()`` value at which to give up, or None.

    Returns
    -------
    (ratio², t, finished, nodes)
    """
    M = D.shape[0]
    L = np.asarray(list(landmarks), dtype=np.int64)
    free = np.setdiff1d(np.arange(n), L)
    targets = np.setdiff1d(np.arange(M), L)
    tol = 1e-12 * n
    best_r, best_t = r0, (None if t0 is None else np.asarray(t0).copy())
    if best_r == math.inf:
        return best_r, best_t, True, 0
    Dx = D[:n, :n]
    iso2 = (objective.ISOMETRY_RTOL**2) * float(np.sum(Dx**2))
    W = D[:n, :] ** 2
    spread = D[:n, :].std(axis=1)
    spread = spread / (spread.max() + 1e-300)
    # Root: A = landmarks (fixed to themselves, so their d² and A×A distortion are 0).
    C1 = _cross(D, free, targets, L, L)
    # Stack entry: (A, TA, U, R, C1 over U×R, d² of A, Dist² of A×A).
    stack = [(L, L, free, targets, C1, 0.0, 0.0)]
    nodes = 0
    while stack:
        A, TA, U, R, C1, d2A, dist2A = stack.pop()
        nodes += 1
        if deadline is not None and nodes % 16 == 1 and time.perf_counter() > deadline:
            return best_r, best_t, False, nodes
        s = best_r
        k = U.size
        As = np.sort(D[U[:, None], U], axis=1)
        Bs = np.sort(D[R[:, None], R], axis=1)
        GL = (As * As).sum(1)[:, None] + (Bs[:, :k] ** 2).sum(1)[None, :] - 2.0 * As @ Bs[:, -k:].T
        np.maximum(GL, 0.0, out=GL)
        Q = 2.0 * C1 + GL  # lower bound of the Dist² terms touching u -> y
        Wn = W[U[:, None], R]
        P = Wn - s * Q
        rows, cols = linear_sum_assignment(P, maximize=True)
        # Primal candidate: the LAP completion (may raise s, which only tightens).
        t = np.empty(n, dtype=np.int64)
        t[A] = TA
        t[U[rows]] = R[cols]
        num = float(W[np.arange(n), t].sum())
        if num > 0.0:
            den = float(((Dx - D[t[:, None], t]) ** 2).sum())
            r = math.inf if den <= iso2 else num / den
            if r > best_r * (1.0 + 1e-12):
                best_r, best_t = r, t
                if r == math.inf:
                    return best_r, best_t, True, nodes
                s = best_r
                P = Wn - s * Q
                rows, cols = linear_sum_assignment(P, maximize=True)
        const = d2A - s * dist2A
        bound = const + float(P[rows, cols].sum())
        if bound <= tol:
            continue
        # Branching.  est[u, y] = const + Σ_{u' != u} max_y' P[u', y'] + P[u, y]
        # bounds F_s over completions with T u = y (the row-max relaxation of the
        # assignment).  Branch on the sample with the fewest surviving children
        # (first fail), ties broken towards the most distinctive distance row.
        rowmax = P.max(axis=1)
        alive = (const + (rowmax.sum() - rowmax)[:, None] + P) > tol
        i = int(np.argmin(alive.sum(axis=1) - 0.5 * spread[U]))
        u = U[i]
        U2 = np.delete(U, i)
        A2 = np.append(A, u)
        if k == 1:
            for j in np.flatnonzero(alive[i]):
                t = np.empty(n, dtype=np.int64)
                t[A] = TA
                t[u] = R[j]
                num = float(W[np.arange(n), t].sum())
                if num > 0.0:
                    den = float(((Dx - D[t[:, None], t]) ** 2).sum())
                    r = math.inf if den <= iso2 else num / den
                    if r > best_r * (1.0 + 1e-12):
                        best_r, best_t = r, t
                        if r == math.inf:
                            return best_r, best_t, True, nodes
            continue
        Cu = np.delete(C1, i, axis=0)
        for j in np.argsort(P[i], kind="stable"):  # best profit pushed last, popped first
            if not alive[i, j]:
                continue
            if k > 2:  # the same bound with T u = y forced: an exact LAP on the rest
                Pr = np.delete(np.delete(P, i, axis=0), j, axis=1)
                rr, cc = linear_sum_assignment(Pr, maximize=True)
                if const + P[i, j] + float(Pr[rr, cc].sum()) <= tol:
                    continue
            y = R[j]
            R2 = np.delete(R, j)
            C2 = np.delete(Cu, j, axis=1) + (D[U2, u][:, None] - D[R2, y][None, :]) ** 2
            stack.append((A2, np.append(TA, y), U2, R2, C2, d2A + W[u, y], dist2A + 2.0 * C1[i, j]))
    return best_r, best_t, True, nodes


def _cross(D, U, R, A, TA):
    """C1[u, y] = Σ_{a∈A} (D[u,a] − D[y,Ta])², shape (|U|, |R|)."""
    if A.size == 0:
        return np.zeros((U.size, R.size))
    Du = D[U[:, None], A]
    Dy = D[R[:, None], TA]
    C1 = (Du * Du).sum(1)[:, None] + (Dy * Dy).sum(1)[None, :] - 2.0 * Du @ Dy.T
    return np.maximum(C1, 0.0)


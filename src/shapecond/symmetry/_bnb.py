"""Branch and bound for the exact global symmetry score.

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
linear assignment maximum of ``P`` (Hungarian method, ``_lap_max``)
bounds ``F_s`` over every completion.  The LAP solution is itself a complete
map and is evaluated as a primal candidate at every node.  A child ``T u = y``
is discarded before it is visited when ``const + P[u, y]`` plus the assignment
maximum of ``P`` without row ``u`` and column ``y`` is ``<= tol``: the same
bound restricted to the completions with ``T u = y``.

Implementation: the depth-first search runs in numba (``_dfs``) with explicit
per-depth state (``_Stack``: children in best-profit order, the cross term
``C1`` updated incrementally by ``(D[x,u] − D[y,Tu])²`` when ``u -> Tu`` is
fixed); a node is evaluated by ``_visit`` (bound, primal candidate) and
``_branch`` (children), a child entered by ``_descend``.  It checks the clock
every 256 nodes (every node when nodes are large).

Floating point: a node is pruned when its bound is ``<= tol`` with
``tol = 1e-12 · N``; a pruned map can beat the result only by a relative
``tol / d²(T)``, far below the accuracy of the distances themselves.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np
from numba import njit, objmode

from . import objective


def ratio_of(D: np.ndarray, t: np.ndarray) -> float:
    """σ_T² of one map (``inf`` for an isometry, 0 for d² = 0): ``objective.map_score`` squared."""
    return objective.map_score(D, t) ** 2


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
    iso = den <= objective.isometry_floor(D, n)
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
    if r0 == math.inf:
        return r0, np.asarray(t0).copy(), True, 0
    D = np.ascontiguousarray(D, dtype=np.float64)
    M = D.shape[0]
    L = np.asarray(sorted(int(v) for v in landmarks), dtype=np.int64)
    free = np.setdiff1d(np.arange(n), L).astype(np.int64)
    targets = np.setdiff1d(np.arange(M), L).astype(np.int64)
    t_init = np.arange(n, dtype=np.int64) if t0 is None else np.asarray(t0, dtype=np.int64).copy()
    iso2 = objective.isometry_floor(D, n)
    budget = math.inf if deadline is None else deadline - time.perf_counter()
    r, t, finished, nodes = _dfs(_Tree(D, n, L, free, targets, iso2, 1e-12 * n), float(r0), t_init, float(budget))
    if t0 is None and r == 0.0:
        return 0.0, None, bool(finished), int(nodes)
    return float(r), t, bool(finished), int(nodes)


class _Tree(NamedTuple):
    """The instance the tree search solves (``branch_and_bound``)."""

    D: np.ndarray  # (M, M) distances, samples first
    n: int  # N
    L: np.ndarray  # landmarks
    free: np.ndarray  # free samples
    targets: np.ndarray  # targets that are not landmarks
    iso2: float  # objective.isometry_floor
    tol: float  # a bound <= tol prunes (module docstring, "Floating point")


class _Stack(NamedTuple):
    """The depth-first search's state per depth (index ``depth``: the node at that depth)."""

    t: np.ndarray  # the partial map (-1: unassigned)
    used: np.ndarray  # targets taken
    C1: np.ndarray  # (free + 1, N, M) cross terms of the assigned samples
    d2A: np.ndarray  # d² of the assigned samples
    dist2A: np.ndarray  # Dist² among the assigned samples
    u_at: np.ndarray  # the sample branched on
    kids: np.ndarray  # its images to visit, best profit first
    nkids: np.ndarray
    pos: np.ndarray  # the next child to visit


class _Work(NamedTuple):
    """Scratch arrays of one node."""

    U: np.ndarray  # unassigned samples
    R: np.ndarray  # unused targets
    As: np.ndarray  # sorted rows of D over U
    Bs: np.ndarray  # sorted rows of D over R
    P: np.ndarray  # profit W − s (2 C1 + GL) over U × R
    Pr: np.ndarray  # P without a row and a column (a forced child's bound)
    col: np.ndarray  # the assignment of the linear assignment problem
    cand: np.ndarray  # the node's LAP completion
    alive: np.ndarray  # children not pruned by the row-max estimate
    rowmax: np.ndarray
    order: np.ndarray
    spread: np.ndarray  # std of each row of D, normalised: ties go to distinctive rows


@njit(cache=True)
def _clock():
    with objmode(now="float64"):
        now = time.perf_counter()
    return now


@njit(cache=True)
def _late(clock):
    """``clock = (start, budget)``: True once ``budget`` seconds have passed since ``start``."""
    return _clock() - clock[0] > clock[1]


@njit(cache=True)
def _lap_max(P, k, m, col_of_row):
    """Maximum-weight assignment of the k rows of P[:k, :m] (k <= m) to distinct columns.

    Shortest augmenting paths with potentials (the Hungarian method, O(k² m)).
    Fills ``col_of_row[:k]``; returns the total weight.
    """
    INF = 1e300
    u = np.zeros(k + 1)
    v = np.zeros(m + 1)
    p = np.zeros(m + 1, dtype=np.int64)
    way = np.zeros(m + 1, dtype=np.int64)
    minv = np.empty(m + 1)
    used = np.empty(m + 1, dtype=np.bool_)
    for i in range(1, k + 1):
        p[0] = i
        j0 = 0
        minv[:] = INF
        used[:] = False
        while True:
            used[j0] = True
            i0 = p[j0]
            delta = INF
            j1 = 0
            for j in range(1, m + 1):
                if not used[j]:
                    cur = -P[i0 - 1, j - 1] - u[i0] - v[j]
                    if cur < minv[j]:
                        minv[j] = cur
                        way[j] = j0
                    if minv[j] < delta:
                        delta = minv[j]
                        j1 = j
            for j in range(m + 1):
                if used[j]:
                    u[p[j]] += delta
                    v[j] -= delta
                else:
                    minv[j] -= delta
            j0 = j1
            if p[j0] == 0:
                break
        while True:
            j1 = way[j0]
            p[j0] = p[j1]
            j0 = j1
            if j0 == 0:
                break
    total = 0.0
    for j in range(1, m + 1):
        if p[j] != 0:
            col_of_row[p[j] - 1] = j - 1
            total += P[p[j] - 1, j - 1]
    return total


@njit(cache=True)
def _map_ratio(D, n, t, iso2):
    num = 0.0
    for x in range(n):
        num += D[x, t[x]] ** 2
    if num <= 0.0:
        return 0.0
    den = 0.0
    for x in range(n):
        for y in range(n):
            dd = D[x, y] - D[t[x], t[y]]
            den += dd * dd
    if den <= iso2:
        return np.inf
    return num / den


@njit(cache=True)
def _profit(D, U, R, C1, s, As, Bs, P):
    """P = W − s (2 C1 + GL) over U×R (module docstring); ``As`` and ``Bs`` receive the sorted rows
    of D over U and over R."""
    k, m = U.size, R.size
    for a in range(k):
        for b in range(k):
            As[a, b] = D[U[a], U[b]]
        As[a, :k] = np.sort(As[a, :k])
    for a in range(m):
        for b in range(m):
            Bs[a, b] = D[R[a], R[b]]
        Bs[a, :m] = np.sort(Bs[a, :m])
    for a in range(k):
        sa = 0.0
        for q in range(k):
            sa += As[a, q] ** 2
        for b in range(m):
            sb = 0.0
            cross = 0.0
            for q in range(k):
                sb += Bs[b, q] ** 2
                cross += As[a, q] * Bs[b, m - k + q]
            gl = max(sa + sb - 2.0 * cross, 0.0)
            P[a, b] = D[U[a], R[b]] ** 2 - s * (2.0 * C1[U[a], R[b]] + gl)


@njit(cache=True, inline="always")
def _root(tree):
    """The stack and the scratch arrays, with the landmarks assigned at the root."""
    D, n, L = tree.D, tree.n, tree.L
    M = D.shape[0]
    nf = tree.free.size
    spread = np.zeros(n)
    for x in range(n):
        spread[x] = np.std(D[x, :])
    spread /= spread.max() + 1e-300
    t = -np.ones(n, dtype=np.int64)
    used = np.zeros(M, dtype=np.bool_)
    for l in L:
        t[l] = l
        used[l] = True
    C1 = np.zeros((nf + 1, n, M))
    for x in range(n):
        for y in range(M):
            c = 0.0
            for l in L:
                dd = D[x, l] - D[y, l]
                c += dd * dd
            C1[0, x, y] = c
    stack = _Stack(t, used, C1, np.zeros(nf + 1), np.zeros(nf + 1), np.zeros(nf + 1, dtype=np.int64),
                   np.zeros((nf + 1, M), dtype=np.int64), np.zeros(nf + 1, dtype=np.int64),
                   np.zeros(nf + 1, dtype=np.int64))
    work = _Work(np.empty(nf, dtype=np.int64), np.empty(M, dtype=np.int64), np.empty((nf, nf)), np.empty((M, M)),
                 np.empty((nf, M)), np.empty((nf, M)), np.empty(M, dtype=np.int64), np.empty(n, dtype=np.int64),
                 np.empty((nf, M), dtype=np.bool_), np.empty(nf), np.empty(M, dtype=np.int64), spread)
    return stack, work


@njit(cache=True, inline="always")
def _open_parts(tree, stack, work):
    """Gather the node's unassigned samples into ``work.U`` and unused targets into ``work.R``;
    returns their counts (k, m)."""
    t, used, U, R = stack.t, stack.used, work.U, work.R
    k = 0
    for x in tree.free:
        if t[x] < 0:
            U[k] = x
            k += 1
    m = 0
    for y in tree.targets:
        if not used[y]:
            R[m] = y
            m += 1
    return k, m


@njit(cache=True, inline="always")
def _branch(tree, stack, work, depth, k, m, const, clock):
    """Choose the sample to branch on and list its children (module docstring): first fail on the
    row-max estimate, ties to distinctive rows; a child ``T u = y`` is kept when the bound with
    it forced stays above ``tol``.  False when the clock ran out (large nodes only)."""
    P, Pr, alive, rowmax, U, R = work.P, work.Pr, work.alive, work.rowmax, work.U, work.R
    spread, order, col, kids, nkids, tol = work.spread, work.order, work.col, stack.kids, stack.nkids, tree.tol
    total = 0.0
    for a in range(k):
        rowmax[a] = P[a, :m].max()
        total += rowmax[a]
    best_i, best_c = 0, np.inf
    for a in range(k):
        cnt = 0
        for b in range(m):
            alive[a, b] = const + total - rowmax[a] + P[a, b] > tol
            cnt += alive[a, b]
        c = cnt - 0.5 * spread[U[a]]
        if c < best_c:
            best_c, best_i = c, a
    stack.u_at[depth] = U[best_i]
    order[:m] = np.argsort(-P[best_i, :m])
    for q in range(m):
        b = order[q]
        if not alive[best_i, b]:
            continue
        if clock[2] == 1 and _late(clock):  # large nodes: one LAP per child
            return False
        if k > 2:  # the same bound with T u = y forced
            ra = 0
            for a in range(k):
                if a == best_i:
                    continue
                cb = 0
                for bb in range(m):
                    if bb != b:
                        Pr[ra, cb] = P[a, bb]
                        cb += 1
                ra += 1
            if const + P[best_i, b] + _lap_max(Pr, k - 1, m - 1, col) <= tol:
                continue
        kids[depth, nkids[depth]] = R[b]
        nkids[depth] += 1
    return True


@njit(cache=True, inline="always")
def _visit(tree, stack, work, depth, best_r, best_t, clock):
    """Evaluate the node at ``depth``: a leaf's ratio, or the LAP bound with its completion as a
    primal candidate, and the children when the bound is above ``tol``.

    Returns ``(status, best_r, best_t)``: status 0 go on, 1 out of time, 2 an isometry found.
    """
    D, n, iso2 = tree.D, tree.n, tree.iso2
    k, m = _open_parts(tree, stack, work)
    if k == 0:
        r = _map_ratio(D, n, stack.t, iso2)
        if r > best_r * (1.0 + 1e-12):
            best_r, best_t = r, stack.t.copy()
            if r == np.inf:
                return 2, best_r, best_t
        return 0, best_r, best_t
    U, R, C1 = work.U[:k], work.R[:m], stack.C1[depth]
    s = best_r
    _profit(D, U, R, C1, s, work.As, work.Bs, work.P)
    lap = _lap_max(work.P, k, m, work.col)
    if clock[2] == 1 and _late(clock):  # a large node's bound takes seconds
        return 1, best_r, best_t
    cand, col = work.cand, work.col
    cand[:] = stack.t
    for a in range(k):
        cand[U[a]] = R[col[a]]
    r = _map_ratio(D, n, cand, iso2)
    if r > best_r * (1.0 + 1e-12):  # primal candidate: the LAP completion
        best_r, best_t = r, cand.copy()
        if r == np.inf:
            return 2, best_r, best_t
        s = best_r
        _profit(D, U, R, C1, s, work.As, work.Bs, work.P)
        lap = _lap_max(work.P, k, m, work.col)
    const = stack.d2A[depth] - s * stack.dist2A[depth]
    if const + lap > tree.tol and not _branch(tree, stack, work, depth, k, m, const, clock):
        return 1, best_r, best_t
    return 0, best_r, best_t


@njit(cache=True, inline="always")
def _descend(tree, stack, depth):
    """Assign the node's next child ``T u = y`` (undoing the previous sibling) and fill the
    state of depth + 1: d², Dist² and the cross terms C1 updated by ``(D[x,u] − D[z,y])²``."""
    D, n = tree.D, tree.n
    M = D.shape[0]
    t, used, C1 = stack.t, stack.used, stack.C1
    u = stack.u_at[depth]
    y = stack.kids[depth, stack.pos[depth]]
    stack.pos[depth] += 1
    if t[u] >= 0:  # undo the previous sibling
        used[t[u]] = False
    stack.d2A[depth + 1] = stack.d2A[depth] + D[u, y] ** 2
    stack.dist2A[depth + 1] = stack.dist2A[depth] + 2.0 * C1[depth, u, y]
    for x in range(n):
        for z in range(M):
            dd = D[x, u] - D[z, y]
            C1[depth + 1, x, z] = C1[depth, x, z] + dd * dd
    t[u] = y
    used[y] = True


@njit(cache=True)
def _dfs(tree, best_r, best_t, budget):
    """The depth-first search of ``branch_and_bound``: (ratio², map, finished, nodes)."""
    nf = tree.free.size
    start = _clock()
    # read the clock every node when a node is large (N = 400: ~0.4 s each), every 256 when tiny
    stride = max(1, min(256, (1 << 20) // max(1, nf * nf * tree.D.shape[0])))
    clock = (start, budget, stride)
    stack, work = _root(tree)
    t, used, pos, nkids, u_at = stack.t, stack.used, stack.pos, stack.nkids, stack.u_at
    nodes = 0
    depth = 0
    enter = True
    while True:
        if enter:
            enter = False
            nodes += 1
            nkids[depth] = 0
            pos[depth] = 0
            if nodes % stride == 1 % stride and _late(clock):
                return best_r, best_t, False, nodes
            status, best_r, best_t = _visit(tree, stack, work, depth, best_r, best_t, clock)
            if status != 0:
                return best_r, best_t, status == 2, nodes
        # move: into the next child, or back up
        if pos[depth] < nkids[depth]:
            _descend(tree, stack, depth)
            depth += 1
            enter = True
        else:
            if depth == 0:
                break
            depth -= 1
            if pos[depth] >= nkids[depth]:  # the parent is done too: undo its assignment
                u = u_at[depth]
                used[t[u]] = False
                t[u] = -1
    return best_r, best_t, True, nodes

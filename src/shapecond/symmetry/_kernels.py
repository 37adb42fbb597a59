"""Compiled inner loops of the witness search.

For a map ``t`` (samples ``0..n-1`` into targets ``0..M-1``) the products of
``shapecond.symmetry.objective`` are::

    G[x, y] = Σ_{x'} D[x, x'] D[t x', y]      (n × M)
    H[y]    = Σ_{x'} D[t x', y]²              (M,)

With them a swap of two samples' images or the reassignment of one sample to a
free target changes d² and Dist² by a closed form in O(1) (the formulas of
``objective.swap_delta`` and ``objective.reassign_delta``).  A move changes G by
a rank-1 term:

* swap ``a, b`` (images ``ta, tb``):  G += (D[:, a] − D[:, b]) ⊗ (D[tb] − D[ta]);
  ``H`` is unchanged;
* reassign ``a`` from ``ta`` to ``y``:  G += D[:, a] ⊗ (D[y] − D[ta]) and
  H += D[y]² − D[ta]².

:func:`local_search` reads G once, at its start, and then keeps only what its
scan reads (n × n tables and G at the k nearest targets of each image, see its
Notes): one best-improvement step costs O(n² + n·k), whatever M.  Keeping all
of G up to date cost O(n·M) per move, most of a step at M = 8n.  ``apply_swap``
and ``apply_reassign`` update a full G for callers that keep one (the CNBS warm
starts).  Everything here is ``numba.njit(cache=True, nogil=True)``: the
compilation is paid once per machine, not once per process, and searches run
in parallel threads (the CNBS heat map).

The arguments of :func:`local_search` come in three named tuples (numba compiles
them like separate arguments): the search ``Space`` (fixed for a search stage),
the ``Goal`` (what is maximised, when to stop) and the ``MapState`` (the map and
its products, updated in place).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

#: Objective modes of :func:`local_search`.
MODE_RATIO = 0  # maximise d² / Dist² (σ² of the map, paper Eq. 5)
MODE_FIXED_S = 1  # maximise d² − s·Dist² (one rung of the fixed-s ladder)
MODE_BUDGET = 2  # maximise d² subject to Dist² ≤ s (the scale-aware score; infeasible: −excess)


class Space(NamedTuple):
    """Where :func:`local_search` moves: fixed for a whole search stage.

    D : (M, M) float64 distance matrix; the samples are ``0..n-1``.
    n : number of samples N.
    free : int64 indices of the samples that may move (non-landmarks).
    knn : (M, k) int64 nearest targets of each target (k = 0 when M == n: no
        reassignment moves).
    floor : Dist² values below it count as ``floor`` (``objective.isometry_floor``: a
        ratio never divides by round-off; isometries are decided exactly by the caller).
    """

    D: np.ndarray
    n: int
    free: np.ndarray
    knn: np.ndarray
    floor: float


class Goal(NamedTuple):
    """What :func:`local_search` maximises and when it stops.

    mode : ``MODE_RATIO``, ``MODE_FIXED_S`` or ``MODE_BUDGET`` (parameter ``s``).
    max_moves : cap on accepted moves.
    stop : stop as soon as the current value exceeds ``stop`` (``np.inf``: never).
        The value only grows during the search, so a caller looking for a minimum
        over several searches (the CNBS heat map's argmin) learns all it needs
        once a search passes the incumbent.
    anchors, anchor_budget : ``MODE_BUDGET`` only: anchor rows (landmark samples)
        and the budget each of their distortions
        ``Σ_x (D[l,x] − D[l,Tx])²`` must stay within (empty ``anchors``: none).
    """

    mode: int
    s: float
    max_moves: int
    stop: float
    anchors: np.ndarray
    anchor_budget: float


class MapState(NamedTuple):
    """The map :func:`local_search` starts from, with its products (arrays updated in place).

    t : (n,) int64 current map.
    G : (n, M) ``objective.cross_product`` of ``t``: read, never written.
    H : (M,) ``objective.image_energy`` of ``t``.
    used : bool (M,), True for the targets in the image.
    rows : current anchor-row distortions (``objective.anchor_rows`` of ``Goal.anchors``).
    d2, dist2 : d²(T) and Dist²(T) of ``t``.
    """

    t: np.ndarray
    G: np.ndarray
    H: np.ndarray
    used: np.ndarray
    rows: np.ndarray
    d2: float
    dist2: float


class _Tables(NamedTuple):
    """What the scan of :func:`local_search` reads, kept exact under every move (its Notes),
    and its work buffers."""

    P: np.ndarray  # P[x, x'] = G[x, t x']
    R: np.ndarray  # R[a, b] = P[a, b] + P[b, a] + 2 D[a, b] D[ta, tb]
    Q: np.ndarray  # Q[a, b] = D[a, tb]² + D[b, ta]²
    Gk: np.ndarray  # Gk[a, q] = G[a, knn[ta, q]]
    pd: np.ndarray  # P[x, x]
    dd: np.ndarray  # D[x, t x]²
    isfree: np.ndarray
    buf: np.ndarray  # one row of candidate values
    drl: np.ndarray  # change of the anchor rows under one move
    zero: np.ndarray  # no change of the anchor rows
    ea: np.ndarray  # ea[i, x] = (D[l, x] − D[l, t x])², anchor l = anchors[i]: its row's terms
    eslack: np.ndarray  # rows[i] − lb − max_x ea[i, x] (``_row_floor``)
    dv: np.ndarray  # the rank-1 term of a move: G' = G + c ⊗ dv
    c: np.ndarray
    w: np.ndarray  # dv at the images: w[x'] = dv[t x']


@njit(cache=True, nogil=True)
def _image_change(D, old, new, out):
    """out[y] = D[new, y] − D[old, y]: the change of a row of D when an image moves."""
    for y in range(D.shape[0]):
        out[y] = D[new, y] - D[old, y]


@njit(cache=True, nogil=True)
def _move_energy(D, H, old, new):
    """H += D[new]² − D[old]²: ``image_energy`` after one image moves from ``old`` to ``new``."""
    for y in range(D.shape[0]):
        H[y] += D[new, y] * D[new, y] - D[old, y] * D[old, y]


@njit(cache=True, nogil=True)
def _add_outer(G, n, c, v):
    """G[x, :] += c[x] v for the rows ``x < n`` with ``c[x] != 0`` (a rank-1 update)."""
    for x in range(n):
        cx = c[x]
        if cx != 0.0:
            for y in range(v.size):
                G[x, y] += cx * v[y]


@njit(cache=True, nogil=True)
def apply_swap(D, n, t, G, a, b):
    """Exchange T(a) and T(b) and update ``G`` in place (rank-1, O(n·M))."""
    ta = t[a]
    tb = t[b]
    v = np.empty(D.shape[0])
    _image_change(D, ta, tb, v)
    c = np.empty(n)
    for x in range(n):
        c[x] = D[x, a] - D[x, b]
    _add_outer(G, n, c, v)
    t[a] = tb
    t[b] = ta


@njit(cache=True, nogil=True)
def apply_reassign(D, n, t, G, H, used, a, y0):
    """Send sample ``a`` to the free target ``y0``; update ``G``, ``H``, ``used``."""
    ta = t[a]
    v = np.empty(D.shape[0])
    _image_change(D, ta, y0, v)
    c = np.empty(n)
    for x in range(n):
        c[x] = D[x, a]
    _add_outer(G, n, c, v)
    _move_energy(D, H, ta, y0)
    used[ta] = False
    used[y0] = True
    t[a] = y0


@njit(cache=True, nogil=True)
def _swap_cols(A, a, b):
    for x in range(A.shape[0]):
        tmp = A[x, a]
        A[x, a] = A[x, b]
        A[x, b] = tmp


@njit(cache=True, nogil=True)
def _entries(D, t, P, a, b):
    """(R[a, b], Q[a, b]) from their definitions (``local_search``'s Notes)."""
    u = D[a, t[b]]
    w = D[b, t[a]]
    return P[a, b] + P[b, a] + 2.0 * D[a, b] * D[t[a], t[b]], u * u + w * w


@njit(cache=True, nogil=True)
def _pair_row(D, n, t, P, R, Q, a):
    """Row and column ``a`` of the scan tables R and Q from P and the map t."""
    for x in range(n):
        r, q = _entries(D, t, P, a, x)
        R[a, x] = r
        R[x, a] = r
        Q[a, x] = q
        Q[x, a] = q


@njit(cache=True, nogil=True, inline="always")
def _tables(space, goal, state):
    """The tables the scan reads row-wise (``local_search``'s Notes) for the start map, and the
    work buffers."""
    D, n, knn, t, G = space.D, space.n, space.knn, state.t, state.G
    k = knn.shape[1]
    P = np.empty((n, n))
    R = np.empty((n, n))
    Q = np.empty((n, n))
    Gk = np.empty((n, k))
    for x in range(n):
        for xp in range(n):
            P[x, xp] = G[x, t[xp]]
        for q in range(k):
            Gk[x, q] = G[x, knn[t[x], q]]
    for a in range(n):
        for b in range(n):
            R[a, b], Q[a, b] = _entries(D, t, P, a, b)
    dv = np.empty(D.shape[0])
    c = np.empty(n)
    w = np.empty(n)
    isfree = np.zeros(n, dtype=np.bool_)
    free = space.free
    for i in range(free.shape[0]):
        isfree[free[i]] = True
    pd = np.empty(n)
    dd = np.empty(n)
    for x in range(n):
        pd[x] = P[x, x]
        u = D[x, t[x]]
        dd[x] = u * u
    na = goal.anchors.size if goal.mode == MODE_BUDGET else 0
    return _Tables(P, R, Q, Gk, pd, dd, isfree, np.empty(n), np.zeros(na), np.zeros(na), np.empty((na, n)),
                   np.empty(na), dv, c, w)


@njit(cache=True, nogil=True)
def _g_column(D, n, t, y, u, out):
    """out[x] = G[x, y] = Σ_x' D[x, x'] D[y, t x'] for the current map (O(n²); D symmetric)."""
    for xp in range(n):
        u[xp] = D[y, t[xp]]
    for x in range(n):
        g = 0.0
        for xp in range(n):
            g += D[x, xp] * u[xp]
        out[x] = g


@njit(cache=True, nogil=True)
def _gk_row(D, n, t, knn, Gk, x):
    """Gk[x, q] = G[x, knn[t x, q]] (O(n·k))."""
    ty = t[x]
    for q in range(knn.shape[1]):
        y = knn[ty, q]
        g = 0.0
        for xp in range(n):
            g += D[x, xp] * D[y, t[xp]]
        Gk[x, q] = g


@njit(cache=True, nogil=True)
def _value(mode, s, num, den, floor):
    """Objective of one candidate: num / max(den, floor) (σ², the identity and
    round-off of it scoring -1), num − s·den on a rung of the fixed-s ladder, or
    num when den ≤ s and −(den − s) otherwise (a budget: every feasible map
    beats every infeasible one, and an infeasible one improves by losing distortion)."""
    if mode == MODE_RATIO:
        return num / max(den, floor) if num > 0.0 else -1.0
    if mode == MODE_BUDGET:
        return num if den <= s else s - den
    return num - s * den


@njit(cache=True, nogil=True)
def _anchored(s, num, den, rl, drl, lb):
    """Budget value with anchor rows (``rl + drl``, each within ``lb``): num if every
    constraint holds, else minus the total excess."""
    exc = den - s if den > s else 0.0
    for i in range(rl.size):
        r = rl[i] + drl[i]
        if r > lb:
            exc += r - lb
    return num if exc == 0.0 else -exc


@njit(cache=True, nogil=True)
def _row_terms(D, n, t, lrows, rl, lb, ea, eslack):
    """The anchor rows' terms ``ea`` of the current map and ``eslack[i] = rl[i] − lb − max_x ea[i, x]``
    (``_row_floor``), O(L·n)."""
    for i in range(lrows.size):
        l = lrows[i]
        top = 0.0
        for x in range(n):
            u = D[l, x] - D[l, t[x]]
            ea[i, x] = u * u
            if ea[i, x] > top:
                top = ea[i, x]
        eslack[i] = rl[i] - lb - top


@njit(cache=True, nogil=True)
def _row_floor(ea, eslack, a, scale):
    """A lower bound of the anchor rows' total excess after any move of sample ``a`` (a swap with
    any b, or a reassignment): a move takes at most ea[i, a] + ea[i, b] ≤ ea[i, a] + max ea[i]
    off row i (its new terms are squares), so row i keeps at least eslack[i] − ea[i, a] above its
    budget.  Lowered by 1e-9 ``scale`` (the rows' size) against round-off: a candidate whose
    value with this excess is already no better than the best is skipped without computing its
    rows, and skipping it never changes the move chosen."""
    exc = 0.0
    for i in range(eslack.size):
        r = eslack[i] - ea[i, a]
        if r > 0.0:
            exc += r
    return max(exc - 1e-9 * scale, 0.0)


@njit(cache=True, nogil=True, inline="always")
def _pair_floor(ea, rl, lb, a, b, scale):
    """As ``_row_floor`` for the swap (a b) alone: row i keeps at least rl[i] − ea[i, a] − ea[i, b]."""
    exc = 0.0
    for i in range(rl.size):
        r = rl[i] - lb - ea[i, a] - ea[i, b]
        if r > 0.0:
            exc += r
    return max(exc - 1e-9 * scale, 0.0)


@njit(cache=True, nogil=True)
def _swap_rows_delta(D, lrows, a, b, ta, tb, drl):
    """Change of each anchor row Σ_x (D[l,x] − D[l,Tx])² when T(a) and T(b) are exchanged."""
    for i in range(lrows.size):
        l = lrows[i]
        x1 = D[l, a] - D[l, tb]
        x2 = D[l, b] - D[l, ta]
        y1 = D[l, a] - D[l, ta]
        y2 = D[l, b] - D[l, tb]
        drl[i] = x1 * x1 + x2 * x2 - y1 * y1 - y2 * y2


@njit(cache=True, nogil=True)
def _move_rows_delta(D, lrows, a, ta, y, drl):
    """Change of each anchor row when T(a) moves from ``ta`` to ``y``."""
    for i in range(lrows.size):
        l = lrows[i]
        x1 = D[l, a] - D[l, y]
        y1 = D[l, a] - D[l, ta]
        drl[i] = x1 * x1 - y1 * y1


@njit(cache=True, nogil=True, inline="always")
def _swap_value(b2, bS, q_ab, dd_b, r_ab, pd_b):
    """(d², Dist²) after the swap (a b), from ``b2 = d² − D[a,ta]²``, ``bS = Dist² + 4 P[a,a]`` and
    the table entries ``Q[a,b]``, ``D[b,tb]²``, ``R[a,b]``, ``P[b,b]`` (``local_search``'s Notes)."""
    return b2 + q_ab - dd_b, bS - 4.0 * (r_ab - pd_b)


@njit(cache=True, nogil=True, inline="always")
def _reassign_value(b2, dist2, day, dty, gk, pd_a, h_y, h_ta):
    """(d², Dist²) after sending ``a`` from ``ta`` to a free target ``y`` (``objective.reassign_delta``),
    from ``b2 = d² − D[a,ta]²``, ``day = D[a,y]``, ``dty = D[ta,y]``, ``gk = G[a,y]``, ``pd_a = G[a,ta]``,
    ``h_y = H[y]`` and ``h_ta = H[ta]``."""
    dS = 2.0 * (gk - pd_a)
    return b2 + day * day, dist2 + 2.0 * (h_y - dty * dty - h_ta) - 2.0 * dS


@njit(cache=True, nogil=True)
def _rows_change(space, goal, state, tab, a, b, swap):
    """Fill ``tab.drl`` with the change of the anchor rows under a move: the swap (a b) when
    ``swap``, else the reassignment of ``a`` to the target ``b``."""
    t = state.t
    if swap:
        _swap_rows_delta(space.D, goal.anchors, a, b, t[a], t[b], tab.drl)
    else:
        _move_rows_delta(space.D, goal.anchors, a, t[a], b, tab.drl)


@njit(cache=True, nogil=True, inline="always")
def _best_move(space, goal, state, tab, d2, dist2, cur):
    """One best-improvement scan over every swap and reassignment of the free samples.

    With anchors (a budget), a candidate that beats the best without its anchor rows is
    skipped when lower bounds of its rows' excess (``_row_floor``, ``_pair_floor``, O(L)
    per row and pair from the terms ``_row_terms`` tabulates once per scan) already keep it
    below the best: only then are its rows computed (``_swap_rows_delta``).  From a start
    far off the rows' budget (a reflection or a ladder rung with landmarks, rows 100x their
    budget) nearly every candidate beat the best without its rows, and computing them was
    4/5 of a move (5.3 against 1.0 ms at N = 400, M = 3200); the moves chosen are the same.

    Returns ``(kind, a, b, q)``: kind 0 the swap (a b), kind 1 the reassignment of ``a``
    to ``b = knn[T a, q]``, kind -1 no move improves ``cur`` (by more than round-off).
    The tables are taken out of their tuples once: the rows run in one loop, at the speed
    of a single function (a call per row with the tuples cost 25 % more per move).
    """
    D, n, free, knn, floor = space.D, space.n, space.free, space.knn, space.floor
    mode, s, lrows, lb = goal.mode, goal.s, goal.anchors, goal.anchor_budget
    t, H, used, rl = state.t, state.H, state.used, state.rows
    Q, R, Gk, pd, dd, isfree, buf, drl = tab.Q, tab.R, tab.Gk, tab.pd, tab.dd, tab.isfree, tab.buf, tab.drl
    nl = lrows.size if mode == MODE_BUDGET else 0
    best = cur + 1e-12 * abs(cur)
    kind, ba, bb, bq = -1, -1, -1, -1
    scale = 0.0
    if nl > 0:
        _row_terms(D, n, t, lrows, rl, lb, tab.ea, tab.eslack)
        for j in range(nl):
            scale += abs(rl[j]) + lb
    xa = 0.0
    for i in range(free.shape[0]):
        a = free[i]
        ta = t[a]
        b2 = d2 - dd[a]
        bS = dist2 + 4.0 * pd[a]
        if nl > 0:  # the anchor rows' excess after any move of a is at least xa
            xa = _row_floor(tab.ea, tab.eslack, a, scale)
        # swaps (a b), b > a: a branch-free row of candidate values (vectorises), v - best,
        # then the positive ones
        for b in range(a + 1, n):
            nd2, nds = _swap_value(b2, bS, Q[a, b], dd[b], R[a, b], pd[b])
            v = _value(mode, s, nd2, nds, floor)
            buf[b] = (v - best) if isfree[b] else -1.0
        for b in range(a + 1, n):
            if buf[b] > 0.0:
                nd2, nds = _swap_value(b2, bS, Q[a, b], dd[b], R[a, b], pd[b])
                v = _value(mode, s, nd2, nds, floor)
                if v <= best:
                    continue
                if nl > 0:
                    if xa > 0.0:  # its rows alone may keep it below the best (``_row_floor``)
                        over = nds - s if nds > s else 0.0
                        if -(over + xa) <= best or -(over + _pair_floor(tab.ea, rl, lb, a, b, scale)) <= best:
                            continue
                    _swap_rows_delta(D, lrows, a, b, ta, t[b], drl)
                    v = _anchored(s, nd2, nds, rl, drl, lb)
                    if v <= best:
                        continue
                best, kind, ba, bb = v, 0, a, b
        # reassignments of a to a free target among the nearest of its image
        for q in range(knn.shape[1]):
            y = knn[ta, q]
            if used[y]:
                continue
            nd2, nds = _reassign_value(b2, dist2, D[a, y], D[ta, y], Gk[a, q], pd[a], H[y], H[ta])
            v = _value(mode, s, nd2, nds, floor)
            if v > best and nl > 0:
                if xa > 0.0 and -((nds - s if nds > s else 0.0) + xa) <= best:
                    continue
                _move_rows_delta(D, lrows, a, ta, y, drl)
                v = _anchored(s, nd2, nds, rl, drl, lb)
            if v > best:
                best, kind, ba, bb, bq = v, 1, a, y, q
    return kind, ba, bb, bq


@njit(cache=True, nogil=True, inline="always")
def _rank1_tables(space, state, tab):
    """P += c wᵀ, R += c wᵀ + w cᵀ and Gk += c ⊗ dv at the neighbours: a move's rank-1 term
    (the rows and columns of the moved samples are rebuilt afterwards)."""
    n, knn, t = space.n, space.knn, state.t
    P, R, Gk, c, w, dv = tab.P, tab.R, tab.Gk, tab.c, tab.w, tab.dv
    k = knn.shape[1]
    for xp in range(n):
        w[xp] = dv[t[xp]]
    for x in range(n):
        cx = c[x]
        wx = w[x]
        for xp in range(n):
            P[x, xp] += cx * w[xp]
            R[x, xp] += cx * w[xp] + wx * c[xp]
        if k > 0:
            tx = t[x]
            for q in range(k):
                Gk[x, q] += cx * dv[knn[tx, q]]


@njit(cache=True, nogil=True, inline="always")
def _apply_move(space, state, tab, kind, a, b):
    """Make the move (kind 0: swap a b; kind 1: a to the target b) and update the tables.

    The arrays are taken out of the tuples before the loops: a field read inside a loop
    costs a reference count each time."""
    D, n, knn, t = space.D, space.n, space.knn, state.t
    P, R, Q, Gk, pd, dd, c, w = tab.P, tab.R, tab.Q, tab.Gk, tab.pd, tab.dd, tab.c, tab.w
    ta = t[a]
    if kind == 0:
        tb = t[b]
        _image_change(D, ta, tb, tab.dv)
        for x in range(n):
            c[x] = D[x, a] - D[x, b]
        t[a] = tb
        t[b] = ta
        _swap_cols(P, a, b)
    else:
        _image_change(D, ta, b, tab.dv)
        _move_energy(D, state.H, ta, b)
        for x in range(n):
            c[x] = D[x, a]
        state.used[ta] = False
        state.used[b] = True
        t[a] = b
    _rank1_tables(space, state, tab)
    if kind == 1:
        # column a of P is G'[:, b]: not derivable from P, computed directly
        _g_column(D, n, t, b, w, c)
        for x in range(n):
            P[x, a] = c[x]
    for j in range(2 if kind == 0 else 1):  # the rows of the moved samples, from their definitions
        x = a if j == 0 else b
        _pair_row(D, n, t, P, R, Q, x)
        if knn.shape[1] > 0:
            _gk_row(D, n, t, knn, Gk, x)
        dd[x] = D[x, t[x]] * D[x, t[x]]
    for x in range(n):
        pd[x] = P[x, x]


@njit(cache=True, nogil=True)
def local_search(space, goal, state):
    """Best-improvement local search over swaps and nearby reassignments.

    Parameters
    ----------
    space : Space
        D, N, the free samples, the neighbour lists of the targets, the isometry floor.
    goal : Goal
        The mode and its parameter ``s``, the cap on moves, the ``stop`` value and,
        with a budget, the anchor rows.  A move's value with anchors never exceeds
        its value without them, so the anchor terms (O(L)) are evaluated only for
        moves that would be the best.
    state : MapState
        The start map with its products; ``t``, ``H``, ``used`` and ``rows`` are
        updated in place and stay consistent with the map.

    Returns
    -------
    (d2, dist2, moves) after the search.  ``G`` is read, never written: on return
    it belongs to the starting map, and a caller that needs it for the final map
    recomputes it (``objective.cross_product``).

    Notes
    -----
    The scan reads two n × n tables row-wise (upper triangles), kept exact under
    every move instead of G::

        Q[a, b] = D[a, tb]² + D[b, ta]²
        R[a, b] = P[a, b] + P[b, a] + 2 D[a, b] D[ta, tb],   P[x, x'] = G[x, t x']

    so that the swap (a b) has new d² = d² − D[a,ta]² − D[b,tb]² + Q[a,b] and
    Dist² = Dist² − 4 (R[a,b] − P[a,a] − P[b,b]) (``objective.swap_delta``), and
    ``Gk[a, q] = G[a, knn[ta, q]]`` for the reassignments.  After a move P gets its
    rank-1 term (columns permuted), R the symmetric rank-2 term, and the rows of
    the moved samples are rebuilt from their definitions in O(n) (O(n²) for the
    column of P at a new target, O(n·k) for the rows of Gk).  Two tables read per
    pair instead of six (P, its transpose, D[x, t x'], its transpose, D[t x, t x'],
    D) made a step 1.3x faster at M = n = 400, and dropping the O(n·M) update of
    G 1.6x at M = 3,200 on TOSCA cat0 (the project's kernel benchmark).

    Its steps (``_tables``, ``_best_move``, ``_apply_move``) are inlined into it
    (``inline="always"``): compiled as one function, with the tables it allocates
    known not to overlap, a move took 7 % less time than with the steps compiled
    apart.
    """
    tab = _tables(space, goal, state)
    nl = goal.anchors.size if goal.mode == MODE_BUDGET else 0
    d2 = state.d2
    dist2 = state.dist2
    moves = 0
    while moves < goal.max_moves:
        if nl == 0:
            cur = _value(goal.mode, goal.s, d2, dist2, space.floor)
        else:
            cur = _anchored(goal.s, d2, dist2, state.rows, tab.zero, goal.anchor_budget)
        if cur > goal.stop:
            break
        kind, a, b, q = _best_move(space, goal, state, tab, d2, dist2, cur)
        if kind < 0:
            break
        b2 = d2 - tab.dd[a]
        if kind == 0:
            d2, dist2 = _swap_value(b2, dist2 + 4.0 * tab.pd[a], tab.Q[a, b], tab.dd[b], tab.R[a, b], tab.pd[b])
        else:
            ta = state.t[a]
            d2, dist2 = _reassign_value(b2, dist2, space.D[a, b], space.D[ta, b], tab.Gk[a, q], tab.pd[a],
                                        state.H[b], state.H[ta])
        if nl > 0:  # the anchor rows after the chosen move
            _rows_change(space, goal, state, tab, a, b, kind == 0)
            rows, drl = state.rows, tab.drl
            for i in range(nl):
                rows[i] += drl[i]
        _apply_move(space, state, tab, kind, a, b)
        moves += 1
    return d2, dist2, moves

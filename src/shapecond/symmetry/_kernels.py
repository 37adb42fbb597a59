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
"""
from __future__ import annotations

import numpy as np
from numba import njit

#: Objective modes of :func:`local_search`.
MODE_RATIO = 0  # maximise d² / Dist² (σ² of the map, paper Eq. 5)
MODE_FIXED_S = 1  # maximise d² − s·Dist² (one rung of the fixed-s ladder)
MODE_BUDGET = 2  # maximise d² subject to Dist² ≤ s (the scale-aware score; infeasible: −excess)


@njit(cache=True, nogil=True)
def apply_swap(D, n, t, G, a, b):
    """Exchange T(a) and T(b) and update ``G`` in place (rank-1, O(n·M))."""
    ta = t[a]
    tb = t[b]
    M = D.shape[0]
    v = np.empty(M)
    for y in range(M):
        v[y] = D[tb, y] - D[ta, y]
    for x in range(n):
        c = D[x, a] - D[x, b]
        if c != 0.0:
            for y in range(M):
                G[x, y] += c * v[y]
    t[a] = tb
    t[b] = ta


@njit(cache=True, nogil=True)
def apply_reassign(D, n, t, G, H, used, a, y0):
    """Send sample ``a`` to the free target ``y0``; update ``G``, ``H``, ``used``."""
    ta = t[a]
    M = D.shape[0]
    v = np.empty(M)
    for y in range(M):
        v[y] = D[y0, y] - D[ta, y]
    for x in range(n):
        c = D[x, a]
        if c != 0.0:
            for y in range(M):
                G[x, y] += c * v[y]
    for y in range(M):
        H[y] += D[y0, y] * D[y0, y] - D[ta, y] * D[ta, y]
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


@njit(cache=True, nogil=True)
def _setup(D, n, t, G, knn):
    """Gather the tables the scan reads row-wise (see ``local_search``)."""
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
    return P, R, Q, Gk


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


@njit(cache=True, nogil=True)
def local_search(D, n, t, G, H, free, knn, used, mode, s, d2, dist2, floor, max_moves, stop,
                 lrows, rl, lb):
    """Best-improvement local search over swaps and nearby reassignments.

    Parameters
    ----------
    D : (M, M) float64 distance matrix; samples are ``0..n-1``.
    t : (n,) int64 current map, modified in place; ``G``, ``H``, ``used``
        (bool (M,), True for targets in the image) are kept consistent with it.
    free : int64 indices of the samples that may move (non-landmarks).
    knn : (M, k) int64 nearest targets of each target (k = 0 when M == n:
        no reassignment moves).
    mode : ``MODE_RATIO``, ``MODE_FIXED_S`` or ``MODE_BUDGET`` (parameter ``s``).
    d2, dist2 : current d²(T) and Dist²(T).
    floor : Dist² values below it count as ``floor`` (a ratio never divides by
        round-off; isometries are decided exactly by the caller).
    max_moves : cap on accepted moves.
    stop : stop as soon as the current value exceeds ``stop`` (``np.inf``:
        never).  The value only grows during the search, so a caller looking for
        a minimum over several searches (the CNBS heat map's argmin) learns all it
        needs once a search passes the incumbent.
    lrows, rl, lb : ``MODE_BUDGET`` only: anchor rows (landmark samples), their
        current distortions ``rl[i] = Σ_x (D[l,x] − D[l,Tx])²`` (updated in place)
        and the budget ``lb`` each must stay within (empty ``lrows``: none).  A
        move's value with anchors never exceeds its value without them, so the
        anchor terms (O(L)) are evaluated only for moves that would be the best.

    Returns
    -------
    (d2, dist2, moves) after the search; ``t``, ``used`` and ``H`` updated.  ``G``
    is read, never written: on return it belongs to the starting map, and a
    caller that needs it for the final map recomputes it
    (``objective.cross_product``).

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
    """
    nf = free.shape[0]
    k = knn.shape[1]
    M = D.shape[0]
    P, R, Q, Gk = _setup(D, n, t, G, knn)
    dv = np.empty(M)
    c = np.empty(n)
    w = np.empty(n)
    moves = 0
    isfree = np.zeros(n, dtype=np.bool_)
    for i in range(nf):
        isfree[free[i]] = True
    pd = np.empty(n)
    dd = np.empty(n)
    buf = np.empty(n)
    nl = lrows.size if mode == MODE_BUDGET else 0
    drl = np.zeros(lrows.size)
    zero = np.zeros(lrows.size)
    for x in range(n):
        pd[x] = P[x, x]
        u = D[x, t[x]]
        dd[x] = u * u
    while moves < max_moves:
        cur = _value(mode, s, d2, dist2, floor) if nl == 0 else _anchored(s, d2, dist2, rl, zero, lb)
        if cur > stop:
            break
        best = cur + 1e-12 * abs(cur)
        kind = -1
        ba = -1
        bb = -1
        bq = -1
        for i in range(nf):
            a = free[i]
            ta = t[a]
            b2 = d2 - dd[a]
            bS = dist2 + 4.0 * pd[a]
            # branch-free row of candidate values (vectorises): v - best, then the positive ones
            for b in range(a + 1, n):
                nd2 = b2 + Q[a, b] - dd[b]
                nds = bS - 4.0 * (R[a, b] - pd[b])
                v = _value(mode, s, nd2, nds, floor)
                buf[b] = (v - best) if isfree[b] else -1.0
            for b in range(a + 1, n):
                if buf[b] > 0.0:
                    nd2 = b2 + Q[a, b] - dd[b]
                    nds = bS - 4.0 * (R[a, b] - pd[b])
                    v = _value(mode, s, nd2, nds, floor)
                    if v <= best:
                        continue
                    if nl > 0:
                        _swap_rows_delta(D, lrows, a, b, ta, t[b], drl)
                        v = _anchored(s, nd2, nds, rl, drl, lb)
                        if v <= best:
                            continue
                    best = v
                    kind = 0
                    ba = a
                    bb = b
            for q in range(k):
                y = knn[ta, q]
                if used[y]:
                    continue
                day = D[a, y]
                nd2 = b2 + day * day
                dS = 2.0 * (Gk[a, q] - pd[a])
                dty = D[ta, y]
                nds = dist2 + 2.0 * (H[y] - dty * dty - H[ta]) - 2.0 * dS
                v = _value(mode, s, nd2, nds, floor)
                if v > best and nl > 0:
                    _move_rows_delta(D, lrows, a, ta, y, drl)
                    v = _anchored(s, nd2, nds, rl, drl, lb)
                if v > best:
                    best = v
                    kind = 1
                    ba = a
                    bb = y
                    bq = q
        if kind < 0:
            break
        ta = t[ba]
        if kind == 0:
            tb = t[bb]
            bd2 = d2 - dd[ba] + Q[ba, bb] - dd[bb]
            bdist = dist2 + 4.0 * pd[ba] - 4.0 * (R[ba, bb] - pd[bb])
        else:
            day = D[ba, bb]
            bd2 = d2 - dd[ba] + day * day
            dty = D[ta, bb]
            bdist = dist2 + 2.0 * (H[bb] - dty * dty - H[ta]) - 4.0 * (Gk[ba, bq] - pd[ba])
        if nl > 0:  # the anchor rows after the chosen move
            if kind == 0:
                _swap_rows_delta(D, lrows, ba, bb, ta, t[bb], drl)
            else:
                _move_rows_delta(D, lrows, ba, ta, bb, drl)
            for i in range(nl):
                rl[i] += drl[i]
        # the move, as G' = G + c ⊗ v (G itself is not kept: only the tables read from it)
        if kind == 0:
            for y in range(M):
                dv[y] = D[tb, y] - D[ta, y]
            for x in range(n):
                c[x] = D[x, ba] - D[x, bb]
            t[ba] = tb
            t[bb] = ta
            _swap_cols(P, ba, bb)
        else:
            y0 = bb
            for y in range(M):
                dv[y] = D[y0, y] - D[ta, y]
                H[y] += D[y0, y] * D[y0, y] - D[ta, y] * D[ta, y]
            for x in range(n):
                c[x] = D[x, ba]
            used[ta] = False
            used[y0] = True
            t[ba] = y0
        for xp in range(n):
            w[xp] = dv[t[xp]]
        # P += c wᵀ; R += c wᵀ + w cᵀ (rows and columns of the moved samples rebuilt below)
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
        if kind == 1:
            # column ba of P is G'[:, y0]: not derivable from P, computed directly
            _g_column(D, n, t, y0, w, c)
            for x in range(n):
                P[x, ba] = c[x]
        _pair_row(D, n, t, P, R, Q, ba)
        if k > 0:
            _gk_row(D, n, t, knn, Gk, ba)
        if kind == 0:
            _pair_row(D, n, t, P, R, Q, bb)
            if k > 0:
                _gk_row(D, n, t, knn, Gk, bb)
        for x in range(n):
            pd[x] = P[x, x]
        dd[ba] = D[ba, t[ba]] * D[ba, t[ba]]
        if kind == 0:
            dd[bb] = D[bb, t[bb]] * D[bb, t[bb]]
        d2 = bd2
        dist2 = bdist
        moves += 1
    return d2, dist2, moves

"""Compiled inner loops of the witness search.

The search keeps, for the current map ``t`` (samples ``0..n-1`` into targets
``0..M-1``), the products of ``shapecond.symmetry.objective``::

    G[x, y] = Σ_{x'} D[x, x'] D[t x', y]      (n × M)
    H[y]    = Σ_{x'} D[t x', y]²              (M,)

With them a swap of two samples' images or the reassignment of one sample to a
free target changes d² and Dist² by a closed form in O(1) (the formulas of
``objective.swap_delta`` and ``objective.reassign_delta``), and an accepted
move updates ``G`` by a rank-1 correction in O(n·M):

* swap ``a, b`` (images ``ta, tb``):  G += (D[:, a] − D[:, b]) ⊗ (D[tb] − D[ta]);
  ``H`` is unchanged;
* reassign ``a`` from ``ta`` to ``y``:  G += D[:, a] ⊗ (D[y] − D[ta]) and
  H += D[y]² − D[ta]².

One best-improvement step therefore costs O(n² + n·k) evaluations plus O(n·M)
for the update.  Everything here is ``numba.njit(cache=True)`` so that the
compilation is paid once per machine, not once per process.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Objective modes of :func:`local_search`.
MODE_RATIO = 0  # maximise d² / Dist² (σ² of the map, paper Eq. 5)
MODE_FIXED_S = 1  # maximise d² − s·Dist² (one rung of the fixed-s ladder)
MODE_BUDGET = 2  # maximise d² subject to Dist² ≤ s (the scale-aware score; infeasible: −excess)


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def _setup(D, n, t, G):
    """Gather the n × n blocks the pair scan reads row-wise (see ``local_search``)."""
    P = np.empty((n, n))
    PT = np.empty((n, n))
    Dc = np.empty((n, n))
    DcT = np.empty((n, n))
    Di = np.empty((n, n))
    for x in range(n):
        for xp in range(n):
            P[x, xp] = G[x, t[xp]]
            PT[xp, x] = P[x, xp]
            Dc[x, xp] = D[x, t[xp]]
            DcT[xp, x] = Dc[x, xp]
            Di[x, xp] = D[t[x], t[xp]]
    return P, PT, Dc, DcT, Di


@njit(cache=True)
def _swap_cols(A, a, b):
    for x in range(A.shape[0]):
        tmp = A[x, a]
        A[x, a] = A[x, b]
        A[x, b] = tmp


@njit(cache=True)
def _swap_rows(A, a, b):
    for x in range(A.shape[1]):
        tmp = A[a, x]
        A[a, x] = A[b, x]
        A[b, x] = tmp


@njit(cache=True)
def _rank1(P, PT, c, w):
    """P += c wᵀ and PT += w cᵀ."""
    n = P.shape[0]
    for x in range(n):
        cx = c[x]
        if cx != 0.0:
            for xp in range(n):
                P[x, xp] += cx * w[xp]
    for xp in range(n):
        wx = w[xp]
        for x in range(n):
            PT[xp, x] += wx * c[x]


@njit(cache=True)
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


@njit(cache=True)
def _anchored(s, num, den, rl, drl, lb):
    """Budget value with anchor rows (``rl + drl``, each within ``lb``): num if every
    constraint holds, else minus the total excess."""
    exc = den - s if den > s else 0.0
    for i in range(rl.size):
        r = rl[i] + drl[i]
        if r > lb:
            exc += r - lb
    return num if exc == 0.0 else -exc


@njit(cache=True)
def _swap_rows_delta(D, lrows, a, b, ta, tb, drl):
    """Change of each anchor row Σ_x (D[l,x] − D[l,Tx])² when T(a) and T(b) are exchanged."""
    for i in range(lrows.size):
        l = lrows[i]
        x1 = D[l, a] - D[l, tb]
        x2 = D[l, b] - D[l, ta]
        y1 = D[l, a] - D[l, ta]
        y2 = D[l, b] - D[l, tb]
        drl[i] = x1 * x1 + x2 * x2 - y1 * y1 - y2 * y2


@njit(cache=True)
def _move_rows_delta(D, lrows, a, ta, y, drl):
    """Change of each anchor row when T(a) moves from ``ta`` to ``y``."""
    for i in range(lrows.size):
        l = lrows[i]
        x1 = D[l, a] - D[l, y]
        y1 = D[l, a] - D[l, ta]
        drl[i] = x1 * x1 - y1 * y1


@njit(cache=True)
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
    (d2, dist2, moves) after the search; ``t``, ``used`` updated, and ``G``,
    ``H`` too when k > 0 (without reassignment moves the scan needs only the
    gathered blocks below, so ``G`` is left stale to save O(n·M) per move).

    Notes
    -----
    The scan reads ``P[x, x'] = G[x, t x']``, ``Dc[x, x'] = D[x, t x']`` and
    ``Di[x, x'] = D[t x, t x']`` (and the transposes of the first two) as
    contiguous n × n rows; reading them from ``G`` and a large ``D`` directly
    is a cache miss per pair and was 4x slower at n = 400, M = 3200.
    """
    nf = free.shape[0]
    k = knn.shape[1]
    M = D.shape[0]
    P, PT, Dc, DcT, Di = _setup(D, n, t, G)
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
    while moves < max_moves:
        cur = _value(mode, s, d2, dist2, floor) if nl == 0 else _anchored(s, d2, dist2, rl, zero, lb)
        if cur > stop:
            break
        best = cur + 1e-12 * abs(cur)
        kind = -1
        ba = -1
        bb = -1
        for x in range(n):
            pd[x] = P[x, x]
            dd[x] = Dc[x, x] * Dc[x, x]
        for i in range(nf):
            a = free[i]
            ta = t[a]
            b2 = d2 - dd[a]
            bS = 2.0 * pd[a]
            # branch-free row of candidate values (vectorises), then its max
            for b in range(a + 1, n):
                dab = Dc[a, b]
                dba = DcT[a, b]
                nd2 = b2 + dab * dab + dba * dba - dd[b]
                nds = dist2 - 4.0 * (P[a, b] + PT[a, b] - pd[b] + 2.0 * D[a, b] * Di[a, b]) + 2.0 * bS
                v = _value(mode, s, nd2, nds, floor)
                buf[b] = v if isfree[b] else -np.inf
            for b in range(a + 1, n):
                if buf[b] > best:
                    v = buf[b]
                    if nl > 0:
                        dab = Dc[a, b]
                        dba = DcT[a, b]
                        nd2 = b2 + dab * dab + dba * dba - dd[b]
                        nds = dist2 - 4.0 * (P[a, b] + PT[a, b] - pd[b] + 2.0 * D[a, b] * Di[a, b]) + 2.0 * bS
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
                dS = 2.0 * (G[a, y] - pd[a])
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
        if kind == 0:
            dab = Dc[ba, bb]
            dba = DcT[ba, bb]
            bd2 = d2 - dd[ba] + dab * dab + dba * dba - dd[bb]
            bdist = dist2 - 4.0 * (P[ba, bb] + PT[ba, bb] - pd[ba] - pd[bb]
                                   + 2.0 * D[ba, bb] * Di[ba, bb])
        elif kind == 1:
            ta = t[ba]
            day = D[ba, bb]
            bd2 = d2 - dd[ba] + day * day
            dty = D[ta, bb]
            bdist = dist2 + 2.0 * (H[bb] - dty * dty - H[ta]) - 4.0 * (G[ba, bb] - pd[ba])
        if kind < 0:
            break
        ta = t[ba]
        if nl > 0:  # the anchor rows after the chosen move
            if kind == 0:
                _swap_rows_delta(D, lrows, ba, bb, ta, t[bb], drl)
            else:
                _move_rows_delta(D, lrows, ba, ta, bb, drl)
            for i in range(nl):
                rl[i] += drl[i]
        if kind == 0:
            tb = t[bb]
            for y in range(M):
                dv[y] = D[tb, y] - D[ta, y]
            if k > 0:
                apply_swap(D, n, t, G, ba, bb)
            else:  # bijections: the scan reads P only, G is not needed
                t[ba] = tb
                t[bb] = ta
            for x in range(n):
                c[x] = D[x, ba] - D[x, bb]
            _swap_cols(P, ba, bb)
            _swap_rows(PT, ba, bb)
            _swap_cols(Dc, ba, bb)
            _swap_rows(DcT, ba, bb)
            _swap_cols(Di, ba, bb)
            _swap_rows(Di, ba, bb)
        else:
            for y in range(M):
                dv[y] = D[bb, y] - D[ta, y]
            apply_reassign(D, n, t, G, H, used, ba, bb)
            for x in range(n):
                c[x] = D[x, ba]
                # column ba of P must hold the *old* G[:, bb] before the rank-1 step
                P[x, ba] = G[x, bb] - c[x] * dv[bb]
                PT[ba, x] = P[x, ba]
                Dc[x, ba] = D[x, bb]
                DcT[ba, x] = D[x, bb]
            for x in range(n):
                Di[x, ba] = D[t[x], bb]
                Di[ba, x] = Di[x, ba]
        for xp in range(n):
            w[xp] = dv[t[xp]]
        _rank1(P, PT, c, w)
        d2 = bd2
        dist2 = bdist
        moves += 1
    return d2, dist2, moves

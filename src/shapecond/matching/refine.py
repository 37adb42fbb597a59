"""Discrete refinement of a sample map on a pairwise-consistency objective.

Spectral matching (Leordeanu and Hebert 2005) maximises ``vᵀ M v`` over the
candidate assignments, relaxes it to an eigenvector and rounds it; the
rounding can end far below the best permutation of the very same objective.
This module maximises that objective over permutations directly, starting
from a given map, so that the spectral solution is only the start.

The objective ``F`` and its gain matrix ``Q`` are those of
``shapecond.matching.consistency``.

Moves (``polish``), each evaluated exactly from the gain matrix

    Q[x, y] = Σ_{x' ≠ x} K(D_s[x, x'], D_t[y, T x'])     (N_s × N_t)

* *swap*: exchange the images of ``a`` and ``b`` whose images are neighbours
  (``b``'s image among the ``k`` nearest target samples of ``a``'s);
  ``ΔF = 2 (Q[a,Tb] − Q[a,Ta] + Q[b,Ta] − Q[b,Tb] − 2 K(D_s[a,b], 0)
  + 2 K(D_s[a,b], D_t[Ta,Tb]))``; an accepted swap updates ``Q`` by the terms of
  ``a`` and ``b`` only (rows within the kernel's support);
* *reassignment*: the linear assignment maximising ``Σ_x Q[x, T' x]`` (every
  sample moves to the image most consistent with the others' current images),
  accepted only when ``F`` grows.

``robust_reassignment`` is a global move for whole regions that are shifted
by a sample or two (a local objective cannot see them: inside the region every
pair is consistent): each source sample goes to the target sample whose
distances to the current images ``T a`` of *all* samples agree best with its
own, judged by the ``q``-quantile of ``|D_s[x, a] − D_t[y, T a]|`` over ``a``,
which ignores the samples the map still gets wrong.
"""

from __future__ import annotations

import numba
import numpy as np
from scipy.optimize import linear_sum_assignment

from shapecond.selection.fps import fps_landmarks

from shapecond.matching.consistency import (  # noqa: F401  (re-exported for spectral and tests)
    SUPPORT, Kernel, _f64, _gain_band, _gain_columns, _gain_entry, _gain_near, _gain_row, _k,
    _objective, _objective_near, _support_terms, gain, objective, support_lists)


def rank_table(knn: np.ndarray) -> np.ndarray:
    """(M, M) int16: ``rank[u, v] = j + 1`` for the first ``j`` with ``knn[u, j] = v``, else 0."""
    m, k = knn.shape
    rank = np.zeros((m, m), dtype=np.int16)
    for j in range(k - 1, -1, -1):  # the first occurrence written last
        rank[np.arange(m), knn[:, j]] = j + 1
    return rank


@numba.njit(cache=True, nogil=True)
def _swap_search(Ds, Dt, t, knn, rank, near, isfree, t0, r2, ir2, cut2, max_moves):
    """Best-improvement swaps of neighbouring images; ``t`` updated in place.

    The band of x is its image and the ``k`` nearest target samples of it:
    ``B[x] = (T x, knn[T x])`` with gains ``Qb[x, j] = Q[x, B[x, j]]``.  The gain
    of b at T a is read from b's band at ``rank[T b, T a]`` (``rank_table``), or
    summed over ``near[b]`` (``support_lists``) when T a is not in it.

    Each sample ``a`` keeps its best swap (largest gain, first in band order);
    after a move only the samples whose gains can have changed are rescanned:
    those within the kernel's support of the two moved samples (``S``: their
    band gains changed) and those with a swap partner in ``S``.  A gain summed
    over ``near[b]`` is kept with the version of ``b``'s neighbourhood.  The
    move chosen is the first of the largest gain in ``(a, band)`` order, as a
    full scan would choose it.
    """
    n = Ds.shape[0]
    m = Dt.shape[0]
    kb = knn.shape[1] + 1
    B = np.empty((n, kb), dtype=np.int64)
    for x in range(n):
        B[x, 0] = t[x]
        B[x, 1:] = knn[t[x]]
    Qb = _gain_band(Ds, Dt, t, np.arange(n), B, t0, r2, ir2, cut2)
    inv = np.full(m, -1, dtype=np.int64)
    for x in range(n):
        inv[t[x]] = x
    count, nd, nden, nw = _support_terms(Ds, near, t0, r2, ir2)
    buf = np.empty(near.shape[1])
    version = np.zeros(n, dtype=np.int64)  # bumped when T changes within near[b]
    cache = np.zeros((n, kb))  # Q[b, T a] of a pair (a, j) summed over near[b] ...
    cache_key = np.full((n, kb, 3), -1, dtype=np.int64)  # ... for this (b, T a, version[b])
    best_gain = np.full(n, -np.inf)
    best_j = np.zeros(n, dtype=np.int64)
    dirty = np.ones(n, dtype=np.bool_)
    in_s = np.zeros(n, dtype=np.bool_)
    moves = 0
    while moves < max_moves:
        for a in range(n):
            if not dirty[a]:
                continue
            dirty[a] = False
            best_gain[a] = -np.inf
            if not isfree[a]:
                continue
            ta = t[a]
            for j in range(1, kb):
                b = inv[B[a, j]]
                if b < 0 or b == a or not isfree[b]:
                    continue
                tb = t[b]
                dab = Ds[a, b]
                # ΔF / 2 of exchanging T a and T b (module docstring)
                rb = rank[tb, ta]
                if rb > 0:
                    qba = Qb[b, rb]
                elif cache_key[a, j, 0] == b and cache_key[a, j, 1] == ta and \
                        cache_key[a, j, 2] == version[b]:
                    qba = cache[a, j]
                else:
                    qba = _gain_near(Dt, t, near, count, nd, nden, nw, b, ta, buf)
                    cache[a, j] = qba
                    cache_key[a, j, 0] = b
                    cache_key[a, j, 1] = ta
                    cache_key[a, j, 2] = version[b]
                gain = (Qb[a, j] - Qb[a, 0] + qba - Qb[b, 0]
                        - 2.0 * _k(dab, 0.0, t0, r2, ir2, cut2)
                        + 2.0 * _k(dab, Dt[ta, tb], t0, r2, ir2, cut2))
                if gain > best_gain[a]:
                    best_gain[a] = gain
                    best_j[a] = j
        best = 1e-12
        ba = -1
        for a in range(n):
            if best_gain[a] > best:
                best = best_gain[a]
                ba = a
        if ba < 0:
            break
        bb = inv[B[ba, best_j[ba]]]
        ta = t[ba]
        tb = t[bb]
        in_s[:] = False
        for x in range(n):
            if x == ba or x == bb:
                continue
            da = Ds[x, ba]
            db = Ds[x, bb]
            if da * da > cut2 and db * db > cut2:
                continue
            in_s[x] = True
            for j in range(kb):
                y = B[x, j]
                Qb[x, j] += (_k(da, Dt[y, tb], t0, r2, ir2, cut2) - _k(da, Dt[y, ta], t0, r2, ir2, cut2)
                             + _k(db, Dt[y, ta], t0, r2, ir2, cut2) - _k(db, Dt[y, tb], t0, r2, ir2, cut2))
        t[ba] = tb
        t[bb] = ta
        inv[tb] = ba
        inv[ta] = bb
        for x in (ba, bb):
            in_s[x] = True
            B[x, 0] = t[x]
            B[x, 1:] = knn[t[x]]
            _gain_row(Ds, Dt, t, x, B[x], Qb[x], t0, r2, ir2, cut2)
        moves += 1
        for x in range(n):
            if in_s[x]:
                version[x] += 1
                dirty[x] = True
                continue
            for j in range(1, kb):
                b = inv[B[x, j]]
                if b >= 0 and in_s[b]:
                    dirty[x] = True
                    break
    return moves


def neighbours(D_target, k: int) -> np.ndarray:
    """(N_t, k) the ``k`` nearest other target samples of each target sample."""
    D = _f64(D_target)
    k = min(k, D.shape[0] - 1)
    order = np.argsort(D, axis=1, kind="stable")
    return np.ascontiguousarray(order[:, 1:k + 1])


def _reassign(Ds, Dt, t, free, p):
    """Linear assignment of the free samples to their current images maximising Σ Q[x, T' x]."""
    img = t[free]
    Q = _gain_columns(Ds, np.ascontiguousarray(Dt[img, :].T), t, free, *p)
    r, c = linear_sum_assignment(Q, maximize=True)
    out = t.copy()
    out[free[r]] = img[c]
    return out


def polish(D_source, D_target, t, free, kernel: Kernel, knn=None, k: int = 16,
           max_rounds: int = 8) -> tuple[np.ndarray, float]:
    """Swaps and reassignments (module docstring) until neither raises ``F``.

    Swaps keep gains for each sample's current image and its ``k`` nearest
    target samples only (the *band*: O(N k) kernel values per move instead of
    O(N²)); each reassignment computes the gains of every free sample at every
    free image once (O(N³), less the pairs outside the kernel's support).

    Parameters
    ----------
    t : (N_s,) int start map (not modified); ``free`` : samples that may move
        (the others, landmarks, keep their image).
    knn : neighbour lists ``neighbours(D_target, k)`` or longer (computed when None).

    Returns
    -------
    (map, F(map)); ``F`` never decreases from the start's.
    """
    Ds, Dt = _f64(D_source), _f64(D_target)
    p = kernel.params()
    t = np.array(t, dtype=np.int64)
    free = np.asarray(free, dtype=np.int64)
    isfree = np.zeros(Ds.shape[0], dtype=np.bool_)
    isfree[free] = True
    knn = neighbours(Dt, k) if knn is None else np.ascontiguousarray(knn[:, :k], dtype=np.int64)
    rank, near = rank_table(knn), support_lists(Ds, p[3])
    f = _objective_near(Ds, Dt, t, near, *p)
    for _ in range(max_rounds):
        _swap_search(Ds, Dt, t, knn, rank, near, isfree, *p, 50 * Ds.shape[0])
        f = _objective_near(Ds, Dt, t, near, *p)
        t2 = _reassign(Ds, Dt, t, free, p)
        f2 = _objective_near(Ds, Dt, t2, near, *p)
        if not f2 > f * (1 + 1e-12):
            break
        t, f = t2, f2
    return t, float(f)


@numba.njit(cache=True, nogil=True)
def _select(buf, rank):
    """The ``rank``-th smallest entry of ``buf`` (0-based; Hoare's selection, in place).

    The value ``np.partition(buf, rank)[rank]`` returns, without its copy."""
    lo = 0
    hi = buf.size - 1
    while lo < hi:
        pivot = buf[rank]
        i = lo
        j = hi
        while i <= j:
            while buf[i] < pivot:
                i += 1
            while pivot < buf[j]:
                j -= 1
            if i <= j:
                buf[i], buf[j] = buf[j], buf[i]
                i += 1
                j -= 1
        if j < rank:
            lo = i
        if rank < i:
            hi = j
    return buf[rank]


@numba.njit(cache=True, parallel=True, nogil=True)
def _quantile_cost(Ds, Dt, t, rows, band, anchors, rank):
    """C[i, j] = the rank-th smallest |D_s[x, a] − D_t[y, T a]| over the anchors, x = rows[i], y = band[i, j]."""
    C = np.empty(band.shape)
    na = anchors.size
    ta = t[anchors]
    for i in numba.prange(rows.size):
        x = rows[i]
        ds = np.empty(na)
        for q in range(na):
            ds[q] = Ds[x, anchors[q]]
        buf = np.empty(na)
        for j in range(band.shape[1]):
            y = band[i, j]
            for q in range(na):
                buf[q] = abs(ds[q] - Dt[y, ta[q]])
            C[i, j] = _select(buf, rank)
    return C


def anchor_order(D_source, m: int) -> np.ndarray:
    """``m`` samples in farthest-point order from an end of the diameter (the sample
    farthest from any other), from the distances alone.

    The order does not depend on how the samples are numbered (a relabelled
    instance gets the relabelled samples, up to exact ties of distances), nor
    on the landmarks: matching the same samples listed in another order — the
    evaluation lists a problem's landmarks first — moves them the same way,
    which the landmark-nested matchers (``shapecond.matching.nested``) need
    for their bound to hold between two such calls.
    """
    D = np.asarray(D_source)
    if m <= 0:
        return np.zeros(0, dtype=np.int64)
    start = int(np.argmax(D.max(axis=1)))
    return np.array([start] + fps_landmarks(D, D.shape[0], m - 1, fixed=[start]), dtype=np.int64)


def robust_reassignment(D_source, D_target, t, free, quantile: float = 0.25,
                        n_anchors: int = 64, knn=None, k: int = 64) -> np.ndarray:
    """Re-place every free sample by the anchors ``T a`` (module docstring).

    The anchors are the samples that are not free (the landmarks, whose
    images are right) and the first farthest-point samples of ``D_source``
    (``anchor_order``), ``n_anchors`` in all.  Each free sample may move to its
    image's ``k`` nearest target samples (``knn``; a region shifted by a sample
    or two comes back), the images shared by the free samples, assigned to
    minimise the sum of the ``quantile``-quantiles of the distance disagreements.
    """
    Ds, Dt = _f64(D_source), _f64(D_target)
    t = np.asarray(t, dtype=np.int64)
    free = np.asarray(free, dtype=np.int64)
    knn = neighbours(Dt, k) if knn is None or knn.shape[1] < k else knn
    fixed = np.setdiff1d(np.arange(Ds.shape[0]), free)
    spread = anchor_order(Ds, min(n_anchors, Ds.shape[0]))
    spread = spread[~np.isin(spread, fixed)][:max(0, n_anchors - fixed.size)]
    anchors = np.concatenate([fixed, spread])
    rank = min(anchors.size - 1, max(0, int(round(quantile * (anchors.size - 1)))))
    img = t[free]
    band = np.ascontiguousarray(np.concatenate([img[:, None], knn[img, :k]], axis=1))
    pos = np.full(Dt.shape[0], -1, dtype=np.int64)
    pos[img] = np.arange(img.size)
    cols = pos[band]
    ok = cols >= 0
    C = np.full((free.size, free.size), 1e30)
    C[np.nonzero(ok)[0], cols[ok]] = _quantile_cost(Ds, Dt, t, free, band, anchors, rank)[ok]
    r, c = linear_sum_assignment(C)
    out = t.copy()
    out[free[r]] = img[c]
    return out


def refine(D_source, D_target, t, free, kernel: Kernel, knn=None, robust_rounds: int = 4
           ) -> tuple[np.ndarray, float]:
    """``polish``, then ``robust_reassignment`` + ``polish`` while ``F`` grows.

    Returns (map, F(map)); ``F`` never decreases from the start's.
    """
    knn = neighbours(D_target, 64) if knn is None else knn
    t, f = polish(D_source, D_target, t, free, kernel, knn)
    for _ in range(robust_rounds):
        t2, f2 = polish(D_source, D_target, robust_reassignment(D_source, D_target, t, free, knn=knn),
                        free, kernel, knn)
        if not f2 > f:
            break
        t, f = t2, f2
    return t, f

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

from typing import NamedTuple

import numba
import numpy as np
from scipy.optimize import linear_sum_assignment

from shapecond.selection.fps import fps_landmarks

from shapecond.matching.consistency import (
    Kernel, _f64, _gain_band, _gain_columns, _gain_near, _gain_row, _k, _objective_near, _support_terms, support_lists)


def rank_table(knn: np.ndarray) -> np.ndarray:
    """(M, M) int16: ``rank[u, v] = j + 1`` for the first ``j`` with ``knn[u, j] = v``, else 0
    (entries ``-1``, padding, are skipped)."""
    m, k = knn.shape
    rank = np.zeros((m, m), dtype=np.int16)
    rows = np.arange(m)
    for j in range(k - 1, -1, -1):  # the first occurrence written last
        ok = knn[:, j] >= 0
        rank[rows[ok], knn[ok, j]] = j + 1
    return rank


def reverse_extension(knn: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each target's neighbour list followed by its *reverse* neighbours missing from it.

    Returns ``(ext, length)``: ``ext[u, :k] = knn[u]``, then, in increasing order, every
    ``v ≠ u`` with ``u`` in ``knn[v]`` but ``v`` not in ``knn[u]`` (``-1`` after
    ``length[u]`` entries).  A swap partner ``b`` of ``a`` has its image in ``knn[T a]``,
    so ``T a`` is in ``ext[T b]``: the band of ``b`` built on ``ext`` holds every gain
    ``Q[b, T a]`` a swap search asks for (``_swap_search``).
    """
    m, k = knn.shape
    member = np.zeros((m, m), dtype=np.bool_)
    member[np.repeat(np.arange(m), k), knn.reshape(-1)] = True  # member[u, v]: v in knn[u]
    rev = member.T & ~member
    np.fill_diagonal(rev, False)
    counts = rev.sum(axis=1)
    ext = np.full((m, k + int(counts.max(initial=0))), -1, dtype=np.int64)
    ext[:, :k] = knn
    rows, cols = np.nonzero(rev)  # row by row, columns increasing
    ext[rows, k + np.arange(rows.size) - np.repeat(np.cumsum(counts) - counts, counts)] = cols
    return ext, k + counts


class _Lists(NamedTuple):
    """The neighbour lists of ``_swap_search`` (``swap_lists``)."""

    knn: np.ndarray  # (N_t, k) nearest target samples of each target sample (``neighbours``)
    ext: np.ndarray  # (N_t, k + r) knn, then the reverse neighbours (``reverse_extension``), -1 padded
    ext_len: np.ndarray  # (N_t,) entries of each ext row
    rank: np.ndarray  # (N_t, N_t) position + 1 of a target in another's ext row (``rank_table``)
    near: np.ndarray  # (N_s, w) source samples within the kernel's support (``support_lists``)


def swap_lists(knn: np.ndarray, near: np.ndarray) -> _Lists:
    """``_swap_search``'s lists for the neighbour lists ``knn`` and the support lists ``near``."""
    knn = np.ascontiguousarray(knn, dtype=np.int64)
    ext, length = reverse_extension(knn)
    return _Lists(knn, ext, length, rank_table(ext), near)


class _Bands(NamedTuple):
    """What ``_swap_search`` keeps between moves (its docstring)."""

    B: np.ndarray  # (N_s, 1 + k + r) band of each sample: its image, then the image's ext row
    length: np.ndarray  # (N_s,) entries of each band (the rest: the image, gains unset)
    Qb: np.ndarray  # gains over the bands, Qb[x, j] = Q[x, B[x, j]]
    slack: float  # bound on |Qb[x, j] − Q[x, B[x, j]]| (``_swap_search``)
    inv: np.ndarray  # (N_t,) source sample of each target (-1: none)
    terms: tuple  # ``_support_terms`` of the source
    buf: np.ndarray
    version: np.ndarray  # bumped when T changes within near[b]
    cache: np.ndarray  # Q[b, T a] of a pair (a, j) summed over near[b] ...
    cache_key: np.ndarray  # ... for this (b, T a, version[b])
    best_gain: np.ndarray  # each sample's best swap: its gain ...
    best_j: np.ndarray  # ... and its position in the sample's band
    dirty: np.ndarray  # samples to rescan
    in_s: np.ndarray  # samples whose band gains changed in the last move
    pend: np.ndarray  # (k,) a rescanned sample's band positions whose partner gain is an estimate


def _bands(Ds, Dt, t, lists, kp, slack):
    """The bands of the map ``t`` and their gains; every sample to be scanned.

    Plain Python: a cached numba function calling the parallel ``_gain_band`` segfaults
    when it is loaded from numba's cache after that callee was compiled in another process
    (numba issue 8578); called from Python, the two are cached separately.
    """
    n, m = Ds.shape[0], Dt.shape[0]
    ext = lists.ext[t]
    B = np.ascontiguousarray(np.concatenate([t[:, None], np.where(ext >= 0, ext, t[:, None])], axis=1),
                             dtype=np.int64)
    kb, k = B.shape[1], lists.knn.shape[1]
    length = 1 + lists.ext_len[t]
    Qb = _gain_band(Ds, Dt, t, np.arange(n), B, kp, length)
    inv = np.full(m, -1, dtype=np.int64)
    inv[t] = np.arange(n)
    near = lists.near
    return _Bands(B, length, Qb, float(slack), inv, _support_terms(Ds, near, kp),
                  np.empty(near.shape[1]), np.zeros(n, dtype=np.int64), np.zeros((n, kb)),
                  np.full((n, kb, 3), -1, dtype=np.int64), np.full(n, -np.inf), np.zeros(n, dtype=np.int64),
                  np.ones(n, dtype=np.bool_), np.zeros(n, dtype=np.bool_), np.zeros(k, dtype=np.int64))


@numba.njit(cache=True, error_model="numpy", inline="always")
def _swap_gain(qaj, qa0, qba, qb0, k0, k1):
    """ΔF / 2 of swapping a and b (module docstring) from the four gains and ``k0 = K(D_s[a, b], 0)``,
    ``k1 = K(D_s[a, b], D_t[T a, T b])``; non-decreasing in ``qba`` (each addition and
    subtraction of floats is monotone, left to right)."""
    return qaj - qa0 + qba - qb0 - 2.0 * k0 + 2.0 * k1


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _fresh_gain(Dt, t, lists, st, a, j, b):
    """Q[b, T a] summed over ``near[b]``, kept in a's cache with the version of b's neighbourhood."""
    q = _gain_near(Dt, t, lists.near, st.terms, b, t[a], st.buf)
    st.cache[a, j] = q
    st.cache_key[a, j, 0] = b
    st.cache_key[a, j, 1] = t[a]
    st.cache_key[a, j, 2] = st.version[b]
    return q


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _rescan(Ds, Dt, t, lists, isfree, kp, st):
    """The best swap of every dirty sample a: the largest gain ΔF / 2 (module docstring), first in
    band order, over the samples b whose image is in a's knn band.

    The gain of b at T a is read from b's band at ``rank[T b, T a] ≤ k``, else it is the sum
    over ``near[b]`` (kept with the version of b's neighbourhood).  That sum is computed only
    when the estimate kept in b's band (T a is then a reverse neighbour of T b), give or take
    ``st.slack``, leaves the swap a chance to be a's best: the swaps of exact gains are
    scanned first, then those of estimated ones (``st.pend``), in band order."""
    B, Qb, inv, rank, cache, key, version = st.B, st.Qb, st.inv, lists.rank, st.cache, st.cache_key, st.version
    dirty, best_gain, best_j, pend = st.dirty, st.best_gain, st.best_j, st.pend
    k = lists.knn.shape[1]
    for a in range(Ds.shape[0]):
        if not dirty[a]:
            continue
        dirty[a] = False
        best_gain[a] = -np.inf
        if not isfree[a]:
            continue
        ta = t[a]
        n_pend = 0
        floor = -np.inf  # a gain some swap of a reaches (exact, or a lower bound)
        for j in range(1, k + 1):
            b = inv[B[a, j]]
            if b < 0 or b == a or not isfree[b]:
                continue
            tb = t[b]
            dab = Ds[a, b]
            k0, k1 = _k(dab, 0.0, kp), _k(dab, Dt[ta, tb], kp)
            rb = rank[tb, ta]
            if 0 < rb <= k:
                qba = Qb[b, rb]
            elif key[a, j, 0] == b and key[a, j, 1] == ta and key[a, j, 2] == version[b]:
                qba = cache[a, j]
            elif rb > k:  # an estimate: decided below
                low = _swap_gain(Qb[a, j], Qb[a, 0], Qb[b, rb] - st.slack, Qb[b, 0], k0, k1)
                floor = max(floor, low)
                pend[n_pend] = j
                n_pend += 1
                continue
            else:
                qba = _fresh_gain(Dt, t, lists, st, a, j, b)
            gain = _swap_gain(Qb[a, j], Qb[a, 0], qba, Qb[b, 0], k0, k1)
            floor = max(floor, gain)
            if gain > best_gain[a]:
                best_gain[a] = gain
                best_j[a] = j
        for p in range(n_pend):
            j = pend[p]
            b = inv[B[a, j]]
            tb = t[b]
            dab = Ds[a, b]
            k0, k1 = _k(dab, 0.0, kp), _k(dab, Dt[ta, tb], kp)
            high = _swap_gain(Qb[a, j], Qb[a, 0], Qb[b, rank[tb, ta]] + st.slack, Qb[b, 0], k0, k1)
            if high < floor:
                continue  # below a gain some swap of a reaches: never a's best
            gain = _swap_gain(Qb[a, j], Qb[a, 0], _fresh_gain(Dt, t, lists, st, a, j, b), Qb[b, 0], k0, k1)
            if gain > best_gain[a] or (gain == best_gain[a] and j < best_j[a]):  # the first of the largest
                best_gain[a] = gain
                best_j[a] = j


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _make_swap(Ds, Dt, t, lists, kp, st, ba, bb):
    """Exchange the images of ``ba`` and ``bb``: the band gains of the samples within the kernel's
    support of either (``in_s``) get the terms of the two, their own bands are rebuilt, and every
    sample in ``in_s`` or with a swap partner in it is marked dirty."""
    n, B, Qb, in_s = Ds.shape[0], st.B, st.Qb, st.in_s
    ta = t[ba]
    tb = t[bb]
    in_s[:] = False
    for x in range(n):
        if x == ba or x == bb:
            continue
        da = Ds[x, ba]
        db = Ds[x, bb]
        if da * da > kp[3] and db * db > kp[3]:
            continue
        in_s[x] = True
        for j in range(st.length[x]):
            y = B[x, j]
            Qb[x, j] += (_k(da, Dt[y, tb], kp) - _k(da, Dt[y, ta], kp)
                         + _k(db, Dt[y, ta], kp) - _k(db, Dt[y, tb], kp))
    t[ba] = tb
    t[bb] = ta
    st.inv[tb] = ba
    st.inv[ta] = bb
    for x in (ba, bb):
        in_s[x] = True
        B[x, :] = t[x]
        st.length[x] = 1 + lists.ext_len[t[x]]
        B[x, 1:st.length[x]] = lists.ext[t[x], :st.length[x] - 1]
        _gain_row(Ds, Dt, t, x, B[x, :st.length[x]], Qb[x, :st.length[x]], kp)
    for x in range(n):
        if in_s[x]:
            st.version[x] += 1
            st.dirty[x] = True
            continue
        for j in range(1, lists.knn.shape[1] + 1):
            b = st.inv[B[x, j]]
            if b >= 0 and in_s[b]:
                st.dirty[x] = True
                break


def _swap_search(Ds, Dt, t, lists, isfree, kp, max_moves):
    """Best-improvement swaps of neighbouring images; ``t`` updated in place.

    The band of x is its image, the ``k`` nearest target samples of it and their
    reverse neighbours (``reverse_extension``): ``B[x] = (T x, ext[T x])`` with gains
    ``Qb[x, j] = Q[x, B[x, j]]``, updated by the terms of the moved samples.  Each sample
    ``a`` keeps its best swap (``_rescan``); after a move (``_make_swap``) only the
    samples whose gains can have changed are rescanned: those within the kernel's
    support of the two moved samples (their band gains changed) and those with a swap
    partner among them.  The move chosen is the first of the largest gain in
    ``(a, band)`` order, as a full scan would choose it.  Returns the number of moves.

    A partner's gain at ``T a`` beyond its ``k`` nearest is the sum over ``near[b]``
    (``_gain_near``), as before the reverse neighbours were kept; their band values only
    decide which of these sums can matter.  A band value is off that sum by the rounding
    of at most ``W`` terms in [0, 1] twice (its first sum and the reference) and of one
    update per move: under ``u (W + 170) (2 W + M)`` for ``W`` terms a gain (the widest
    support list), ``M = max_moves`` and ``u = 2⁻⁵³`` (each term off by at most ``40 u``,
    each addition by ``u`` times a value at most ``W``); the bands' ``slack`` is 64 times
    that, so a swap whose band estimate plus the slack stays below a gain reached by
    another partner is never ``a``'s best, and the sums skipped change no move.  On
    LH05's 400 samples of a SMAL_r pair (cow → dog2, 6 landmarks; ``k = 16``, 1.6 reverse
    neighbours a target on average, 10 at most) the coarse kernel's first swap search (281
    moves) summed 172,000 gains over 399 terms each when every one was summed, 0.66 s of its
    0.86 s; the 18 polishes' swap searches of one LH05 match took 0.70-0.80 s (coarse kernel)
    and 0.36-0.41 s (fine kernel) before, 0.17-0.31 s and 0.28-0.30 s with the estimates, the
    same moves (one core, a loaded machine).
    """
    W = lists.near.shape[1]
    slack = 64 * 2.0 ** -53 * (W + 170) * (2 * W + max_moves)
    return _moves(Ds, Dt, t, lists, isfree, kp, _bands(Ds, Dt, t, lists, kp, slack), max_moves)


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _moves(Ds, Dt, t, lists, isfree, kp, st, max_moves):
    """``_swap_search``'s moves from the bands ``st`` (``_bands``)."""
    moves = 0
    while moves < max_moves:
        _rescan(Ds, Dt, t, lists, isfree, kp, st)
        best = 1e-12
        ba = -1
        for a in range(Ds.shape[0]):
            if st.best_gain[a] > best:
                best = st.best_gain[a]
                ba = a
        if ba < 0:
            break
        _make_swap(Ds, Dt, t, lists, kp, st, ba, st.inv[st.B[ba, st.best_j[ba]]])
        moves += 1
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
    Q = _gain_columns(Ds, np.ascontiguousarray(Dt[img, :].T), t, free, p)
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
    lists = swap_lists(knn, support_lists(Ds, p[3]))
    f = _objective_near(Ds, Dt, t, lists.near, p)
    for _ in range(max_rounds):
        _swap_search(Ds, Dt, t, lists, isfree, p, 50 * Ds.shape[0])
        f = _objective_near(Ds, Dt, t, lists.near, p)
        t2 = _reassign(Ds, Dt, t, free, p)
        f2 = _objective_near(Ds, Dt, t2, lists.near, p)
        if not f2 > f * (1 + 1e-12):
            break
        t, f = t2, f2
    return t, float(f)


@numba.njit(cache=True, error_model="numpy", nogil=True)
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


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _count_at_most(buf, bound):
    """The entries of ``buf`` at most ``bound`` (branch-free)."""
    c = 0
    for q in range(buf.size):
        c += buf[q] <= bound
    return c


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _select_near(buf, rank, guess, scratch):
    """The ``rank``-th smallest entry of ``buf`` (as ``_select``) from a positive ``guess`` of it.

    The answer is bracketed by counting the entries below the guess, or, above it, at most
    twice the guess (doubled until the bracket holds it); only the entries in the bracket are
    selected from (``scratch``).  The same value as ``_select(buf, rank)`` (an order statistic
    is one number), at a fraction of its cost when the guess is within a factor 2."""
    lt = buf.size - _count_at_most(-buf, -guess)  # entries below the guess
    le = _count_at_most(buf, guess)
    if lt <= rank < le:
        return guess
    m = 0
    if rank < lt:
        for q in range(buf.size):
            scratch[m] = buf[q]
            m += buf[q] < guess
        return _select(scratch[:m], rank)
    high = 2.0 * guess
    while _count_at_most(buf, high) <= rank:
        high *= 2.0
    for q in range(buf.size):
        scratch[m] = buf[q]
        m += (buf[q] > guess) & (buf[q] <= high)
    return _select(scratch[:m], rank - le)


@numba.njit(cache=True, error_model="numpy", parallel=True, nogil=True)
def _quantile_cost(Ds, Dt, t, rows, band, anchors, rank):
    """C[i, j] = the rank-th smallest |D_s[x, a] − D_t[y, T a]| over the anchors, x = rows[i], y = band[i, j].

    Along a band (neighbouring targets) the quantile changes little: each is selected from the
    previous one as a guess (``_select_near``); measured 4x faster than selecting each from
    scratch on LH05's 400 samples (64 anchors, 65 targets a band), the same values."""
    C = np.empty(band.shape)
    na = anchors.size
    ta = t[anchors]
    for i in numba.prange(rows.size):
        x = rows[i]
        ds = np.empty(na)
        for q in range(na):
            ds[q] = Ds[x, anchors[q]]
        buf = np.empty(na)
        scratch = np.empty(na)
        for j in range(band.shape[1]):
            y = band[i, j]
            for q in range(na):
                buf[q] = abs(ds[q] - Dt[y, ta[q]])
            guess = C[i, j - 1] if j > 0 else 0.0
            C[i, j] = _select_near(buf, rank, guess, scratch) if guess > 0.0 else _select(buf, rank)
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

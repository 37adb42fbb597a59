"""The compiled local search against brute force on small instances.

``_kernels.local_search`` tracks d² and Dist² by closed-form deltas and keeps its
scan tables (not G) up to date after every move; here every claim of its docstring
is checked exactly: the tracked values, H and ``used`` equal their definitions for
the final map, landmarks stay fixed, the map stays injective, and the result is a
local optimum of the mode's objective over every swap and every reassignment to a
free neighbouring target, enumerated.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from shapecond.symmetry import _kernels as K
from shapecond.symmetry import objective as obj
from shapecond.symmetry.search import SearchStage


def _instance(seed, n, m):
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(m, 3))
    D = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1))
    return D / D.max(), rng


def _value(mode, s, D, t, lm, n):
    """The objective the kernel maximises, from the definitions."""
    num, den = obj.d2(D, t), obj.dist2(D, t)
    if mode == K.MODE_RATIO:
        return num / max(den, obj.isometry_floor(D, n)) if num > 0 else -1.0
    if mode == K.MODE_FIXED_S:
        return num - s * den
    exc = max(den - s, 0.0) + float(np.sum(np.maximum(obj.anchor_rows(D, t, lm) - s / n, 0.0)))
    return num if exc == 0.0 else -exc


@settings(max_examples=120, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(4, 9), extra=st.integers(0, 9),
       mode=st.sampled_from([K.MODE_RATIO, K.MODE_FIXED_S, K.MODE_BUDGET]), n_lm=st.integers(0, 2))
def test_local_search_tracks_exact_values_and_ends_in_a_local_optimum(seed, n, extra, mode, n_lm):
    m = n + extra
    D, rng = _instance(seed, n, m)
    lm = np.sort(rng.choice(n, size=n_lm, replace=False)).astype(np.int64)
    free = np.setdiff1d(np.arange(n), lm).astype(np.int64)
    stage = SearchStage(D, n, free, 3)
    t = np.arange(n, dtype=np.int64)
    perm = rng.permutation(free)
    t[free] = perm  # a random bijection fixing the landmarks
    if m > n:  # and a few samples sent outside X
        for a in rng.choice(free, size=min(2, free.size), replace=False):
            t[a] = rng.integers(n, m)
        if len(set(t.tolist())) < n:
            t = np.arange(n, dtype=np.int64)
            t[free] = perm
    s = {K.MODE_RATIO: 0.0, K.MODE_FIXED_S: 0.5, K.MODE_BUDGET: 0.3 * obj.dist2(D, t) + 1e-3}[mode]
    start = _value(mode, s, D, t, lm, n)
    G, H = obj.cross_product(D, t), obj.image_energy(D, t)
    used = np.zeros(m, dtype=bool)
    used[t] = True
    rows = obj.anchor_rows(D, t, lm)
    d2, dist2, moves = K.local_search(stage.space(), K.Goal(mode, float(s), 10_000, np.inf, lm, s / n),
                                      K.MapState(t, G, H, used, rows, obj.d2(D, t), obj.dist2(D, t)))
    assert moves < 10_000
    assert math.isclose(d2, obj.d2(D, t), rel_tol=1e-9, abs_tol=1e-12)
    assert math.isclose(dist2, obj.dist2(D, t), rel_tol=1e-9, abs_tol=1e-12)
    np.testing.assert_allclose(H, obj.image_energy(D, t), rtol=1e-9, atol=1e-12)
    if mode == K.MODE_BUDGET:
        np.testing.assert_allclose(rows, obj.anchor_rows(D, t, lm), rtol=1e-9, atol=1e-12)
    assert np.array_equal(t[lm], lm) and len(set(t.tolist())) == n
    assert np.array_equal(np.flatnonzero(used), np.sort(t))
    final = _value(mode, s, D, t, lm, n)
    assert final >= start - 1e-12 * abs(start)
    tol = 1e-9 * max(abs(final), 1e-12)
    for i, a in enumerate(free):  # no swap improves
        for b in free[i + 1:]:
            u = t.copy()
            u[a], u[b] = u[b], u[a]
            assert _value(mode, s, D, u, lm, n) <= final + tol
        for y in stage.knn[t[a]]:  # no reassignment to a free nearby target improves
            if not used[y]:
                u = t.copy()
                u[a] = y
                assert _value(mode, s, D, u, lm, n) <= final + tol


def test_local_search_leaves_g_alone_and_stops_above_stop():
    D, rng = _instance(3, 8, 14)
    n, free = 8, np.arange(8, dtype=np.int64)
    stage = SearchStage(D, n, free, 4)
    t = rng.permutation(n).astype(np.int64)
    G = obj.cross_product(D, t)
    G0, H, used = G.copy(), obj.image_energy(D, t), np.zeros(14, dtype=bool)
    used[t] = True
    start = obj.d2(D, t) / obj.dist2(D, t)
    goal = K.Goal(K.MODE_RATIO, 0.0, 10_000, start * 1.0001, np.zeros(0, np.int64), 0.0)
    d2, dist2, moves = K.local_search(stage.space(), goal,
                                      K.MapState(t, G, H, used, np.zeros(0), obj.d2(D, t), obj.dist2(D, t)))
    assert np.array_equal(G, G0)  # read, never written
    assert moves >= 1 and d2 / dist2 > start * 1.0001


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(4, 9), extra=st.integers(0, 6), n_lm=st.integers(1, 3))
def test_row_floors_bound_the_anchor_rows_after_every_move(seed, n, extra, n_lm):
    # the scan skips a candidate on these bounds: they must never exceed the rows' true excess
    m = n + extra
    D, rng = _instance(seed, n, m)
    lm = np.sort(rng.choice(n, size=n_lm, replace=False)).astype(np.int64)
    free = np.setdiff1d(np.arange(n), lm).astype(np.int64)
    t = np.arange(n, dtype=np.int64)
    t[free] = rng.choice(np.setdiff1d(np.arange(m), lm), size=free.size, replace=False)
    rl = obj.anchor_rows(D, t, lm)
    lb = float(rng.uniform(0.0, 1.0) * rl.mean())
    ea, eslack = np.empty((lm.size, n)), np.empty(lm.size)
    K._row_terms(D, n, t, lm, rl, lb, ea, eslack)
    scale = float(np.sum(np.abs(rl) + lb))
    used = set(t.tolist())
    for a in free:
        excess = []
        for b in free[free != a]:
            u = t.copy()
            u[a], u[b] = t[b], t[a]
            excess.append(np.maximum(obj.anchor_rows(D, u, lm) - lb, 0.0).sum())
            assert K._pair_floor(ea, rl, lb, a, b, scale) <= excess[-1]
        for y in set(range(m)) - used:
            u = t.copy()
            u[a] = y
            excess.append(np.maximum(obj.anchor_rows(D, u, lm) - lb, 0.0).sum())
        assert all(K._row_floor(ea, eslack, a, scale) <= e for e in excess)

"""The discrete refinement of LH05 (``matching.refine``) against brute force on small instances."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.spatial.distance import cdist

from shapecond.matching import consistency as C
from shapecond.matching import refine as R
from shapecond.matching.seeded import faq_match
from shapecond.matching.spectral import LH05Options, default_sigma, fine_kernel, lh05_match


def _instance(n, seed, noise=0.0):
    """Source distances of random planar points; target = a noisy copy, permuted."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(size=(n, 2)) * [2.0, 1.0]
    p[:, 1] *= 1.0 - 0.35 * p[:, 0]
    Ds = cdist(p, p)
    q = p + noise * rng.normal(size=p.shape)
    perm = rng.permutation(n)  # target j holds source perm[j]
    Dt = cdist(q, q)[np.ix_(perm, perm)]
    return Ds, Dt, np.argsort(perm)


def _K(kernel, d, e):
    """The kernel of the module docstring, written out."""
    tau2 = kernel.tol ** 2 + (kernel.rel * d) ** 2
    u = (d - e) / math.sqrt(tau2)
    phi = max(0.0, 1.0 - u * u / 4.0) ** 2
    w = 1.0 if math.isinf(kernel.radius) else max(0.0, 1.0 - d * d / (4 * kernel.radius ** 2)) ** 2
    return phi * w


def _F(Ds, Dt, t, kernel):
    n = len(t)
    return sum(_K(kernel, Ds[x, y], Dt[t[x], t[y]]) for x in range(n) for y in range(n) if x != y)


KERNELS = [C.Kernel(0.3), C.Kernel(0.2, 0.1), C.Kernel(0.15, 0.0, 0.4)]


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(KERNELS))
def test_objective_and_gain_equal_their_definitions(seed, kernel):
    Ds, Dt, _ = _instance(9, seed, noise=0.05)
    t = np.random.default_rng(seed).permutation(9)
    assert C.objective(Ds, Dt, t, kernel) == pytest.approx(_F(Ds, Dt, t, kernel), rel=1e-9, abs=1e-12)
    for x, y in ((0, 3), (4, 4), (8, 1)):
        want = sum(_K(kernel, Ds[x, xp], Dt[y, t[xp]]) for xp in range(9) if xp != x)
        assert C.gain(Ds, Dt, t, x, y, kernel) == pytest.approx(want, rel=1e-9, abs=1e-12)


def test_biweights_agree_with_gaussians_to_second_order():
    k = C.Kernel(1.0, 0.0, 1.0)
    for small in (1e-3, 1e-2):
        # φ(u) w(d) ≈ exp(-u²/2) exp(-d²/(2R²)) up to fourth-order terms
        assert _K(k, small, 0.0) == pytest.approx(math.exp(-small ** 2), abs=10 * small ** 4)
    assert _K(k, 2.0, 2.0) == 0.0 and _K(C.Kernel(1.0), 3.0, 0.5) == 0.0


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(KERNELS))
def test_polish_never_lowers_the_objective_and_ends_at_a_swap_optimum(seed, kernel):
    n = 9
    Ds, Dt, _ = _instance(n, seed, noise=0.05)
    rng = np.random.default_rng(seed)
    t0 = rng.permutation(n)
    free = np.setdiff1d(np.arange(n), [2])
    knn = R.neighbours(Dt, n - 1)  # every swap is a neighbour swap
    t, f = R.polish(Ds, Dt, t0, free, kernel, knn, k=n - 1)
    assert sorted(t) == list(range(n)) and t[2] == t0[2]
    assert f == pytest.approx(_F(Ds, Dt, t, kernel), rel=1e-9, abs=1e-12)
    assert f >= _F(Ds, Dt, t0, kernel) - 1e-12
    for a in free:
        for b in free:
            if a < b:
                s = t.copy()
                s[a], s[b] = s[b], s[a]
                assert _F(Ds, Dt, s, kernel) <= f + 1e-9


def _brute_force_swaps(Ds, Dt, t, knn, free, kernel, max_moves):
    """Best-improvement neighbour swaps, every gain from the objective (tested against its
    definition above) of the swapped map."""
    t = t.copy()
    inv = np.argsort(t)
    for move in range(max_moves):
        f = C.objective(Ds, Dt, t, kernel)
        best, pair = 1e-9, None
        for a in free:
            for y in knn[t[a]]:
                b = inv[y]
                if b != a and b in free:
                    s = t.copy()
                    s[a], s[b] = s[b], s[a]
                    gain = C.objective(Ds, Dt, s, kernel) - f
                    if gain > best:
                        best, pair = gain, (a, b)
        if pair is None:
            return t, move
        a, b = pair
        t[a], t[b] = t[b], t[a]
        inv[t[a]], inv[t[b]] = a, b
    return t, max_moves


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(KERNELS + [C.Kernel(0.1, 0.0, 0.15)]))
def test_swap_search_makes_the_moves_of_a_full_rescan(seed, kernel):
    # the swap search rescans only the samples a move can affect: the same moves as
    # recomputing every gain (short bands: some gains summed outside them; a kernel
    # of small support: moves leave most samples' gains alone)
    n, k = 40, 3
    Ds, Dt, _ = _instance(n, seed, noise=0.05)
    t0 = np.random.default_rng(seed).permutation(n)
    free = np.setdiff1d(np.arange(n), [5])
    isfree = np.isin(np.arange(n), free)
    knn = R.neighbours(Dt, k)
    p = kernel.params()
    for max_moves in (3, 50 * n):
        want, moves = _brute_force_swaps(Ds, Dt, t0, knn, set(free.tolist()), kernel, max_moves)
        t = t0.astype(np.int64)
        lists = R.swap_lists(knn, C.support_lists(Ds, p[3]))
        got = R._swap_search(Ds, Dt, t, lists, isfree, p, max_moves)
        assert got == moves and np.array_equal(t, want)


def test_reverse_extension_holds_every_swap_partners_gain():
    # a partner b of a has T b in knn[T a]: T a must be in b's band (knn[T b], then the reverse ones)
    _, Dt, _ = _instance(50, 7, noise=0.05)
    knn = R.neighbours(Dt, 4)
    ext, length = R.reverse_extension(knn)
    assert np.array_equal(ext[:, :4], knn) and np.all(ext[np.arange(ext.shape[1]) >= length[:, None]] == -1)
    for u in range(50):
        row = ext[u, :length[u]]
        assert len(set(row.tolist())) == row.size and u not in row
        assert set(row[4:].tolist()) == {v for v in range(50) if u in knn[v] and v not in knn[u]}
    rank = R.rank_table(ext)
    for v in range(50):
        for u in knn[v]:
            assert ext[u, rank[u, v] - 1] == v


@settings(max_examples=8, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(KERNELS + [C.Kernel(0.05, 0.0, 0.3)]))
def test_swap_search_estimates_skip_no_move(seed, kernel):
    # gains at reverse neighbours are summed only when their band estimate (within the slack)
    # may be a sample's best: the same moves as summing every one of them (infinite slack)
    n, k = 150, 6
    Ds, Dt, _ = _instance(n, seed, noise=0.05)
    t0 = np.random.default_rng(seed).permutation(n).astype(np.int64)
    isfree = np.ones(n, dtype=np.bool_)
    isfree[[3, 77]] = False
    p = kernel.params()
    lists = R.swap_lists(R.neighbours(Dt, k), C.support_lists(Ds, p[3]))
    runs = []
    for slack in (math.inf, None):
        t = t0.copy()
        if slack is None:
            moves = R._swap_search(Ds, Dt, t, lists, isfree, p, 50 * n)
        else:
            moves = R._moves(Ds, Dt, t, lists, isfree, p, R._bands(Ds, Dt, t, lists, p, slack), 50 * n)
        runs.append((moves, t))
    assert runs[0][0] == runs[1][0] > 0 and np.array_equal(runs[0][1], runs[1][1])


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000), st.integers(0, 30), st.sampled_from([1e-3, 0.5, 1.0, 3.0, 1e3]))
def test_selection_from_a_guess_is_the_order_statistic(seed, rank, factor):
    # any guess, far or near, below or above (ties included): the value np.partition gives
    rng = np.random.default_rng(seed)
    buf = np.round(rng.exponential(size=31), 1)  # repeated values
    want = np.partition(buf, rank)[rank]
    assert R._select_near(buf.copy(), rank, want * factor + 1e-9, np.empty(31)) == want
    assert R._select_near(buf.copy(), rank, want, np.empty(31)) == want


def test_quantile_costs_are_the_quantiles_of_the_disagreements():
    Ds, Dt, truth = _instance(60, 4, noise=0.05)
    t = np.random.default_rng(4).permutation(60).astype(np.int64)
    rows, anchors = np.arange(3, 60), np.arange(0, 60, 3)
    band = np.ascontiguousarray(np.concatenate([t[rows, None], R.neighbours(Dt, 9)[t[rows]]], axis=1))
    got = R._quantile_cost(Ds, Dt, t, rows, band, anchors, 5)
    dis = np.abs(Ds[rows][:, None, anchors] - Dt[band][:, :, t[anchors]])
    assert np.array_equal(got, np.partition(dis, 5, axis=2)[:, :, 5])


def test_robust_reassignment_keeps_a_permutation_and_recovers_a_shifted_region():
    Ds, Dt, truth = _instance(60, 3)
    t = truth.copy()
    region = np.argsort(Ds[0])[:12]  # a patch around sample 0, rotated by one position
    t[region] = truth[np.roll(region, 1)]
    free = np.setdiff1d(np.arange(60), [59])
    out = R.robust_reassignment(Ds, Dt, t, free)
    assert sorted(out) == list(range(60)) and out[59] == t[59]
    assert np.array_equal(out, truth)


@pytest.mark.parametrize("seed", [0, 1])
def test_lh05_reports_its_objective_and_beats_the_truth_on_an_isometry(seed):
    Ds, Dt, truth = _instance(80, seed)
    ls = [0, 1, 2]
    m = lh05_match(Ds, Dt, ls, truth[ls], options=LH05Options(k=10))
    kern = fine_kernel(default_sigma(Ds))
    assert m.info["objective"] == pytest.approx(C.objective(Ds, Dt, m.t, kern), rel=1e-9)
    assert m.info["objective"] >= C.objective(Ds, Dt, truth, kern) - 1e-9
    assert np.array_equal(m.t, truth)


@pytest.mark.parametrize("matcher", ["lh05", "faq"])
@pytest.mark.parametrize("seed", [4, 5, 6])
def test_correct_landmarks_do_not_cost_accuracy(matcher, seed):
    """A near-isometric pair: matching with 10 correct landmarks errs no more than with 3."""
    Ds, Dt, truth = _instance(100, seed, noise=0.004)
    order = [0]
    for _ in range(9):  # farthest-point landmarks, spread over the domain
        order.append(int(np.argmax(Ds[order].min(axis=0))))
    match = lh05_match if matcher == "lh05" else faq_match
    err = {}
    for c in (3, 10):
        t = match(Ds, Dt, order[:c], truth[order[:c]]).t
        err[c] = float(np.mean(Ds[np.arange(100), np.argsort(truth)[t]]))
    assert err[10] <= err[3] * 1.05 + 1e-12, err


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(KERNELS))
def test_compiled_gain_tables_equal_the_gain_entries(seed, kernel):
    # every compiled form of Q sums the non-zero terms of the definition in its order
    Ds, Dt, _ = _instance(12, seed, noise=0.05)
    t = np.random.default_rng(seed).permutation(12)
    p = kernel.params()
    rows = np.arange(1, 12)
    img = t[rows]
    entries = np.array([[C._gain_entry(Ds, Dt, t, x, y, p) for y in img] for x in rows])
    band = C._gain_band(Ds, Dt, t, rows, np.ascontiguousarray(np.broadcast_to(img, (rows.size, img.size))), p,
                        np.full(rows.size, img.size))
    cols = C._gain_columns(Ds, np.ascontiguousarray(Dt[img, :].T), t, rows, p)
    assert np.array_equal(cols, band)
    assert np.allclose(band, entries, rtol=1e-12, atol=1e-15)
    near = C.support_lists(Ds, p[3])
    terms, buf = C._support_terms(Ds, near, p), np.empty(near.shape[1])
    assert np.array_equal([[C._gain_near(Dt, t, near, terms, x, y, buf) for y in img] for x in rows],
                          entries)


def test_rank_table_finds_the_first_position_in_each_neighbour_list():
    knn = np.array([[1, 2, 1], [0, 2, 3], [3, 0, 1], [2, 1, 0]])
    rank = R.rank_table(knn)
    for u in range(4):
        for v in range(4):
            hits = np.flatnonzero(knn[u] == v)
            assert rank[u, v] == (hits[0] + 1 if hits.size else 0)

"""Witness search (lower bound of σ, paper Eq. 5) against brute-force enumeration."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.symmetry import objective as obj
from shapecond.symmetry.search import best_single_swap, witness_search
from shapecond.symmetry.starts import repair

from tests.helpers import (brute_sigma, dense_instance, mixed_instances, near_symmetric_instance, random_instance,
                           same)


@pytest.mark.slow
def test_n8_lower_bound_equals_enumeration_on_200_instances():
    """At N = 8 the witness search finds the exact σ on at least 196 of 200 instances, never above it."""
    from shapecond.symmetry.exact import exact_sigma  # enumeration (the exact helper's oracle)

    instances = mixed_instances(seed=3, count=200, n=8)
    hits = 0
    for k, D in enumerate(instances):
        exact = exact_sigma(D).sigma
        if k % 20 == 0:  # cross-check the oracle against this file's enumeration
            assert same(exact, brute_sigma(D)[0])
        res = witness_search(D, seed=k)
        assert res.sigma <= exact * (1 + 1e-9) or exact == math.inf
        assert same(obj.map_score(D, res.witness), res.sigma)
        hits += same(res.sigma, exact)
    assert hits >= 196, hits


def test_landmarks_are_fixed_and_bound_matches_enumeration():
    rng = np.random.default_rng(5)
    for k in range(20):
        D = near_symmetric_instance(rng, 8, 2 + k % 2, 0.05) if k % 2 else random_instance(rng, 8, 3)
        lm = tuple(int(v) for v in rng.choice(8, size=1 + k % 3, replace=False))
        exact, _ = brute_sigma(D, landmarks=lm)
        res = witness_search(D, landmarks=lm, seed=k)
        assert np.all(res.witness[list(lm)] == list(lm))
        assert same(res.sigma, exact)
        assert res.sigma <= witness_search(D, seed=k).sigma * (1 + 1e-12)  # landmarks only lower σ


@pytest.mark.slow
def test_dense_targets_against_injective_enumeration():
    """Dense targets: the search over injective maps of N <= 6 samples into M <= 10 targets against
    enumeration."""
    rng = np.random.default_rng(7)
    hits = total = 0
    for k in range(16):
        n, m = (5, 9) if k % 2 else (6, 10)
        D = dense_instance(rng, n, m, 2 + k % 2, noise=None if k % 4 < 2 else 0.05)
        exact, _ = brute_sigma(D, n)
        res = witness_search(D, n_samples=n, seed=k)
        assert res.witness.shape == (n,) and len(set(res.witness.tolist())) == n
        assert res.witness.max() < m
        assert res.sigma <= exact * (1 + 1e-9)
        assert res.sigma >= brute_sigma(D[:n, :n])[0] * (1 - 1e-9)  # dense >= bijections
        hits += same(res.sigma, exact)
        total += 1
    assert hits >= total - 1, (hits, total)


def test_exact_symmetry_gives_inf_with_an_isometric_witness():
    rng = np.random.default_rng(11)
    for k in range(5):
        D = near_symmetric_instance(rng, 10 + k, 3, 0.0)
        res = witness_search(D, seed=k)
        assert res.sigma == math.inf
        assert obj.is_isometry(D, obj.dist2(D, res.witness))
        assert obj.d2(D, res.witness) > 0


def test_best_single_swap_is_exact_over_all_swaps():
    rng = np.random.default_rng(2)
    for k in range(10):
        D = random_instance(rng, 9, 2 + k % 2)
        lm = (0, 4) if k % 2 else ()
        sigma, a, b = best_single_swap(D, landmarks=lm)
        best = 0.0
        for i, j in itertools.combinations([x for x in range(9) if x not in lm], 2):
            t = np.arange(9)
            t[[i, j]] = [j, i]
            best = max(best, obj.map_score(D, t))
        assert same(sigma, best)
        t = np.arange(9)
        t[[a, b]] = [b, a]
        assert same(obj.map_score(D, t), sigma)
        assert witness_search(D, landmarks=lm, effort="quick").sigma >= sigma * (1 - 1e-12)


def test_floor_one_over_sqrt_two_n_minus_two():
    """Every metric space has a swap with σ >= 1/sqrt(2(N-2)) (the floor of every score)."""
    rng = np.random.default_rng(4)
    for n in (5, 12, 30):
        D = random_instance(rng, n, 3)
        assert best_single_swap(D)[0] >= 1.0 / math.sqrt(2 * (n - 2)) * (1 - 1e-12)


def test_deterministic_and_maps_distinct_best_first():
    D = random_instance(np.random.default_rng(8), 30, 3)
    a = witness_search(D, seed=4)
    b = witness_search(D, seed=4)
    assert np.array_equal(a.witness, b.witness) and a.sigma == b.sigma
    assert list(a.sigmas) == sorted(a.sigmas, reverse=True) and a.sigmas[0] == a.sigma
    keys = {m.tobytes() for m in a.maps}
    assert len(keys) == len(a.maps) <= 5
    for m, s in zip(a.maps, a.sigmas):
        assert same(obj.map_score(D, m), s)
    assert not np.array_equal(a.witness, np.arange(30))


def test_warm_start_is_repaired_and_never_hurts():
    rng = np.random.default_rng(9)
    D = near_symmetric_instance(rng, 40, 3, 0.02)
    cold = witness_search(D, seed=1, effort="quick")
    bad = np.zeros(40, dtype=np.int64)  # not injective, moves landmark 3
    warm = witness_search(D, seed=1, effort="quick", landmarks=(3,), starts=[bad, cold.witness])
    assert warm.witness[3] == 3
    fixed = repair(bad, 40, 40, np.array([3]))
    assert len(set(fixed.tolist())) == 40 and fixed[3] == 3


def test_time_limit_returns_a_valid_witness():
    D = random_instance(np.random.default_rng(1), 60, 3)
    res = witness_search(D, time_limit=0.0)
    assert res.sigma >= best_single_swap(D)[0] * (1 - 1e-12)
    assert same(obj.map_score(D, res.witness), res.sigma)


@pytest.mark.parametrize("kwargs, message", [
    (dict(D=np.zeros((3, 4))), "square"),
    (dict(D=np.full((4, 4), np.nan)), "NaN"),
    (dict(D=np.ones((4, 4)) - np.eye(4), landmarks=(0, 0)), "repeat"),
    (dict(D=np.ones((4, 4)) - np.eye(4), landmarks=(7,)), "not a sample index"),
    (dict(D=np.ones((4, 4)) - np.eye(4), landmarks=(0, 1, 2)), "free"),
    (dict(D=np.ones((4, 4)) - np.eye(4), n_samples=1), "samples"),
    (dict(D=np.ones((4, 4)) - np.eye(4), effort="huge"), "effort"),
    (dict(D=np.ones((4, 4))), "diagonal"),
    (dict(D=np.array([[0, 1, 2.0], [1, 0, 1], [1, 1, 0]])), "symmetric"),
    (dict(D=np.array([[0, -1, 2.0], [-1, 0, 1], [2, 1, 0]])), "negative"),
])
def test_bad_input_raises_input_error(kwargs, message):
    with pytest.raises(InputError, match=message):
        witness_search(**kwargs)


def test_n12_n16_lower_over_exact_at_least_0_9_on_90_percent():
    """At N = 12 and 16 the witness search reaches at least 0.9 of the exact σ (branch and bound) on
    90 % of the instances."""
    from shapecond.symmetry.exact import exact_sigma

    for n, count in ((12, 20), (16, 10)):
        ratios = []
        for k, D in enumerate(mixed_instances(seed=40 + n, count=count, n=n)):
            ex = exact_sigma(D, time_limit=20)
            if not ex.finished:
                continue
            res = witness_search(D, seed=k)
            assert res.sigma <= ex.sigma * (1 + 1e-9)
            ratios.append(1.0 if res.sigma == ex.sigma else res.sigma / ex.sigma)
        assert len(ratios) >= count - 1
        assert np.mean(np.array(ratios) >= 0.9) >= 0.9, (n, ratios)


@pytest.mark.parametrize("budget", [None, 0.5])
def test_the_same_result_with_one_thread_and_with_two(budget):
    """The starts of a phase are polished in threads and taken in order (``threads``): the
    pool, hence the witness and every kept map, is the one of a serial loop."""
    import numba

    from shapecond.symmetry.resolution import coarse_to_fine

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba has one thread on this machine")
    D = dense_instance(np.random.default_rng(5), 40, 320, 3)
    b = None if budget is None else budget * obj.dist2(D, np.roll(np.arange(40), 1))
    out = []
    before = numba.get_num_threads()
    try:
        for k in (1, 2):
            numba.set_num_threads(k)
            r = witness_search(D, 40, landmarks=[2], seed=3, budget=b)
            fine, coarse = coarse_to_fine(D, 40, seed=3, budget=b)
            out.append([m.tobytes() for res in (r, fine, coarse) for m in res.maps] + [r.sigma, fine.sigma])
    finally:
        numba.set_num_threads(before)
    assert out[0] == out[1]


def test_budget_search_does_not_polish_starts_far_off_a_landmark_row(monkeypatch):
    # HOPELESS_START: a start whose landmark row is far above its budget is dropped, one within it is polished
    import shapecond.symmetry.search as S

    rng = np.random.default_rng(3)
    pts = rng.normal(size=(40, 3))
    D = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1))
    n, lm = 40, [0]
    far = np.arange(n)
    far[1:] = np.roll(np.arange(1, n), 7)  # moves every other sample: row 0 far off
    near = np.arange(n)
    b = 2 + int(np.argmin(D[1, 2:]))  # swap sample 1 with its nearest neighbour
    near[[1, b]] = [b, 1]
    budget = 1.5 * max(obj.dist2(D, near), obj.anchor_rows(D, near, lm)[0] * n)
    assert obj.anchor_rows(D, far, lm)[0] > S.HOPELESS_START * budget / n
    polished = []
    orig = S.SearchStage.polished

    def spy(self, ts, *args, **kw):
        polished.extend(np.asarray(t).tobytes() for t in ts)
        return orig(self, ts, *args, **kw)

    monkeypatch.setattr(S.SearchStage, "polished", spy)
    witness_search(D, n_samples=n, landmarks=lm, starts=[far, near], effort="quick", budget=budget)
    assert near.astype(np.int64).tobytes() in polished
    assert far.astype(np.int64).tobytes() not in polished


def test_nearest_targets_are_the_nearest_and_kept_for_a_read_only_matrix():
    """The k nearest other targets of every target (against a full sort), computed once per
    read-only matrix and again for a writable one (it may change)."""
    from shapecond.checks import check_distance_matrix
    from shapecond.symmetry.search import nearest_targets

    rng = np.random.default_rng(7)
    P = rng.normal(size=(30, 3))
    raw = np.linalg.norm(P[:, None] - P[None], axis=2)
    D = check_distance_matrix(raw)  # read-only
    k = 5
    knn = nearest_targets(D, k)
    for y in range(30):
        order = [v for v in np.argsort(D[y], kind="stable") if v != y]
        assert set(knn[y]) == set(order[:k]) and y not in knn[y]
    assert nearest_targets(D, k) is knn
    assert nearest_targets(raw, k) is not nearest_targets(raw, k)

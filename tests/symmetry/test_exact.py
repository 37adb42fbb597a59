"""Exact σ (Eq. 5): enumeration against brute force, branch and bound against enumeration."""

import itertools
import math

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.symmetry import objective
from shapecond.symmetry._bnb import branch_and_bound, swap_search
from shapecond.symmetry.exact import _enumerate, enumerate_maps, exact_sigma, map_count
from tests.helpers import dense_instance, near_symmetric_instance, random_instance


def brute_force(D, n, landmarks=()):
    """σ by a plain loop over itertools.permutations and objective.map_score."""
    M = D.shape[0]
    free = [x for x in range(n) if x not in landmarks]
    targets = [y for y in range(M) if y not in landmarks]
    best = 0.0
    for img in itertools.permutations(targets, len(free)):
        t = np.arange(n)
        t[free] = img
        if np.all(t == np.arange(n)):
            continue
        best = max(best, objective.map_score(D, t))
    return best


def bnb(D, n, landmarks, warm=True):
    r0, w0 = swap_search(D, n, landmarks, np.random.default_rng(0)) if warm else (0.0, None)
    r, t, finished, _ = branch_and_bound(D, n, landmarks, r0, w0, None)
    assert finished
    return math.sqrt(r), t


@pytest.mark.parametrize("n,m,landmarks", [(5, 5, ()), (6, 6, (2,)), (4, 7, ()), (5, 8, (0, 3))])
def test_enumeration_matches_brute_force(n, m, landmarks):
    rng = np.random.default_rng(n * 10 + m)
    for noise in (None, 0.05):
        D = dense_instance(rng, n, m, 2, noise)
        e = exact_sigma(D, n_samples=n, landmarks=landmarks)
        assert e.method == "enumeration" and e.finished
        assert e.sigma == pytest.approx(brute_force(D, n, landmarks), rel=1e-12)
        assert objective.map_score(D, e.witness) == pytest.approx(e.sigma, rel=1e-12)
        assert all(e.witness[l] == l for l in landmarks)


def test_enumerate_maps_counts_and_injectivity():
    maps = enumerate_maps(5, 7, (1,))
    assert maps.shape == (map_count(5, 7, 1), 5) == (360, 5)
    assert np.all(maps[:, 1] == 1)
    assert all(len(set(row)) == 5 for row in maps)
    assert len({tuple(r) for r in maps}) == maps.shape[0]


@pytest.mark.parametrize("seed", range(6))
def test_branch_and_bound_matches_enumeration(seed):
    rng = np.random.default_rng(100 + seed)
    for k in range(6):
        n = int(rng.integers(4, 10))
        dim = 2 + k % 2
        D = random_instance(rng, n, dim) if k % 2 else near_symmetric_instance(rng, n, dim, (0.01, 0.1, 0.3)[k % 3])
        L = sorted(rng.choice(n, int(rng.integers(0, 3)), replace=False).tolist()) if k >= 3 else []
        r_enum, _, _ = _enumerate(D, n, L)
        for warm in (True, False):
            s, t = bnb(D, n, L, warm)
            assert s == pytest.approx(math.sqrt(r_enum), rel=1e-10)
            assert objective.map_score(D, t) == pytest.approx(s, rel=1e-10)
            assert all(t[l] == l for l in L) and not np.all(t == np.arange(n))


def test_branch_and_bound_injective_matches_enumeration():
    rng = np.random.default_rng(7)
    for k in range(8):
        n, m = int(rng.integers(3, 7)), 0
        m = min(n + int(rng.integers(1, 5)), 10)
        D = dense_instance(rng, n, m, 2 + k % 2, None if k % 2 else 0.05)
        L = [0] if k % 3 == 0 else []
        r_enum, _, _ = _enumerate(D, n, L)
        s, t = bnb(D, n, L, warm=bool(k % 2))
        assert s == pytest.approx(math.sqrt(r_enum), rel=1e-10)
        assert np.unique(t).size == n and t.max() < m


def test_branch_and_bound_n12_against_enumeration_with_landmarks():
    """N = 12 with 3 landmarks: 9! maps, so enumeration is the oracle for B&B."""
    rng = np.random.default_rng(12)
    D = random_instance(rng, 12, 2)
    L = [0, 5, 9]
    r_enum, _, _ = _enumerate(D, 12, L)
    s, _ = bnb(D, 12, L)
    assert s == pytest.approx(math.sqrt(r_enum), rel=1e-10)


def test_branch_and_bound_n11_finishes_and_beats_every_swap():
    rng = np.random.default_rng(3)
    D = near_symmetric_instance(rng, 11, 3, 0.1)
    e = exact_sigma(D, time_limit=60)
    assert e.method == "branch-and-bound" and e.finished
    assert objective.map_score(D, e.witness) == pytest.approx(e.sigma, rel=1e-12)
    for a, b in itertools.combinations(range(11), 2):
        t = np.arange(11)
        t[[a, b]] = [b, a]
        assert objective.map_score(D, t) <= e.sigma * (1 + 1e-12)


def test_isometry_gives_inf_with_an_isometric_witness():
    rng = np.random.default_rng(5)
    for n in (7, 11):  # enumeration, then branch and bound
        D = near_symmetric_instance(rng, n, 3, 0.0)
        e = exact_sigma(D)
        assert e.sigma == math.inf and e.finished
        assert objective.is_isometry(D, objective.dist2(D, e.witness))
        assert objective.d2(D, e.witness) > 0


def test_time_limit_reports_not_finished_instead_of_a_value():
    D = random_instance(np.random.default_rng(1), 20, 2)
    e = exact_sigma(D, time_limit=1e-6)
    assert not e.finished and e.sigma is None
    assert e.witness is not None and e.lower > 0
    assert objective.map_score(D, e.witness) == pytest.approx(e.lower)


def test_landmarks_can_only_lower_sigma():
    rng = np.random.default_rng(9)
    D = random_instance(rng, 8, 2)
    s0 = exact_sigma(D).sigma
    s1 = exact_sigma(D, landmarks=[3]).sigma
    s2 = exact_sigma(D, landmarks=[3, 6]).sigma
    assert s0 >= s1 >= s2 > 0


def test_no_free_map_scores_zero():
    D = random_instance(np.random.default_rng(0), 4, 2)
    e = exact_sigma(D, landmarks=[0, 1, 2])
    assert e.sigma == 0.0 and e.witness is None and e.finished


@pytest.mark.parametrize("D,kw,match", [
    (np.zeros((3, 4)), {}, "square"),
    (np.array([[0, 1.0], [1.0, np.nan]]), {}, "NaN"),
    (np.array([[0, 1.0, 2], [1, 0, 1], [2, 1, 0]]), {"landmarks": [3]}, "landmark 3"),
    (np.array([[0, 1.0, 2], [1, 0, 1], [2, 1, 0]]), {"landmarks": [1, 1]}, "repeated"),
    (np.array([[0, 1.0, 2], [1, 0, 1], [2, 3, 0]]), {}, "symmetric"),
    (np.array([[0, 1.0, 2], [1, 0, 1], [2, 1, 0]]), {"n_samples": 1}, "samples"),
])
def test_bad_input_raises_input_error(D, kw, match):
    with pytest.raises(InputError, match=match):
        exact_sigma(D, **kw)

"""Start maps of the witness search: each family is a bijection of the samples fixing the
landmarks, and each finds what it is built for (sign flips and reflections a mirror, Gilmore–Lawler
a near-isometry from a valid lower bound of the distortion)."""

import itertools

import numpy as np
import pytest
from scipy.spatial.distance import cdist

from shapecond.symmetry import objective as obj
from shapecond.symmetry import starts as S
from shapecond.symmetry.search import witness_search

from tests.helpers import random_instance


def _mirrored_cloud(n=40, extra=40, seed=0):
    """Samples X in R^6 (distinct axis scales) and targets Y = X ∪ R(X) ∪ noise,
    R flipping three coordinates at once (not one or two): returns D, n, mirror."""
    rng = np.random.default_rng(seed)
    scale = np.array([6.0, 5.0, 4.0, 3.0, 2.0, 1.0])
    flip = np.array([1.0, -1.0, 1.0, -1.0, -1.0, 1.0])
    A = rng.standard_normal((n // 2, 6)) * scale
    # X itself nearly symmetric (as on a TOSCA animal), its exact mirror in Y
    X = np.vstack([A, A * flip + 0.05 * rng.standard_normal(A.shape)])
    Z = rng.standard_normal((extra, 6)) * scale
    P = np.vstack([X, X * flip, Z])
    D = cdist(P, P)
    return D / D.max(), n, np.arange(n, 2 * n)


def test_reflection_start_finds_multi_coordinate_mirror():
    D, n, mirror = _mirrored_cloud()
    free = np.arange(n)
    cand = S.reflection_starts(D, n, free, np.array([], dtype=np.int64))
    assert cand, "no reflection start"
    agree = max(np.mean(t == mirror) for t in cand)
    assert agree >= 0.9


def _mirror_pairs(seed=0, half=9, on_plane=2):
    """Points in R^3 (axis scales 3, 2, 1) and their mirror images across y = 0, then ``on_plane``
    points on the plane: (distance matrix, mirror map, indices of the points on the plane)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((half, 3)) * [3.0, 2.0, 1.0]
    A[:, 1] = np.abs(A[:, 1]) + 0.3
    mid = rng.standard_normal((on_plane, 3)) * [3.0, 2.0, 1.0]
    mid[:, 1] = 0.0
    P = np.vstack([A, A * [1.0, -1.0, 1.0], mid])
    D = cdist(P, P)
    plane = np.arange(2 * half, 2 * half + on_plane)
    return D / D.max(), np.r_[np.arange(half, 2 * half), np.arange(half), plane], plane


def _valid(t, n, landmarks):
    return t.shape == (n,) and np.array_equal(np.sort(t), np.arange(n)) and np.all(t[landmarks] == landmarks)


def test_a_sign_flip_start_is_the_mirror_and_every_start_fixes_the_landmarks():
    """A mirror commutes with D, so it flips the sign of an embedding coordinate: one of the
    spectral starts is exactly the mirror, with the points on the mirror plane held fixed."""
    D, mirror, plane = _mirror_pairs()
    n = len(D)
    for fixed in (np.array([], dtype=np.int64), plane):
        free = np.setdiff1d(np.arange(n), fixed)
        starts = S.spectral_starts(D, free, 10, 5)
        assert any(np.array_equal(t, mirror) for t in starts)
        assert all(_valid(t, n, fixed) and np.any(t != np.arange(n)) for t in starts)
    off_plane = np.array([0, 4])  # landmarks the mirror moves: no start may move them
    starts = S.spectral_starts(D, np.setdiff1d(np.arange(n), off_plane), 10, 5)
    assert starts and all(_valid(t, n, off_plane) for t in starts)


@pytest.mark.parametrize("landmarks", [(), (2,), (0, 5)])
def test_gilmore_lawler_is_the_best_bound_of_each_row(landmarks):
    """GL[x, y] is the least distortion of row x over the maps T with T x = y that fix the
    landmarks (sorted rows on the free columns, landmark columns exact; checked on all such maps
    of 7 points), hence Σ_x GL[x, T x] <= Dist²(T) for every such map."""
    D = random_instance(np.random.default_rng(len(landmarks)), 7, 3)
    lm = np.array(landmarks, dtype=np.int64)
    GL = S.gilmore_lawler(D, lm)
    free = [x for x in range(7) if x not in landmarks]
    least = np.full((7, 7), np.inf)
    for perm in itertools.permutations(free):
        t = np.arange(7)
        t[free] = perm
        rows = ((D - D[np.ix_(t, t)]) ** 2).sum(axis=1)
        least[np.arange(7), t] = np.minimum(least[np.arange(7), t], rows)
        assert GL[np.arange(7), t].sum() <= obj.dist2(D, t) + 1e-12
    reachable = np.isfinite(least)
    assert np.allclose(GL[reachable], least[reachable], rtol=1e-9, atol=1e-12)


def test_gilmore_lawler_starts_fix_the_landmarks_and_find_the_mirror_at_large_s():
    """Small s favours displacement, large s maps of zero bound: with a landmark on the mirror
    plane the largest s gives the mirror (its bound is 0, and it moves farther than the identity)."""
    D, mirror, plane = _mirror_pairs(seed=1)
    n = len(D)
    lm = plane[:1]
    free = np.setdiff1d(np.arange(n), lm)
    assert np.allclose(S.gilmore_lawler(D, lm)[np.arange(n), mirror], 0.0, atol=1e-12)
    starts = S.gilmore_lawler_starts(D, free, lm, [0.0, 1.0, 10.0, 1e4])
    assert all(_valid(t, n, lm) for t in starts)
    assert np.array_equal(S.gilmore_lawler_starts(D, free, lm, [1e4])[0], mirror)


def test_witness_search_dense_reaches_mirror():
    D, n, mirror = _mirrored_cloud(seed=1)
    r = witness_search(D, n)
    assert r.sigma == np.inf


@pytest.mark.parametrize("landmarks", [(), (0, 5)])
def test_reflection_starts_are_valid_and_deterministic(landmarks):
    D, n, _ = _mirrored_cloud(n=24, extra=10, seed=2)
    lm = np.array(landmarks, dtype=np.int64)
    free = np.setdiff1d(np.arange(n), lm)
    a = S.reflection_starts(D, n, free, lm, n_coords=5, n_best=3)
    b = S.reflection_starts(D, n, free, lm, n_coords=5, n_best=3)
    assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b))
    for t in a:
        assert t.shape == (n,) and np.unique(t).size == n
        assert t.min() >= 0 and t.max() < D.shape[0]
        assert np.all(t[lm] == lm)
        assert np.any(t != np.arange(n))


def test_landmark_mds_extends_exactly_on_samples():
    D, n, _ = _mirrored_cloud(n=20, extra=5, seed=3)
    phi, psi = S._landmark_mds(D, n, 4)
    assert np.allclose(psi[:n], phi, atol=1e-10)


def test_bijection_reflection_start():
    """M = N: the reflection of the samples onto themselves."""
    rng = np.random.default_rng(4)
    X = rng.standard_normal((15, 4)) * np.array([4.0, 3.0, 2.0, 1.0])
    P = np.vstack([X, X * np.array([1.0, -1.0, -1.0, 1.0])])
    D = cdist(P, P)
    D /= D.max()
    n = P.shape[0]
    mirror = np.r_[np.arange(15, 30), np.arange(15)]
    cand = S.reflection_starts(D, n, np.arange(n), np.array([], dtype=np.int64))
    assert any(np.mean(t == mirror) >= 0.9 for t in cand)
    assert witness_search(D).sigma == np.inf


def test_remembered_starts_are_the_computed_ones_and_read_only():
    """``starts._memo``: a repeated call returns the maps of a fresh computation, in a new list
    of read-only arrays, and different arguments (landmarks, grid) are not confused."""
    rng = np.random.default_rng(5)
    pts = rng.normal(size=(30, 3))
    D = cdist(pts, pts)
    free = np.arange(1, 30, dtype=np.int64)
    first = S.spectral_starts(D, free, 6, 3)
    again = S.spectral_starts(D.copy(), free.copy(), 6, 3)
    fresh = S.spectral_starts.__wrapped__(D, free, 6, 3)
    assert again is not first and len(first) == len(fresh)
    assert all(np.array_equal(a, b) for a, b in zip(again, fresh))
    with pytest.raises(ValueError):
        again[0][0] = 1
    again.sort(key=lambda t: int(t[3]))  # the caller's list, not the remembered one
    assert all(np.array_equal(a, b) for a, b in zip(S.spectral_starts(D, free, 6, 3), fresh))
    grid = [1.0, 0.25]
    a = S.gilmore_lawler_starts(D, free, np.array([0]), grid)
    b = S.gilmore_lawler_starts(D, np.arange(2, 30), np.array([0, 1]), grid)
    fresh = S.gilmore_lawler_starts.__wrapped__(D, free, np.array([0]), grid)
    assert all(np.array_equal(x, y) for x, y in zip(a, fresh))
    assert all(t[1] == 1 for t in b)

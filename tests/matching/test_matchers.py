"""Sample matchers (LH05 spectral, FAQ seeded) against known correspondences."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.spatial.distance import cdist

from shapecond.errors import InputError
from shapecond.matching.candidates import (check_landmarks, descriptor_cost, k_best_candidates,
                                           recall)
from shapecond.matching.nested import with_landmarks
from shapecond.matching.seeded import FAQOptions, faq_match, local_width
from shapecond.matching.spectral import (LH05Options, affinity_matrix, assignment_rounding, complete_map,
                                         greedy_discretisation, lh05_match, principal_eigenvector)


def _planar(n, seed):
    """Distances of n random points in an asymmetric planar domain (an isometry class)."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(size=(n, 2)) * [2.0, 1.0]
    p[:, 1] *= 1.0 - 0.35 * p[:, 0]
    return p, cdist(p, p)


def _permuted(D, seed):
    """Target = the same metric with points permuted; truth[x] = target index of x."""
    perm = np.random.default_rng(seed).permutation(D.shape[0])  # target j is source perm[j]
    truth = np.argsort(perm)
    return D[np.ix_(perm, perm)], truth


def test_bad_landmarks_are_input_errors():
    with pytest.raises(InputError, match="counts differ"):
        check_landmarks(10, 10, [1, 2], [1])
    with pytest.raises(InputError, match="out of range"):
        check_landmarks(10, 10, [1, 12], [1, 2])
    with pytest.raises(InputError, match="repeated"):
        check_landmarks(10, 10, [1, 1], [1, 2])
    _, D = _planar(20, 0)
    with pytest.raises(InputError, match="counts differ"):
        lh05_match(D, D, [0, 1, 2], [0, 1])
    with pytest.raises(InputError, match="same number of samples"):
        faq_match(D, D[:15, :15], [0], [0])


@pytest.mark.parametrize("matcher", [lh05_match, faq_match])
@pytest.mark.parametrize("damage, needle", [("inf", "NaN or infinite"), ("nan", "NaN or infinite"),
                                            ("asymmetric", "not symmetric"), ("negative", "negative")])
def test_invalid_distances_are_input_errors(matcher, damage, needle):
    """An invalid matrix (e.g. infinite distances of a disconnected surface) is refused with one
    clear error, not matched into a number nor a scipy traceback."""
    _, D = _planar(20, 0)
    E = D.copy()
    E[0, 5] = {"inf": np.inf, "nan": np.nan, "asymmetric": 2.0 * E[0, 5], "negative": -1.0}[damage]
    if damage != "asymmetric":
        E[5, 0] = E[0, 5]
    with pytest.raises(InputError, match=needle):
        matcher(D, E, [0, 1, 2], [0, 1, 2])
    with pytest.raises(InputError, match=needle):
        matcher(E, D, [0, 1, 2], [0, 1, 2])


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 6))
def test_k_best_candidates_equal_brute_force(seed, k):
    _, Ds = _planar(12, seed)
    Dt, truth = _permuted(Ds, seed + 1)
    ls, lt = [0, 3], truth[[0, 3]]
    cand = k_best_candidates(Ds, Dt, ls, lt, k=k)
    cost = descriptor_cost(Ds, Dt, ls, lt)
    for x in range(12):
        got = sorted(cand.target[cand.source == x])
        if x in ls:
            assert got == [lt[ls.index(x)]]
            continue
        free = [y for y in range(12) if y not in set(lt)]
        want = sorted(sorted(free, key=lambda y: (cost[x, y], y))[:k])
        # ties aside, the k smallest costs are the same set
        assert np.allclose(sorted(cost[x, got]), sorted(cost[x, want]))
    # a true isometric copy: descriptors coincide, recall is perfect
    assert recall(cand, truth) == 1.0


def test_affinity_matrix_matches_definition():
    _, Ds = _planar(7, 3)
    Dt, truth = _permuted(Ds, 4)
    cand = k_best_candidates(Ds, Dt, [0], [truth[0]], k=3)
    s = 0.2
    M = affinity_matrix(Ds, Dt, cand, s)
    assert np.allclose(M, affinity_matrix(Ds, Dt, cand, s, compiled=False), rtol=1e-5, atol=1e-7)
    for a in range(cand.size):
        for b in range(cand.size):
            x, y, x2, y2 = cand.source[a], cand.target[a], cand.source[b], cand.target[b]
            # the biweight of width s: (1 - diff² / (2s)²)² inside |diff| < 2s
            u = max(0.0, 1.0 - (Ds[x, x2] - Dt[y, y2]) ** 2 / (4 * s * s))
            want = 0.0 if (x == x2 or y == y2) else u * u
            assert M[a, b] == pytest.approx(want, rel=1e-5, abs=1e-7)


def test_power_iteration_finds_perron_vector():
    rng = np.random.default_rng(0)
    A = rng.uniform(size=(30, 30)).astype(np.float32)
    A = A + A.T
    v, _, ok = principal_eigenvector(A, tol=1e-7, max_iter=1000)
    w, V = np.linalg.eigh(A.astype(np.float64))
    assert ok
    assert np.allclose(v, np.abs(V[:, -1]), atol=1e-4)


def test_roundings_are_injective_and_keep_landmarks():
    _, Ds = _planar(40, 5)
    Dt, truth = _permuted(Ds, 6)
    ls, lt = [2, 9], truth[[2, 9]]
    cand = k_best_candidates(Ds, Dt, ls, lt, k=4)
    v = np.random.default_rng(1).uniform(size=cand.size)
    for t in (greedy_discretisation(cand, v, 40), assignment_rounding(cand, v, 40, 40)):
        t = complete_map(Ds, Dt, t)
        assert sorted(t) == list(range(40))
        assert list(t[ls]) == list(lt)


@pytest.mark.parametrize("rounding", ["greedy", "assignment"])
def test_lh05_recovers_an_isometric_permutation(rounding):
    _, Ds = _planar(120, 7)
    Dt, truth = _permuted(Ds, 8)
    ls = [0, 1, 2]
    m = lh05_match(Ds, Dt, ls, truth[ls], options=LH05Options(k=10, rounding=rounding))
    assert np.mean(m.t == truth) >= 0.98
    assert list(m.t[ls]) == list(truth[ls])


@pytest.mark.parametrize("objective", ["local", "distance", "gaussian"])
def test_faq_recovers_an_isometric_permutation(objective):
    _, Ds = _planar(120, 9)
    Dt, truth = _permuted(Ds, 10)
    ls = [0, 1, 2]
    m = faq_match(Ds, Dt, ls, truth[ls], options=FAQOptions(objective=objective))
    assert np.mean(m.t == truth) >= 0.98
    assert list(m.t[ls]) == list(truth[ls])


def test_local_width_is_the_spacing_over_the_landmark_pairs_mean_log_ratio():
    """``local_width``, against its definition computed here: a metric stretched by one factor along
    x (not an isometry) gives a finite width; an exact copy, one landmark, or a width beyond every
    distance give None (the distance objective)."""
    p, Ds = _planar(80, 3)
    q = p * [1.4, 1.0]
    Dt = cdist(q, q)
    ls = np.array([0, 5, 9, 17])
    iu = np.triu_indices(ls.size, 1)
    r = np.abs(np.log(Dt[np.ix_(ls, ls)][iu] / Ds[np.ix_(ls, ls)][iu])).mean()
    h = np.median(np.sort(Ds, axis=1)[:, 1])
    assert local_width(Ds, Dt, ls, ls) == pytest.approx(h / r, rel=1e-12)
    assert local_width(Ds, Ds, ls, ls) is None
    assert local_width(Ds, Dt, ls[:1], ls[:1]) is None
    assert local_width(Ds, Ds * 1.0001, ls, ls) is None  # h / r far beyond the largest distance
    with pytest.raises(InputError, match="unknown FAQ objective"):
        FAQOptions(objective="nearest")


def test_faq_local_objective_recovers_a_stretched_permutation():
    """Off isometry (one axis stretched by 1.4, so the width is finite) the local objective still
    maps a permuted copy's samples onto their images; the width used is reported."""
    p, Ds = _planar(120, 9)
    perm = np.random.default_rng(10).permutation(120)
    q = (p * [1.4, 1.0])[perm]
    Dt, truth = cdist(q, q), np.argsort(perm)
    ls = [0, 1, 2, 3]
    m = faq_match(Ds, Dt, ls, truth[ls], FAQOptions(objective="local"))
    assert m.info["objective"] == "gaussian" and m.info["sigma"] == local_width(Ds, Dt, ls, truth[ls])
    assert np.mean(m.t == truth) >= 0.9


def test_faq_local_objective_nests_at_its_own_width(monkeypatch):
    """The first three landmarks' run of ``objective="local"`` uses the width measured on all of
    them, so the nested maps compare on one objective: the returned map's objective is at least that
    of the first three's map sent to the other landmarks, at that width."""
    import shapecond.matching.seeded as seeded
    calls = []
    real = seeded.faq_match
    monkeypatch.setattr(seeded, "faq_match", lambda *a: calls.append(a[4]) or real(*a))
    rng = np.random.default_rng(4)
    p, Ds = _planar(90, 4)
    q = p * [1.3, 1.0] + rng.normal(scale=0.02, size=p.shape)
    Dt = cdist(q, q)
    ls = np.array([0, 7, 19, 33, 41, 60])
    s = local_width(Ds, Dt, ls, ls)
    K = np.exp(-Ds ** 2 / (2 * s * s)), np.exp(-Dt ** 2 / (2 * s * s))
    F = lambda t: float((K[0] * K[1][np.ix_(t, t)]).sum())  # noqa: E731
    full = real(Ds, Dt, ls, ls, FAQOptions(objective="local"))
    assert [(o.objective, o.sigma) for o in calls] == [("gaussian", s)]  # the nested run, at the width
    core = real(Ds, Dt, ls[:3], ls[:3], FAQOptions(objective="gaussian", sigma=s))
    assert full.info["sigma"] == s and full.info["value"] == pytest.approx(F(full.t), rel=1e-12)
    assert F(full.t) >= F(with_landmarks(core.t, ls, ls)) - 1e-9 * F(full.t)


def _fps(p, n, start):
    idx = [start]
    d = np.linalg.norm(p - p[start], axis=1)
    for _ in range(n - 1):
        idx.append(int(np.argmax(d)))
        d = np.minimum(d, np.linalg.norm(p - p[idx[-1]], axis=1))
    return np.array(idx)


def test_matchers_on_two_different_samplings():
    """Source and target sample the same domain independently: errors ~ one spacing."""
    rng = np.random.default_rng(11)
    p = rng.uniform(size=(5000, 2)) * [2.0, 1.0]
    p = p[p[:, 1] < 1.0 - 0.35 * p[:, 0]]
    a, b = p[_fps(p, 150, 0)], p[_fps(p, 150, 1)].copy()
    ls = np.array([0, 1, 2])
    lt = np.array([10, 20, 30])
    b[lt] = a[ls]
    Ds, Dt = cdist(a, a), cdist(b, b)
    spacing = np.median(np.sort(Ds, 1)[:, 1])
    for m in (lh05_match(Ds, Dt, ls, lt, options=LH05Options(k=20)), faq_match(Ds, Dt, ls, lt)):
        err = np.linalg.norm(a - b[m.t], axis=1)
        assert err.mean() < 2.5 * spacing, m.matcher
        assert np.median(err) < 1.5 * spacing, m.matcher


def test_sparse_affinity_of_a_local_kernel_equals_the_dense_reference():
    from shapecond.matching.consistency import Kernel

    _, Ds = _planar(30, 5)
    Dt, truth = _permuted(Ds, 6)
    cand = k_best_candidates(Ds, Dt, [0, 1], [truth[0], truth[1]], k=4)
    kernel = Kernel(0.05, 0.0, 0.15)
    M = affinity_matrix(Ds, Dt, cand, kernel)  # compiled: CSR, one pass
    ref = affinity_matrix(Ds, Dt, cand, kernel, compiled=False)
    assert M.nnz == np.count_nonzero(ref) > 0
    assert np.allclose(M.toarray(), ref, rtol=1e-6, atol=0)


def test_the_matchers_take_one_options_object_and_match_samples_dispatches_on_its_type():
    from shapecond.matching.pipeline import match_samples

    _, D = _planar(30, 1)
    Dt, _ = _permuted(D, 2)
    lm = [0, 1, 2, 3]
    a = lh05_match(D, Dt, lm, lm, options=LH05Options(k=6, rounds=1))
    assert np.array_equal(match_samples(D, Dt, lm, lm, LH05Options(k=6, rounds=1)).t, a.t) and a.matcher == "lh05"
    c = faq_match(D, Dt, lm, lm, options=FAQOptions(objective="gaussian", maxiter=5))
    d = match_samples(D, Dt, lm, lm, FAQOptions(objective="gaussian", maxiter=5))
    assert np.array_equal(c.t, d.t) and d.matcher == "faq"
    with pytest.raises(TypeError):  # one call form: a field is not a keyword of the function
        lh05_match(D, Dt, lm, lm, k=6)
    with pytest.raises(InputError):
        lh05_match(D, Dt, lm, lm, options=LH05Options(rounding="nearest"))

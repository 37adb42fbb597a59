"""Landmark-nested matching: more correct landmarks never end below the first three's map."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.spatial.distance import cdist

from shapecond.matching import consistency as C
from shapecond.matching import refine as R
from shapecond.matching.nested import CORE_LANDMARKS, core_size, with_landmarks
from shapecond.matching.seeded import FAQOptions, faq_match
from shapecond.matching.spectral import LH05Options, default_sigma, fine_kernel, lh05_match


def _deformed(n, seed, amp=0.25, noise=0.04):
    """A planar domain and a non-isometric deformation of it (relabelled), with 7 landmarks."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(size=(n, 2)) * [2.0, 1.0]
    p[:, 1] *= 1.0 - 0.35 * p[:, 0]
    q = p + amp * np.stack([np.sin(3 * p[:, 1] + seed), np.cos(2 * p[:, 0] - seed)], 1)
    q += rng.normal(scale=noise, size=q.shape)
    perm = rng.permutation(n)  # target j is source perm[j]
    truth = np.argsort(perm)
    Ds, Dq = cdist(p, p), cdist(q, q)
    ls = rng.choice(n, 7, replace=False)
    return Ds, Dq[np.ix_(perm, perm)], ls, truth[ls]


def _objective(matcher, Ds, Dt):
    if matcher == "lh05":
        kernel = fine_kernel(default_sigma(Ds, 1.0))
        return lambda t: C.objective(Ds, Dt, t, kernel)
    return lambda t: float((Ds * Dt[np.ix_(t, t)]).sum())


_MATCH = {"lh05": lh05_match, "faq": faq_match}
_OPTIONS = {"lh05": LH05Options, "faq": FAQOptions}


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10_000), st.integers(2, 12), st.data())
def test_with_landmarks_sends_landmarks_home_by_swaps(seed, n, data):
    rng = np.random.default_rng(seed)
    m = n + data.draw(st.integers(0, 3))  # target may be larger: injective maps
    t = rng.permutation(m)[:n]
    c = data.draw(st.integers(0, n))
    ls = rng.choice(n, c, replace=False)
    lt = rng.choice(m, c, replace=False)
    given_t = t.copy()
    out = with_landmarks(t, ls, lt)
    assert list(out[ls]) == list(lt)
    assert np.unique(out).size == n  # still injective
    # only landmarks and the samples that held a landmark image change
    changed = set(np.flatnonzero(out != t).tolist())
    assert changed <= set(ls.tolist()) | set(np.flatnonzero(np.isin(t, lt)).tolist())
    assert np.array_equal(with_landmarks(out, ls, lt), out)  # a map that satisfies them is kept
    assert np.array_equal(t, given_t)  # input not modified


def test_core_size():
    assert [core_size(c) for c in range(6)] == [None] * (CORE_LANDMARKS + 1) + [CORE_LANDMARKS] * 2


@pytest.mark.parametrize("matcher, seeds", [("lh05", [3, 7, 12]), ("faq", [14, 22, 26])])
def test_more_landmarks_never_end_below_the_first_three(matcher, seeds):
    """F(match(L)) >= F(with_landmarks(match(L[:3]), L)) (``nested``'s bound), on
    non-isometric instances where the matchers without nesting break it."""
    match = _MATCH[matcher]
    broken_without = 0
    for seed in seeds:
        Ds, Dt, ls, lt = _deformed(60, seed)
        F = _objective(matcher, Ds, Dt)
        core = match(Ds, Dt, ls[:3], lt[:3])
        full = match(Ds, Dt, ls, lt)
        start = with_landmarks(core.t, ls, lt)
        assert F(full.t) >= F(start) - 1e-9 * abs(F(start))
        assert list(full.t[ls]) == list(lt)
        value = full.info["objective"] if matcher == "lh05" else full.info["value"]
        assert value == pytest.approx(F(full.t), rel=1e-12)
        plain = match(Ds, Dt, ls, lt, _OPTIONS[matcher](nested=False))
        broken_without += F(plain.t) < F(start) - 1e-9 * abs(F(start))
        if np.array_equal(start, core.t):  # the first three's map satisfies every landmark
            assert F(full.t) >= F(core.t) - 1e-9 * abs(F(core.t))
    assert broken_without == len(seeds)  # the instances exercise the nesting


@pytest.mark.slow
@settings(max_examples=8, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(["lh05", "faq"]))
def test_nested_bound_on_random_instances(seed, matcher):
    Ds, Dt, ls, lt = _deformed(40, seed, amp=0.2, noise=0.03)
    F = _objective(matcher, Ds, Dt)
    match = _MATCH[matcher]
    start = with_landmarks(match(Ds, Dt, ls[:3], lt[:3]).t, ls, lt)
    assert F(match(Ds, Dt, ls, lt).t) >= F(start) - 1e-9 * abs(F(start))


def test_robust_reassignment_does_not_depend_on_sample_numbering():
    """Anchors from the distances (landmarks + farthest points), not from the first indices:
    a relabelled instance gives the relabelled map (the nested core call sees the samples
    in another order than a direct call with three landmarks)."""
    Ds, Dt, ls, lt = _deformed(90, 5)
    rng = np.random.default_rng(0)
    t = rng.permutation(90)
    t = with_landmarks(t, ls, lt)
    free = np.setdiff1d(np.arange(90), ls)
    out = R.robust_reassignment(Ds, Dt, t, free)
    P = rng.permutation(90)  # new source index i is old P[i]
    Pi = np.argsort(P)
    out2 = R.robust_reassignment(Ds[np.ix_(P, P)], Dt, t[P], Pi[free])
    assert np.array_equal(out2, out[P])
    assert not np.array_equal(out, t)  # the move did something

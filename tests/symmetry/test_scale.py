"""The scale-aware score δ(ε) against enumeration of every map (N <= 8)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.spatial.distance import cdist

from shapecond.selection import LandmarkOptions, monotone, select_landmarks
from shapecond.selection.cnbs import HeatMap, full_heat_map, heat_map
from shapecond.shapes.metric import from_distance_matrix
from shapecond.symmetry import objective as obj
from shapecond.symmetry.scale import budget_of, default_epsilon, resolution, scale_score
from tests.helpers import brute_delta


def _points(n, seed):
    p = np.random.default_rng(seed).uniform(size=(n, 2))
    D = cdist(p, p)
    return D / D.max()


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from([0.5, 1.0, 2.0, 4.0]), st.integers(0, 2))
def test_lower_bound_attained_and_exact_on_small_instances(seed, factor, n_landmarks):
    D = _points(7, seed)
    eps = factor * default_epsilon(D)
    lm = list(range(n_landmarks))
    s = scale_score(D, landmarks=lm, epsilon=eps, seed=seed)
    # the witness is feasible and attains the reported value
    assert math.sqrt(obj.d2(D, s.witness) / 7) == pytest.approx(s.displacement, abs=1e-12)
    assert s.distortion <= eps * (1 + 1e-9)
    assert all(s.witness[lm] == lm)
    exact = brute_delta(D, eps, lm)
    assert s.displacement <= exact + 1e-12
    assert s.displacement == pytest.approx(exact, rel=1e-9, abs=1e-12)  # the search finds the optimum here



@settings(max_examples=12, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from([0.5, 1.0, 2.0, 4.0]), st.integers(1, 2))
def test_warm_search_with_one_more_landmark_is_a_feasible_lower_bound(seed, factor, n_landmarks):
    """The next-landmark suggestion's search: continued from the maps of the search before it,
    one more sample fixed, without the structured starts of a fresh search."""
    D = _points(7, seed)
    eps = factor * default_epsilon(D)
    before = scale_score(D, landmarks=list(range(n_landmarks)), epsilon=eps, seed=seed)
    lm = list(range(n_landmarks + 1))
    s = scale_score(D, landmarks=lm, epsilon=eps, seed=seed, effort="warm", starts=before.maps)
    assert math.sqrt(obj.d2(D, s.witness) / 7) == pytest.approx(s.displacement, abs=1e-12)
    assert s.distortion <= eps * (1 + 1e-9)
    assert all(s.witness[lm] == lm)
    exact = brute_delta(D, eps, lm)
    assert s.displacement <= exact + 1e-12
    assert s.displacement == pytest.approx(exact, rel=1e-9, abs=1e-12)

@pytest.mark.slow
@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000))
def test_monotone_in_epsilon_and_in_landmarks(seed):
    D = _points(7, seed)
    h = default_epsilon(D)
    values = [brute_delta(D, f * h, [0]) for f in (0.5, 1, 2, 4)]
    assert values == sorted(values)
    nested = [brute_delta(D, 2 * h, list(range(k))) for k in range(4)]
    assert nested == sorted(nested, reverse=True)
    est = [scale_score(D, landmarks=list(range(k)), epsilon=2 * h).displacement for k in range(4)]
    assert all(e <= v + 1e-12 for e, v in zip(est, nested))
    assert monotone(est) == sorted(monotone(est), reverse=True)


def test_exact_symmetry_gives_its_full_displacement():
    """A regular hexagon plus its centre: the rotation by 60° is an isometry."""
    ang = np.arange(6) * np.pi / 3
    p = np.vstack([np.column_stack([np.cos(ang), np.sin(ang)]), [[0.0, 0.0]]])
    D = cdist(p, p) / 2.0
    rot = np.array([1, 2, 3, 4, 5, 0, 6])
    best_iso = max(math.sqrt(obj.d2(D, t) / 7) for t in (rot, rot[rot], rot[rot[rot]]))
    for eps in (0.0, 0.01, 0.1):
        s = scale_score(D, epsilon=eps)
        assert s.displacement >= best_iso - 1e-12
        assert s.displacement == pytest.approx(brute_delta(D, eps), abs=1e-12)
    assert scale_score(D, epsilon=0.0).isometry
    # the centre is on every symmetry: fixing it changes nothing; fixing a vertex kills the rotations
    assert scale_score(D, landmarks=[6], epsilon=0.0).displacement == pytest.approx(best_iso, abs=1e-12)
    assert scale_score(_points(7, 1), epsilon=0.0).displacement == 0.0


def test_heat_map_with_a_budget_bounds_the_full_searches():
    D = _points(8, 3)
    budget = budget_of(2 * default_epsilon(D), 8)
    hm = heat_map(D, 8, [0], budget=budget)
    full = full_heat_map(D, 8, [0], budget=budget)
    free = np.arange(1, 8)
    # every value is sqrt(d²) of a feasible map: at most the exact optimum with p fixed
    for p in free:
        exact = brute_delta(D, 2 * default_epsilon(D), [0, p]) * math.sqrt(8)
        assert hm.values[p] <= exact + 1e-9 and full[p] <= exact + 1e-9
    # the choice is within the resolution of δ of the best full search, and the farthest
    # from the landmark among the heat map's candidates that close to its smallest value
    c = hm.argmin()
    assert hm.tie == pytest.approx(math.sqrt(8) * resolution(D, 8)) and hm.tie > 0
    assert hm.values[c] <= np.nanmin(full) + hm.tie + 1e-9
    tied = free[hm.values[free] <= np.nanmin(hm.values) + hm.tie]
    assert D[c, 0] == D[tied, 0].max()


def test_near_ties_of_the_scale_heat_map_go_to_the_farthest_candidate():
    values = np.array([np.nan, 1.00, 1.04, 1.20, 1.02])
    spread = np.array([0.0, 0.1, 0.5, 0.9, 0.3])
    hm = HeatMap(values, 2.0, (0,), np.zeros(5), np.zeros(5, bool), tie=0.05, spread=spread)
    assert hm.argmin() == 2  # 3 is farther but not within the tie; 1 is smallest but nearest
    exact = HeatMap(values, 2.0, (0,), np.zeros(5), np.zeros(5, bool))
    assert exact.argmin() == 1  # the paper's σ: no tolerance


def test_cnbs_scale_landmarks_have_non_increasing_scores():
    D = _points(9, 5)
    shape = from_distance_matrix(D)
    res = select_landmarks(shape, 4, "cnbs-scale")
    assert res.score == "scale" and len(res.landmarks) == 4
    assert list(res.scores) == sorted(res.scores, reverse=True)
    assert res.initial_score >= res.scores[0]
    base = select_landmarks(shape, 4, "fps", options=LandmarkOptions(scores=True, score="scale"))
    assert base.score == "scale" and list(base.scores) == sorted(base.scores, reverse=True)


def test_scale_score_repr_is_short():
    D = cdist(*(2 * [np.random.default_rng(2).normal(size=(30, 3))]))
    r = repr(scale_score(D / D.max(), effort="quick"))
    assert len(r) < 300 and "array(" not in r and "N=30" in r

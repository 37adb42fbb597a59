"""The error bar's bound against enumeration: a map found by minimising distortion errs by at most δ(ε̂ + ε)."""

import itertools
import math

import numpy as np
import pytest
from scipy.spatial.distance import cdist

from shapecond.errors import InputError
from shapecond.matching import error_bar as eb
from shapecond.matching.error_bar import (bar_and_samples, bar_surface, error_bar, map_distortion,
                                         sample_map_bar)
from shapecond.matching.sampled import sample_surface
from shapecond.shapes.synthetic import bumpy_blob
from shapecond.symmetry import objective as obj
from shapecond.symmetry.scale import resolution, scale_score
from tests.helpers import brute_delta


def _levels(Ds, Dt, t, lm):
    """(global RMS distortion sqrt(Σ (Ds − Dt∘t)²)/N, largest landmark-row RMS) of the map t: X -> X̃."""
    n = Ds.shape[0]
    diff = Ds - Dt[np.ix_(t, t)]
    rows = [math.sqrt(np.sum(diff[l] ** 2) / n) for l in lm]
    return math.sqrt(np.sum(diff ** 2)) / n, max(rows, default=0.0)


@pytest.mark.parametrize("seed", range(12))
def test_the_distortion_minimiser_errs_by_at_most_delta_of_its_level_plus_the_truths(seed):
    rng = np.random.default_rng(seed)
    n, lm = 7, [0, 1]
    p = rng.uniform(size=(n, 2))
    Ds = cdist(p, p)
    q = p + rng.normal(scale=0.04, size=p.shape)       # the deformed shape: the truth is the identity
    Dt = cdist(q, q)
    best, found = math.inf, None
    for perm in itertools.permutations(range(2, n)):  # the matcher: least distortion, landmarks fixed
        t = np.array([0, 1, *perm])
        g, r = _levels(Ds, Dt, t, lm)
        if max(g, r) < best:
            best, found = max(g, r), t
    truth = max(_levels(Ds, Dt, np.arange(n), lm))
    assert best <= truth + 1e-12                      # ε̂ reads the truth's level from below
    error = math.sqrt(obj.d2(Ds, found) / n)           # RMS displacement of the found map from the truth
    assert error <= brute_delta(Ds, best + truth, lm) + 1e-12  # the triangle bound the bar rests on


def test_map_distortion_is_zero_for_the_identity_and_grows_with_a_deformation():
    g = bumpy_blob(subdivisions=3)
    src = sample_surface(g, 40, cache=False)
    assert map_distortion(src, g, src.samples) == pytest.approx(0.0, abs=1e-6)
    shuffled = src.samples[np.r_[1, 0, 2:40]]          # two samples swapped: a distorting map
    assert map_distortion(src, g, shuffled) > 1e-3


def test_error_bar_is_delta_at_the_maps_own_level_with_its_witness():
    g = bumpy_blob(subdivisions=3)
    src = sample_surface(g, 40, landmarks=[5, 60, 200], cache=False)
    bar = error_bar(src, 3, 0.05, seed=0)                  # about a third of the sample spacing (sqrt(area) units)
    assert bar.epsilon == pytest.approx(0.05)          # the level the sentence states: the map's own distortion
    ref = scale_score(src.D, 40, [0, 1, 2], 0.05, seed=0, effort="quick")
    assert bar.delta == pytest.approx(ref.displacement) and bar.delta > 0
    assert bar.delta_diameter == pytest.approx(bar.delta / src.D.max())
    assert bar.doubt.shape == (40,) and np.all(bar.doubt[:3] == 0)   # the landmarks do not move
    assert np.sqrt(np.mean(bar.doubt ** 2)) == pytest.approx(bar.delta)  # δ is the RMS of the doubt field
    assert bar.bar == pytest.approx(max(np.mean(bar.doubt), bar.resolution))  # its mean, never below h / 2
    assert bar.resolution == pytest.approx(resolution(src.D)) and 0 < bar.bar
    assert bar.bar_diameter == pytest.approx(bar.bar / src.D.max()) and bar.n_samples == 40
    assert "%.3g" % bar.bar in bar.sentence() and bar.to_dict()["bar"] == bar.bar
    assert set(bar.doubt_ids) <= set(g.ids[src.samples].tolist())
    with pytest.raises(InputError):
        error_bar(src, 3, float("nan"))


def test_the_right_map_of_a_shape_onto_itself_has_no_distortion_and_a_bar_at_delta_zero():
    g = bumpy_blob(subdivisions=3)
    src = sample_surface(g, 40, landmarks=[5, 60, 200], cache=False)
    bar, coarse, _ = bar_and_samples(src, g, np.arange(g.n_vertices), 3)
    field = bar.doubt[coarse.nearest]
    assert bar.epsilon_hat == pytest.approx(0.0, abs=1e-6)
    assert bar.delta == pytest.approx(scale_score(src.D, 40, [0, 1, 2], 0.0, effort="quick").displacement, abs=1e-9)
    assert field.shape == (g.n_vertices,) and not field.any()  # no doubt at any vertex
    worse, _, _ = bar_and_samples(src, g, np.roll(np.arange(g.n_vertices), 7), 3)   # a scrambled map
    assert worse.epsilon_hat > bar.epsilon_hat and worse.delta >= bar.delta


def test_the_bar_uses_the_first_samples_with_every_landmark_and_its_field_reaches_every_vertex(monkeypatch):
    g = bumpy_blob(subdivisions=3)
    src = sample_surface(g, 40, landmarks=[5, 60, 200], cache=False)
    monkeypatch.setattr(eb, "BAR_SAMPLES", 12)
    coarse = bar_surface(src, 3)
    assert np.array_equal(coarse.samples, src.samples[:12]) and np.array_equal(coarse.rows, src.rows[:12])
    assert bar_surface(src, 30).n_samples == 30             # never fewer samples than landmarks
    bar, used, _ = bar_and_samples(src, g, np.roll(np.arange(g.n_vertices), 7), 3)
    assert bar.n_samples == 12 and bar.doubt.shape == (12,) and np.array_equal(used.samples, coarse.samples)
    assert bar.epsilon_hat == pytest.approx(map_distortion(coarse, g, np.roll(np.arange(g.n_vertices), 7)[coarse.samples]))


def test_a_sample_map_bar_reads_the_distortion_of_its_own_samples():
    g = bumpy_blob(subdivisions=3)
    src = sample_surface(g, 40, landmarks=[5, 60, 200], cache=False)
    right = sample_map_bar(src, src, np.arange(40), 3)
    assert right.epsilon_hat == pytest.approx(0.0, abs=1e-9)
    swapped = sample_map_bar(src, src, np.r_[0, 1, 2, 4, 3, 5:40], 3)
    assert swapped.epsilon_hat == pytest.approx(eb.rms_distortion(src.D, src.D[np.ix_(np.r_[0, 1, 2, 4, 3, 5:40],
                                                                                   np.r_[0, 1, 2, 4, 3, 5:40])]))
    assert swapped.epsilon_hat > 0 and swapped.delta >= right.delta


@pytest.mark.parametrize("seed", range(6))
def test_the_self_map_between_found_and_true_map_distorts_by_the_difference_of_their_distortions(seed):
    """The identity the level rests on (module docstring): S = T⁻¹∘T̂ has Ds − Ds[S, S] = E_T[S, S] − E_T̂,
    so its distortion is ‖E_T∘S − E_T̂‖ (≤ ε + ε̂, and small when the two maps share their distortion)."""
    rng = np.random.default_rng(seed)
    n = 9
    p = rng.uniform(size=(n, 2))
    Ds = cdist(p, p)
    q = p + rng.normal(scale=0.05, size=p.shape)
    T, That = rng.permutation(n), rng.permutation(n)       # a "true" map and a "found" one, X -> X̃
    Dt = cdist(q[np.argsort(T)], q[np.argsort(T)])         # any target metric
    S = np.argsort(T)[That]                                 # S = T⁻¹∘T̂
    E_T, E_hat = Dt[np.ix_(T, T)] - Ds, Dt[np.ix_(That, That)] - Ds
    lhs = np.linalg.norm(Ds - Ds[np.ix_(S, S)])
    assert lhs == pytest.approx(np.linalg.norm(E_T[np.ix_(S, S)] - E_hat), abs=1e-12)
    assert lhs <= np.linalg.norm(E_T) + np.linalg.norm(E_hat) + 1e-12


def test_off_isometry_the_level_is_at_least_the_landmarks_own_distortion():
    g = bumpy_blob(subdivisions=3)
    src = sample_surface(g, 40, landmarks=[5, 60, 200], cache=False)
    stretched = src.D.copy()
    stretched[0, 1] = stretched[1, 0] = src.D[0, 1] * 1.5      # the target's landmarks 0 and 1 farther apart
    eps_l = eb.landmark_distortion(src.D, stretched, 3)
    assert eps_l == pytest.approx(np.sqrt(2 * (0.5 * src.D[0, 1]) ** 2 / 6))   # RMS over the 6 ordered pairs
    assert eb.landmark_distortion(src.D, stretched, 1) == 0.0 and eb.landmark_distortion(src.D, src.D, 3) == 0.0
    low = error_bar(src, 3, 0.01, seed=0)
    high = error_bar(src, 3, 0.01, seed=0, epsilon_landmarks=eps_l)
    assert low.epsilon == pytest.approx(0.01) and high.epsilon == pytest.approx(max(0.01, eps_l))
    assert high.delta >= low.delta and "landmarks themselves" in high.sentence()
    assert high.to_dict()["epsilon_source"] == "the landmarks' own distortion"
    with pytest.raises(InputError):
        error_bar(src, 3, 0.01, epsilon_landmarks=float("inf"))

"""Score bracket (σ lower/upper/exact, σ̂, κ bracket of Theorem 4.1) and the animal checks."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from shapecond.symmetry import objective as obj
from shapecond.symmetry.resolution import classify
from shapecond.symmetry.score import ScoreOptions, symmetry_score
from shapecond.symmetry.search import best_single_swap, witness_search

from tests.helpers import mixed_instances, near_symmetric_instance, random_instance


def test_bracket_contains_exact_and_kappa_follows_theorem_4_1():
    for k, D in enumerate(mixed_instances(seed=21, count=12, n=7)):
        sc = symmetry_score(D, options=ScoreOptions(exact=False, upper=True, seed=k))
        ex = symmetry_score(D, options=ScoreOptions(exact=True, seed=k))
        assert ex.sigma_exact is not None and ex.sigma_lower == ex.sigma_upper == ex.sigma_exact
        assert sc.sigma_lower <= ex.sigma_exact * (1 + 1e-9) <= sc.sigma_upper * (1 + 2e-9)
        assert sc.kappa_lower == sc.sigma_lower and sc.kappa_upper == 2 * sc.sigma_upper + 1
        assert math.isclose(sc.sigma_hat_lower, sc.sigma_lower * math.sqrt(7))
        assert math.isclose(obj.map_score(D, ex.witness), ex.sigma_exact, rel_tol=1e-9)


def test_auto_exact_only_for_small_instances_and_lower_above_swap():
    rng = np.random.default_rng(3)
    small = symmetry_score(random_instance(rng, 8, 2))
    assert small.upper_method == "exact"
    big = symmetry_score(random_instance(rng, 25, 3))
    assert big.sigma_exact is None and big.sigma_upper == math.inf and big.kappa_upper == math.inf
    assert big.sigma_lower >= big.swap_floor * (1 - 1e-12)


def test_upper_refused_above_lp_limit_gives_inf_and_a_note():
    sc = symmetry_score(random_instance(np.random.default_rng(4), 30, 2), options=ScoreOptions(upper=True))
    assert sc.sigma_upper == math.inf and sc.upper_method == "none"
    assert any("upper bound" in n for n in sc.notes)


def test_isometry_gives_inf_everywhere_and_valid_json():
    sc = symmetry_score(near_symmetric_instance(np.random.default_rng(6), 14, 3, 0.0))
    assert sc.sigma_lower == sc.sigma_upper == sc.sigma_exact == math.inf
    assert sc.kappa_upper == math.inf and sc.upper_method == "isometry"
    from shapecond.jsonable import jsonable

    text = json.dumps(jsonable(sc.to_dict()), allow_nan=False)
    d = json.loads(text)
    assert d["sigma"]["lower"] == "inf" and d["kappa"]["upper"] == "inf"
    assert set(d) >= {"n_points", "landmarks", "sigma", "sigma_hat", "kappa", "witness", "seconds"}


def test_landmarks_lower_the_score():
    D = near_symmetric_instance(np.random.default_rng(8), 8, 2, 0.02)
    free = symmetry_score(D)
    fixed = symmetry_score(D, landmarks=(0, 3))
    assert fixed.sigma_exact <= free.sigma_exact * (1 + 1e-12)
    assert fixed.witness[0] == 0 and fixed.witness[3] == 3


@pytest.mark.parametrize("lo, hi, rms, disp, r, flag", [
    (math.inf, math.inf, 0.0, 0.1, 0.01, "symmetric"),
    (1.0, 1.05, 0.05, 0.1, 0.01, "converged"),
    (1.0, 1.5, 0.005, 0.1, 0.01, "symmetric within resolution"),
    (1.0, 1.5, 0.005, 0.002, 0.01, "undecided"),  # a local map: moves samples by less than 3 r
    (1.0, 1.5, 0.05, 0.1, 0.01, "undecided"),
    (1.0, 0.5, 0.005, 0.1, 0.01, "undecided"),
])
def test_resolution_rule(lo, hi, rms, disp, r, flag):
    assert classify(lo, hi, rms, r, disp) == flag


def _animal_shape(delta, n):
    from shapecond.shapes.metric import Sampling, build_metric_shape
    from shapecond.shapes.synthetic import animal

    return build_metric_shape(animal(delta=delta), n_points=n, sampling=Sampling(target="samples"))


def _mirror_map(shape):
    """The animal's symmetry restricted to the samples (sampling is symmetry-consistent)."""
    where = {int(v): i for i, v in enumerate(shape.samples)}
    return np.array([where[int(shape.geometry.symmetry[v])] for v in shape.samples[: shape.n_points]])


@pytest.mark.parametrize("delta", [0.0, 0.02, 0.05])
def test_animal_n100_mirror_is_the_witness(delta):
    """The animal at N = 100: σ = inf at delta = 0 with the mirror as witness; the mirror is still the
    witness for delta <= 0.05."""
    shape = _animal_shape(delta, 100)
    mirror = _mirror_map(shape)
    res = witness_search(shape.D, seed=0)
    assert res.sigma >= best_single_swap(shape.D)[0]
    if delta == 0.0:
        assert res.sigma == math.inf
        assert obj.is_isometry(shape.D, obj.dist2(shape.D, res.witness))
    else:
        assert math.isfinite(res.sigma)
    assert np.array_equal(res.witness, mirror)


def test_one_call_form_and_the_repr_is_short():
    """The options come as one ``ScoreOptions``: a field given as a keyword is refused."""
    D = random_instance(np.random.default_rng(7), 40, 3)
    a = symmetry_score(D, options=ScoreOptions(exact=False, seed=3, effort="quick"))
    assert len(repr(a)) < 300 and "array(" not in repr(a) and "N=40" in repr(a)
    with pytest.raises(TypeError):
        symmetry_score(D, exact=False)


def _spread_points(n: int) -> np.ndarray:
    """Distances of ``n`` random points of an ellipsoidal cloud: no isometry, a slow full search."""
    from scipy.spatial.distance import cdist

    x = np.random.default_rng(5).normal(size=(n, 3)) * [3.0, 2.0, 1.0]
    return cdist(x, x)


def test_time_limit_bounds_the_whole_score_and_says_it_cut_the_search():
    """`score -n 400 --exact --time-limit 5` took 29 s: the limit bounded only the exact and LP
    solves, not the witness search, δ(ε)'s search or the O(N³) spectral starts (8 s at N = 600
    with limit 2 before)."""
    import time

    import shapecond as sc

    D = _spread_points(600)
    sc.score(D[:12, :12], cache=False)  # loads the compiled kernels: not what is timed
    t0 = time.perf_counter()
    result = sc.score(D, exact=True, time_limit=2.0, cache=False)
    seconds = time.perf_counter() - t0
    out = result.to_dict()
    assert seconds < 1.5 * 2.0 + 0.5, seconds
    assert out["time_limited"] is True and any(n.startswith("time limit reached:") for n in out["notes"])
    assert out["sigma"]["lower"] >= out["swap_floor"] * (1 - 1e-12)  # still a certified lower bound


def test_exact_solve_stopped_by_the_limit_reports_no_exact_value():
    sc = symmetry_score(_spread_points(40), options=ScoreOptions(exact=True, time_limit=0.5))
    assert sc.sigma_exact is None and sc.sigma_upper == math.inf and sc.time_limited
    assert any(n.startswith("time limit reached: the exact solver") for n in sc.notes)
    d = sc.to_dict()
    assert d["sigma"]["exact"] is None and d["time_limited"] is True


def test_without_a_time_limit_nothing_is_cut():
    sc = symmetry_score(_spread_points(30), options=ScoreOptions(exact=False))
    assert not sc.time_limited and sc.to_dict()["time_limited"] is False

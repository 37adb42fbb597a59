"""κ probes (Eq. 4) obey Theorem 4.1, and the construction of its proof reaches σ."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shapecond.errors import InputError, TooLargeError
from shapecond.symmetry import objective
from shapecond.symmetry.condition import (MAX_PROBE_POINTS, kappa_bracket, kappa_probes,
                                          optimal_matching, probe_ratio)
from shapecond.symmetry.exact import enumerate_maps
from tests.helpers import near_symmetric_instance, random_instance


def test_kappa_bracket():
    assert kappa_bracket(1.5, 2.0) == (1.5, 5.0)
    assert kappa_bracket(1.5, None) == (1.5, math.inf)
    assert kappa_bracket(None, math.inf) == (0.0, math.inf)


def test_optimal_matching_is_the_brute_force_minimiser():
    rng = np.random.default_rng(1)
    D = random_instance(rng, 6, 2)
    Dt = D + 0.3 * np.triu(rng.standard_normal((6, 6)), 1)
    Dt = np.maximum(Dt + Dt.T - np.diag(np.diag(Dt)) * 2, 0)
    np.fill_diagonal(Dt, 0)
    t = optimal_matching(D, Dt, [1])
    cost = lambda u: float(np.sum((D - Dt[np.ix_(u, u)]) ** 2))  # noqa: E731
    assert t[1] == 1
    assert cost(t) <= min(cost(u) for u in enumerate_maps(6, 6, [1])) + 1e-12


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(n=st.integers(4, 7), seed=st.integers(0, 10**6), sym=st.booleans(), n_land=st.integers(0, 1),
       noise=st.sampled_from([0.02, 0.1, 0.3]))
def test_probes_obey_theorem_4_1(n, seed, sym, n_land, noise):
    rng = np.random.default_rng(seed)
    D = near_symmetric_instance(rng, n, 2, noise) if sym else random_instance(rng, n, 2)
    L = [0] if n_land else []
    p = kappa_probes(D, trials=8, seed=seed, landmarks=L)
    sigma = p.sigma
    assert math.isfinite(sigma)
    assert sigma <= p.kappa_probe_max * (1 + 1e-9)  # the construction reaches σ
    for r in p.ratios:
        assert r <= 2 * sigma + 1 + 1e-9
        assert r <= 2 * sigma * (1 + 1e-9)  # the sharper bound of the module docstring
    assert p.kinds[0] == "witness" and p.ratios[0] == pytest.approx(sigma, rel=1e-9)


def test_witness_blends_probe_between_sigma_and_two_sigma():
    """Blends towards the witness give σ/λ ∈ (σ, 2σ) when T_opt is the witness (it is here)."""
    rng = np.random.default_rng(4)
    D = near_symmetric_instance(rng, 6, 2, 0.05)
    p = kappa_probes(D, trials=10, seed=2)
    blends = [r for kind, r in zip(p.kinds, p.ratios) if kind == "witness-blend"]
    assert blends and all(r <= 2 * p.sigma * (1 + 1e-9) for r in blends)
    assert max(blends) > p.sigma * (1 + 1e-6)


def test_probe_of_an_unperturbed_shape_is_undefined():
    D = random_instance(np.random.default_rng(0), 5, 2)
    assert probe_ratio(D, D.copy()) is None


def test_limits_and_bad_input():
    D = random_instance(np.random.default_rng(0), MAX_PROBE_POINTS + 1, 2)
    with pytest.raises(TooLargeError, match="free samples"):
        kappa_probes(D, trials=2)
    p = kappa_probes(D, trials=2, landmarks=[0])  # one landmark brings it within the limit
    assert len(p.ratios) == 2
    with pytest.raises(InputError, match="trials"):
        kappa_probes(D[:5, :5], trials=0)


def test_isometry_has_infinite_sigma_and_kappa():
    D = near_symmetric_instance(np.random.default_rng(3), 6, 2, 0.0)
    p = kappa_probes(D, trials=4)
    assert p.sigma == math.inf and p.kappa == (math.inf, math.inf)
    assert "witness" not in p.kinds
    assert objective.is_isometry(D, objective.dist2(D, p.witness))

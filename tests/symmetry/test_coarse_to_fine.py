"""The dense search in two levels (first M/2 targets, then all M) and its reuse by the resolution report."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shapecond.symmetry import objective as obj
from shapecond.symmetry import resolution
from shapecond.symmetry.resolution import coarse_to_fine, refine, resolution_report
from shapecond.symmetry.scale import budget_of, default_epsilon
from shapecond.symmetry.score import ScoreOptions, symmetry_score
from shapecond.symmetry.search import witness_search

from tests.helpers import brute_sigma, dense_instance, same


def test_two_levels_against_injective_enumeration():
    """Each level is a certified lower bound of its own exact σ; the fine one is at least the coarse one."""
    rng = np.random.default_rng(21)
    for k in range(12):
        n, m = 5, 12
        D = dense_instance(rng, n, m, 2 + k % 2, noise=None if k % 4 < 2 else 0.05)
        fine, coarse = coarse_to_fine(D, n, seed=k)
        assert coarse.witness.max() < m // 2 and len(set(fine.witness.tolist())) == n
        assert coarse.sigma <= brute_sigma(D[: m // 2, : m // 2], n)[0] * (1 + 1e-9)
        exact = brute_sigma(D, n)[0]
        assert coarse.sigma * (1 - 1e-12) <= fine.sigma <= exact * (1 + 1e-9)
        assert same(obj.map_score(D, fine.witness), fine.sigma)
        assert list(fine.sigmas) == sorted(fine.sigmas, reverse=True)


def test_refine_within_a_budget_keeps_every_map_feasible():
    rng = np.random.default_rng(4)
    n, m = 12, 48
    D = dense_instance(rng, n, m, 2, noise=0.02)
    budget = budget_of(2 * default_epsilon(D, n), n, D)
    coarse = witness_search(D[: m // 2, : m // 2], n, budget=budget)
    fine = refine(D, n, (), [coarse.witness, *coarse.maps], budget=budget)
    for t in fine.maps:
        assert obj.dist2(D, t) <= budget * (1 + 1e-9)
    assert same(fine.sigma, math.sqrt(obj.d2(D, fine.witness)))
    assert fine.sigma >= coarse.sigma * (1 - 1e-12)  # the coarse maps are feasible over Y too


def test_two_levels_only_for_large_dense_searches():
    assert resolution.two_levels(400, 3200)  # the CLI's default on a mesh
    assert not resolution.two_levels(400, 800)  # the lower level would be the bijections
    assert not resolution.two_levels(20, 160)  # a full search takes milliseconds


def test_symmetry_score_keeps_the_coarse_level_for_the_report(monkeypatch):
    """The report judges the score's own two levels: no witness search is run again."""
    monkeypatch.setattr(resolution, "TWO_LEVEL_SECONDS", 0.0)
    rng = np.random.default_rng(8)
    n, m = 10, 40
    D = dense_instance(rng, n, m, 2, noise=0.03)
    sc = symmetry_score(D, n, options=ScoreOptions(exact=False))
    assert sc.coarse is not None and sc.coarse.witness.max() < m // 2
    assert sc.sigma_lower >= sc.coarse.sigma * (1 - 1e-12)

    def no_search(*a, **k):
        raise AssertionError("the resolution report searched again")

    monkeypatch.setattr(resolution, "witness_search", no_search)
    monkeypatch.setattr(resolution, "coarse_to_fine", no_search)
    rep = resolution_report(D, n, 0.05, score_hi=sc)
    assert rep.n_targets_lo == m // 2 and rep.n_targets_hi == m
    assert rep.sigma_lo <= sc.coarse.sigma * (1 + 1e-12) and rep.sigma_hi <= sc.sigma_lower * (1 + 1e-12)


@pytest.mark.parametrize("m", [10, 11])
def test_too_few_targets_for_two_levels_searches_once(m, monkeypatch):
    """M <= 2N + 1: the lower level would be the bijections; one full search as before."""
    monkeypatch.setattr(resolution, "TWO_LEVEL_SECONDS", 0.0)
    D = dense_instance(np.random.default_rng(m), 5, m, 2)
    sc = symmetry_score(D, 5, options=ScoreOptions(exact=False))
    assert sc.coarse is None
    assert same(sc.sigma_lower, witness_search(D, 5).sigma)


def test_score_report_in_two_levels_keeps_delta_within_its_budget(monkeypatch):
    """δ(ε) searched over the first M/2 targets and refined over M: a feasible witness, at least the coarse δ."""
    from shapecond.api import metric_shape
    from shapecond.symmetry import report
    from shapecond.symmetry.scale import scale_score

    monkeypatch.setattr(resolution, "TWO_LEVEL_SECONDS", 0.0)
    shape = metric_shape("demo:animal", n_points=16, target="dense", cache=False)
    m = shape.D.shape[0]
    r = report.score_report(shape)
    assert r.score.coarse is not None and r.resolution.n_targets_lo == m // 2
    d = r.scale
    assert d.distortion <= d.epsilon * (1 + 1e-9)
    assert same(d.displacement, math.sqrt(obj.d2(shape.D, d.witness) / 16))
    sc = r.score
    starts = [sc.coarse.witness, *sc.coarse.maps] + [t for t in (sc.witness, *sc.maps) if t.max() < m // 2]
    coarse = scale_score(shape.D[: m // 2, : m // 2], 16, starts=starts)  # the lower level δ was refined from
    assert d.displacement >= coarse.displacement * (1 - 1e-12) or d.isometry

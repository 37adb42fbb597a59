"""Resolution report on small dense instances."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shapecond.symmetry import objective as obj
from shapecond.symmetry import resolution
from shapecond.symmetry.resolution import resolution_report
from shapecond.symmetry.search import witness_search

from tests.helpers import dense_instance


def test_exact_symmetry_among_targets_is_symmetric():
    rng = np.random.default_rng(0)
    # mirror pairs everywhere: the targets of the first half contain the samples' mirrors
    P = rng.standard_normal((20, 2))
    P[:, 0] = np.abs(P[:, 0]) + 0.1
    Q = np.concatenate([P, P * [-1, 1]])  # Q[i + 20] mirrors Q[i]
    order = np.r_[np.arange(0, 10), np.arange(20, 30), np.arange(10, 20), np.arange(30, 40)]
    Q = Q[order]  # the first 20 points (samples) are closed under the mirror
    D = np.sqrt(((Q[:, None] - Q[None]) ** 2).sum(-1))
    D /= D.max()
    rep = resolution_report(D, 20, covering_radius=0.05)
    assert rep.flag == "symmetric" and rep.sigma_hi == math.inf


def _judged(D, n, maps, covering_radius):
    """(score, RMS distortion, RMS displacement) of the map the report judges among ``maps``: the best
    one moving the samples by at least DISPLACEMENT_FACTOR covering radii (RMS), else the best."""
    rows = [(obj.map_score(D, t), math.sqrt(obj.dist2(D, t)) / n, math.sqrt(obj.d2(D, t) / n)) for t in maps]
    return max([r for r in rows if r[2] >= resolution.DISPLACEMENT_FACTOR * covering_radius] or rows)


def test_report_is_consistent_on_random_dense_instance(monkeypatch):
    D = dense_instance(np.random.default_rng(3), 8, 32, 2)
    searches = {}  # the report's own searches, by target count

    def recorded(D, *args, **kw):
        searches[D.shape[0]] = witness_search(D, *args, **kw)
        return searches[D.shape[0]]

    monkeypatch.setattr(resolution, "witness_search", recorded)
    r = 0.183  # here the search's best map over all 32 targets moves the samples by less than 3 r (RMS)
    rep = resolution_report(D, 8, covering_radius=r, effort="quick")
    assert rep.n_targets_lo == 16 and rep.n_targets_hi == 32 and set(searches) == {16, 32}
    maps_lo = [searches[16].witness, *searches[16].maps]
    maps_hi = [searches[32].witness, *searches[32].maps]
    # over all targets the maps found over the first half count too (a map over Y_lo is a map over Y)
    assert (rep.sigma_hi, rep.distortion_rms, rep.displacement_rms) == pytest.approx(
        _judged(D, 8, maps_hi + maps_lo, r), rel=1e-12)
    assert rep.sigma_lo == pytest.approx(_judged(D[:16, :16], 8, maps_lo, r)[0], rel=1e-12)
    assert rep.sigma_hi >= rep.sigma_lo  # more targets: the dense score cannot fall
    assert rep.relative_change == pytest.approx((rep.sigma_hi - rep.sigma_lo) / rep.sigma_lo, rel=1e-12)
    assert rep.flag == resolution.classify(rep.sigma_lo, rep.sigma_hi, rep.distortion_rms, r, rep.displacement_rms)

"""Resolution report on small dense instances."""

from __future__ import annotations

import math

import numpy as np

from shapecond.symmetry import objective as obj
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


def test_report_is_consistent_on_random_dense_instance():
    D = dense_instance(np.random.default_rng(3), 8, 32, 2)
    rep = resolution_report(D, 8, covering_radius=0.1, effort="quick")
    assert rep.n_targets_lo == 16 and rep.n_targets_hi == 32
    assert rep.sigma_hi >= rep.sigma_lo  # more targets: the dense score cannot fall
    assert rep.flag in {"converged", "symmetric within resolution", "undecided"}
    best = witness_search(D, 8, effort="quick")
    assert rep.sigma_hi >= best.sigma * (1 - 1e-9) or math.isclose(rep.sigma_hi, best.sigma, rel_tol=1e-9)
    assert rep.distortion_rms >= 0 and math.isfinite(rep.relative_change)
    assert obj.dist2(D, best.witness) >= 0

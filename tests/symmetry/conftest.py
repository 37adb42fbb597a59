"""Shared instance generators for the symmetry tests (DESIGN.md section 3).

Plain functions (importable by other test modules with
``from tests.symmetry.conftest import random_instance`` or through the
fixtures below), all deterministic given a ``numpy.random.Generator``:

- ``random_instance(rng, n, dim)``: Euclidean distances of ``n`` uniform
  points in the unit ``dim``-cube.
- ``near_symmetric_instance(rng, n, dim, noise)``: a mirror-symmetric point
  set (pairs reflected through the plane ``x_0 = 0``, one point on the plane
  when ``n`` is odd) plus Gaussian noise of standard deviation ``noise``.
  ``noise = 0`` gives an exact isometry (σ = ∞).
- ``dense_instance(rng, n, m, dim, noise=None)``: an (m, m) matrix whose first
  ``n`` points are the samples (issue 4's dense targets); near-symmetric when
  ``noise`` is given.

Every matrix is symmetric, has a zero diagonal and is scaled to max 1.
"""

from __future__ import annotations

import numpy as np
import pytest


def _distance_matrix(P: np.ndarray) -> np.ndarray:
    D = np.sqrt(np.sum((P[:, None, :] - P[None, :, :]) ** 2, axis=-1))
    D = 0.5 * (D + D.T)
    np.fill_diagonal(D, 0.0)
    return D / D.max()


def random_points(rng: np.random.Generator, n: int, dim: int) -> np.ndarray:
    """``n`` uniform points in the unit ``dim``-cube, shape (n, dim)."""
    return rng.random((n, dim))


def near_symmetric_points(rng: np.random.Generator, n: int, dim: int, noise: float) -> np.ndarray:
    """Mirror pairs (x, R x) with R = reflection of coordinate 0, plus noise; shape (n, dim)."""
    half = rng.standard_normal((n // 2, dim))
    half[:, 0] = np.abs(half[:, 0]) + 0.2
    mirror = half.copy()
    mirror[:, 0] *= -1.0
    parts = [half, mirror]
    if n % 2:
        mid = rng.standard_normal((1, dim))
        mid[:, 0] = 0.0
        parts.append(mid)
    P = np.concatenate(parts)[rng.permutation(n)]
    return P + noise * rng.standard_normal(P.shape)


def random_instance(rng: np.random.Generator, n: int, dim: int) -> np.ndarray:
    """(n, n) Euclidean distance matrix of random points, max 1."""
    return _distance_matrix(random_points(rng, n, dim))


def near_symmetric_instance(rng: np.random.Generator, n: int, dim: int, noise: float) -> np.ndarray:
    """(n, n) distance matrix of a mirror-symmetric set plus ``noise``, max 1."""
    return _distance_matrix(near_symmetric_points(rng, n, dim, noise))


def dense_instance(rng: np.random.Generator, n: int, m: int, dim: int, noise: float | None = None) -> np.ndarray:
    """(m, m) distance matrix whose first ``n`` points are the samples, max 1."""
    if noise is None:
        P = random_points(rng, m, dim)
    else:
        P = near_symmetric_points(rng, m, dim, noise)
    return _distance_matrix(P)


def mixed_instances(seed: int, count: int, n: int):
    """``count`` instances cycling over random/near-symmetric, 2D/3D, noise levels."""
    rng = np.random.default_rng(seed)
    noises = (0.01, 0.05, 0.2)
    out = []
    for k in range(count):
        dim = 2 + (k % 2)
        if (k // 2) % 2 == 0:
            out.append(random_instance(rng, n, dim))
        else:
            out.append(near_symmetric_instance(rng, n, dim, noises[(k // 4) % 3]))
    return out


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def instance_generators():
    """The generators above, for tests that cannot import this module."""
    from types import SimpleNamespace

    return SimpleNamespace(
        random_instance=random_instance,
        near_symmetric_instance=near_symmetric_instance,
        dense_instance=dense_instance,
        mixed_instances=mixed_instances,
    )

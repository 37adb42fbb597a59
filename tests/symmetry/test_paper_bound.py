"""The paper's Section 4.2 eigenvalue quantity is a diagnostic: λ_0 < 0 on real-like inputs."""

import numpy as np
import pytest

from shapecond.errors import TooLargeError
from shapecond.shapes.metric import Sampling, build_metric_shape
from shapecond.shapes.synthetic import generate
from shapecond.symmetry import objective
from shapecond.symmetry.exact import exact_sigma
from shapecond.symmetry.paper_bound import MAX_PAPER_POINTS, paper_eigen_diagnostic, paper_matrices
from tests.helpers import near_symmetric_instance, random_instance


def test_quadratic_forms_are_d2_and_dist2_of_a_map():
    rng = np.random.default_rng(0)
    D = random_instance(rng, 6, 2)
    A, b, pairs = paper_matrices(D, 6)
    t = rng.permutation(6)
    v = np.zeros(len(pairs))
    v[np.arange(6) * 6 + t] = 1.0
    assert v @ A @ v == pytest.approx(objective.dist2(D, t))
    assert v @ (b * v) == pytest.approx(objective.d2(D, t))
    assert np.trace(A) == 0.0


@pytest.mark.parametrize("name,n", [("animal", 12), ("blob", 10)])
def test_lambda0_is_negative_on_generated_meshes(name, n):
    shape = build_metric_shape(generate(name), n_points=n, sampling=Sampling(metric="geodesic", cache=False))
    diag = paper_eigen_diagnostic(shape.D)
    assert diag.lambda_0 < 0 and diag.paper_value is None and not diag.is_bound
    assert diag.n_negative > 0 and diag.trace_A == 0.0


def test_lambda0_is_negative_where_sigma_is_finite():
    """1/sqrt(λ_0) would have to bound a finite σ; it is not even real."""
    for seed in range(5):
        D = near_symmetric_instance(np.random.default_rng(seed), 7, 3, 0.1)
        assert exact_sigma(D).sigma < np.inf
        assert paper_eigen_diagnostic(D).lambda_0 < 0


def test_refuses_large_inputs():
    with pytest.raises(TooLargeError, match="diagnostic"):
        paper_eigen_diagnostic(random_instance(np.random.default_rng(0), MAX_PAPER_POINTS + 1, 2))

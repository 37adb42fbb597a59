"""LP upper bound (RLT-1 relaxation, Charnes–Cooper) against the exact σ."""

import math

import numpy as np
import pytest

from shapecond.errors import TooLargeError
from shapecond.symmetry import objective
from shapecond.symmetry.exact import exact_sigma
from shapecond.symmetry.relax import MAX_LP_POINTS, build_lp, lp_size, lp_upper_bound
from tests.helpers import dense_instance, mixed_instances, near_symmetric_instance, random_instance


def lp_point(D, n, landmarks, t):
    """The Charnes–Cooper point (τx, τ x⊗x, τ) of a map t, τ = 1/Dist²(t)."""
    M = D.shape[0]
    F = [x for x in range(n) if x not in landmarks]
    R = [y for y in range(M) if y not in landmarks]
    f, r = len(F), len(R)
    tau = 1.0 / objective.dist2(D, t)
    x = np.zeros((f, r))
    for i, xi in enumerate(F):
        x[i, R.index(int(t[xi]))] = 1.0
    ii, jj = np.triu_indices(f, 1)
    aa, bb = np.nonzero(~np.eye(r, dtype=bool))
    I, J = np.repeat(ii, aa.size), np.repeat(jj, aa.size)
    A, B = np.tile(aa, ii.size), np.tile(bb, ii.size)
    y = x[I, A] * x[J, B]
    return tau * np.concatenate([x.ravel(), y, [1.0]])


@pytest.mark.parametrize("n,m,landmarks", [(6, 6, ()), (7, 7, (2,)), (4, 7, ()), (5, 8, (1,))])
def test_every_map_is_a_feasible_point_with_its_own_ratio(n, m, landmarks):
    rng = np.random.default_rng(n + m)
    D = dense_instance(rng, n, m, 2)
    c, A_eq, b_eq, A_ub, b_ub = build_lp(D, n, landmarks)
    assert c.size == lp_size(n - len(landmarks), m - len(landmarks))
    free = [x for x in range(n) if x not in landmarks]
    tfree = [y for y in range(m) if y not in landmarks]
    for _ in range(20):
        t = np.arange(n)
        t[free] = rng.permutation(tfree)[: len(free)]
        if np.all(t == np.arange(n)):
            continue
        z = lp_point(D, n, landmarks, t)
        assert np.allclose(A_eq @ z, b_eq, atol=1e-12)
        assert np.all(A_ub @ z <= b_ub + 1e-12)
        assert -c @ z == pytest.approx(objective.d2(D, t) / objective.dist2(D, t), rel=1e-12)


def test_identity_is_cut_off():
    D = random_instance(np.random.default_rng(0), 6, 2)
    c, A_eq, b_eq, A_ub, b_ub = build_lp(D, 6, ())
    x = np.eye(6).ravel()
    cut = A_ub[-1].toarray().ravel()
    assert cut[: x.size] @ x + cut[-1] > 0  # τ = 1: Σ x_ii = 6 > 6 - 2


def test_lp_brackets_exact_and_is_tight_at_n8():
    """40 of the 200 instances of the benchmark (bench_exact_lp.py runs all 200)."""
    for D in mixed_instances(2024, 40, 8):
        e = exact_sigma(D)
        lp = lp_upper_bound(D)
        assert lp.status == "optimal"
        assert e.sigma <= lp.upper * (1 + 1e-9)
        assert lp.upper / e.sigma <= 1.01


def test_lp_brackets_exact_with_landmarks():
    rng = np.random.default_rng(4)
    for k in range(6):
        D = random_instance(rng, 8, 2) if k % 2 else near_symmetric_instance(rng, 8, 3, 0.05)
        L = [0] if k < 3 else [1, 4]
        e = exact_sigma(D, landmarks=L)
        lp = lp_upper_bound(D, landmarks=L)
        assert e.sigma <= lp.upper * (1 + 1e-9) and lp.upper / e.sigma <= 1.01


def test_lp_brackets_exact_for_injective_maps():
    rng = np.random.default_rng(6)
    for k in range(10):
        n = int(rng.integers(3, 7))
        m = int(rng.integers(n + 1, 11))
        D = dense_instance(rng, n, m, 2 + k % 2, None if k % 2 else 0.05)
        L = [0] if k % 4 == 0 else []
        e = exact_sigma(D, n_samples=n, landmarks=L)
        lp = lp_upper_bound(D, n_samples=n, landmarks=L)
        assert lp.status == "optimal"
        assert e.sigma <= lp.upper * (1 + 1e-9)


def test_isometry_gives_inf():
    D = near_symmetric_instance(np.random.default_rng(2), 7, 2, 0.0)
    assert exact_sigma(D).sigma == math.inf
    assert lp_upper_bound(D).upper == math.inf


def test_refuses_above_the_size_limit_unless_forced():
    D = random_instance(np.random.default_rng(0), MAX_LP_POINTS + 1, 2)
    with pytest.raises(TooLargeError, match="--force"):
        lp_upper_bound(D)
    # Landmarks reduce the free points, so the same matrix is accepted with two of them.
    lp = lp_upper_bound(D[:9, :9], landmarks=[0, 1])
    assert lp.status == "optimal"


def test_no_admissible_map():
    D = random_instance(np.random.default_rng(0), 4, 2)
    assert lp_upper_bound(D, landmarks=[0, 1, 2]).upper == 0.0


def test_triangle_cuts_close_the_gap_of_the_plain_rlt1_bound():
    """A frustrated instance (found in the 200-instance sweep): plain RLT-1 is 1.14x loose."""
    D = mixed_instances(2024, 14, 8)[13]
    e = exact_sigma(D)
    plain = lp_upper_bound(D, cuts=False)
    cut = lp_upper_bound(D)
    assert plain.upper / e.sigma > 1.05 and plain.n_cuts == 0
    assert e.sigma <= cut.upper * (1 + 1e-9) and cut.upper / e.sigma <= 1.001 and cut.n_cuts > 0


@pytest.mark.parametrize("n,m,landmarks", [(7, 7, ()), (5, 8, (1,))])
def test_triangle_inequalities_hold_at_every_map(n, m, landmarks):
    from shapecond.symmetry.relax import _TriangleSeparator

    rng = np.random.default_rng(3)
    D = dense_instance(rng, n, m, 3)
    sep = _TriangleSeparator(n, m, list(landmarks))
    free = [x for x in range(n) if x not in landmarks]
    tfree = [y for y in range(m) if y not in landmarks]
    for _ in range(20):
        t = np.arange(n)
        t[free] = rng.permutation(tfree)[: len(free)]
        if not np.all(t == np.arange(n)):
            assert sep(lp_point(D, n, landmarks, t)) is None


def test_time_limit_gives_inf_rather_than_an_unproven_value():
    D = random_instance(np.random.default_rng(0), 12, 2)
    lp = lp_upper_bound(D, time_limit=1e-3)
    assert lp.upper == math.inf and lp.status == "time-limit"


def test_the_lp_prints_nothing_on_stdout():
    """highspy 1.16 prints a banner on file descriptor 1 when a Highs instance is made, before any
    option can be set; it came out in front of ``score --upper --json``.  HiGHS prints it once per
    process, hence a fresh one."""
    import os
    import subprocess
    import sys

    script = ("import sys; import numpy as np; from shapecond.symmetry.relax import lp_upper_bound; "
              "from tests.helpers import random_instance; "
              "print(lp_upper_bound(random_instance(np.random.default_rng(0), 6, 2)).status, file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert proc.returncode == 0 and proc.stderr.strip() == "optimal", proc.stderr
    assert proc.stdout == ""

"""Heat map of the local score with each vertex fixed, greedy local landmarks (deformation/heatmap.py)."""

import math

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.stats import spearmanr

from shapecond.deformation.heatmap import exact_lambda, local_heatmap, select_local_landmarks
from shapecond.deformation.local_score import LocalProblem
from shapecond.threads import one_blas_thread
from shapecond.errors import InputError
from shapecond.shapes.synthetic import bumpy_blob, sphere


@pytest.fixture(scope="module")
def blob():
    g = bumpy_blob(2)  # 162 vertices: exact re-solves for every vertex stay fast
    return g, LocalProblem(g.vertices, g.faces)


def _exact_all(P, fixed):
    return np.array([exact_lambda(P, list(fixed) + [v])[0] if v not in fixed else np.nan
                     for v in range(P.n_vertices)])


def test_exact_lambda_agrees_with_dense_solve(blob):
    g, P = blob
    H, m = P.H.toarray(), P.mass
    for fixed in ([7], [7, 90, 150]):
        free = np.array([i for i in range(H.shape[0]) if i // 3 not in fixed])
        with one_blas_thread():
            lam = sl.eigh(H[np.ix_(free, free)], np.diag(m[free]), eigvals_only=True, subset_by_index=[0, 0])[0]
        assert np.isclose(exact_lambda(P, fixed)[0], lam, rtol=1e-7)


@pytest.mark.parametrize("fixed", [(), (0,)])
def test_modal_heatmap_bounds_and_ranks_like_exact_resolves(blob, fixed):
    g, P = blob
    exact = _exact_all(P, fixed)
    hm = local_heatmap(P, fixed)
    free = np.isfinite(exact)
    # Courant-Fischer: the modal value is an upper bound of the exact constrained lambda_min
    assert np.all(hm.lambdas[free] >= exact[free] * (1 - 1e-8))
    assert spearmanr(hm.lambdas[free], exact[free]).correlation > 0.9
    best = int(hm.order()[0])
    assert int(np.sum(exact[free] > exact[best])) < 5          # the modal choice is near the top
    assert np.allclose(hm.values[free], np.sqrt(2.0 / hm.lambdas[free]))
    for v in fixed:
        assert hm.lambdas[v] == pytest.approx(P.score(fixed).lambda_min)


def test_sphere_heatmap_keeps_one_zero_mode_then_finite():
    g = sphere(2)
    P = LocalProblem(g.vertices, g.faces)
    hm = local_heatmap(P)
    assert np.all(np.isinf(hm.values)) and np.all(hm.n_zero == 1)  # any single vertex: its own axis
    hm1 = local_heatmap(P, [0])
    antipode = int(np.argmin(g.vertices @ g.vertices[0]))
    others = np.setdiff1d(np.arange(g.n_vertices), [0, antipode])
    assert np.isinf(hm1.values[antipode])
    assert np.all(np.isfinite(hm1.values[others]))


def test_greedy_selection_on_sphere_and_blob(blob):
    s = sphere(2)
    res = select_local_landmarks(LocalProblem(s.vertices, s.faces), 3)
    assert res.initial == math.inf and res.scores[0] == math.inf
    assert math.isfinite(res.scores[1]) and res.scores[2] <= res.scores[1]
    g, P = blob
    res = select_local_landmarks(P, 2, refine=10)
    exact = _exact_all(P, ())
    assert res.landmarks[0] == int(np.nanargmax(exact))    # refinement recovers the exact argmax
    assert res.scores[0] == pytest.approx(math.sqrt(2.0 / np.nanmax(exact)))
    assert res.scores[1] <= res.scores[0] <= res.initial
    d = res.to_dict(ids=np.arange(g.n_vertices) + 1000)
    assert d["landmarks"] == [v + 1000 for v in res.landmarks]
    with pytest.raises(InputError):
        select_local_landmarks(P, 0)

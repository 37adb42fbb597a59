"""Baselines of paper Section 7: FPS, PLS (reimplementation), HKS extrema, user landmarks."""

import numpy as np
import pytest
import scipy.sparse as sp

from shapecond.errors import InputError
from shapecond.landmarks import select_landmarks
from shapecond.landmarks.fps import fps_landmarks
from shapecond.landmarks.hks import _local_maxima, heat_kernel_signature, hks_landmarks
from shapecond.landmarks.pls import _entropy, distance_histograms, pls_landmarks
from shapecond.shapes.metric import from_distance_matrix, metric_shape
from shapecond.shapes.synthetic import animal


def _dist(P):
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    return D / D.max()


@pytest.fixture(scope="module")
def animal_shape():
    return metric_shape(animal(delta=0.05), n_points=60, cache=False)


def test_fps_brute_force():
    rng = np.random.default_rng(0)
    D = _dist(rng.normal(size=(30, 3)))
    for seed in range(3):
        got = fps_landmarks(D, 30, 6, seed=seed)
        r = int(np.random.default_rng(seed).integers(30))
        want = [int(np.argmax(D[r]))]
        while len(want) < 6:
            want.append(int(np.argmax(np.min(D[want], axis=0))))
        assert got == want
    # with fixed landmarks the new ones are farthest from them
    assert fps_landmarks(D, 30, 1, fixed=[4]) == [int(np.argmax(D[4]))]
    with pytest.raises(InputError):
        fps_landmarks(D, 30, 31)


def test_pls_descriptor_and_entropy():
    D = _dist(np.random.default_rng(1).normal(size=(12, 2)))
    H = distance_histograms(D, 12)
    assert np.allclose(H.sum(axis=1), 1.0)
    assert np.isclose(_entropy(np.zeros(8)), np.log(8))
    assert np.isclose(_entropy(np.array([0.0, -1e9])), 0.0)


def test_pls_first_landmark_is_most_distinctive():
    # a regular polygon (all points alike) plus one point far off its centre
    ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    P = np.c_[np.cos(ang), np.sin(ang)]
    P = np.vstack([P, [[0.0, 3.0]]])
    D = _dist(P)
    got, totals = pls_landmarks(D, 17, 4)
    assert got[0] == 16
    assert len(set(got)) == 4
    # planning reduces the total uncertainty at every step
    assert all(b < a for a, b in zip(totals, totals[1:]))
    assert pls_landmarks(D, 17, 4) == (got, totals)  # deterministic


def test_hks_closed_form_and_local_maxima():
    evals = np.array([0.0, 1.0, 4.0])
    evecs = np.array([[1.0, 0.5, 0.0], [1.0, -0.5, 1.0]])
    t = 0.3
    want = [1 + 0.25 * np.exp(-0.3), 1 + 0.25 * np.exp(-0.3) + np.exp(-1.2)]
    assert np.allclose(heat_kernel_signature(evals, evecs, t), want)
    # path graph 0-1-2-3-4 with values peaking at 1 and 4
    h = np.array([0.0, 2.0, 1.0, 1.5, 3.0])
    i = np.r_[0:4, 1:5]
    j = np.r_[1:5, 0:4]
    A = sp.csr_matrix((np.ones(8), (i, j)), shape=(5, 5))
    assert list(_local_maxima(h, A)) == [4, 1]


def test_hks_landmarks_on_extremities(animal_shape):
    shape = animal_shape
    got, n_peaks = hks_landmarks(shape, 4)
    assert len(set(got)) == 4 and n_peaks >= 1
    V = shape.geometry.vertices
    centre = V.mean(axis=0)
    r = np.linalg.norm(V[shape.samples[:60]] - centre, axis=1)
    # HKS maxima sit on protrusions: farther from the centre than the median sample
    assert np.all(r[got[:n_peaks]] > np.median(r))


def test_hks_on_a_matrix_uses_a_graph_laplacian():
    D = _dist(np.random.default_rng(2).normal(size=(40, 3)))
    got, _ = hks_landmarks(from_distance_matrix(D), 5)
    assert len(set(got)) == 5


def test_user_landmarks_from_file(tmp_path, animal_shape):
    shape = animal_shape
    ids = shape.sample_ids[[5, 2, 9]]
    f = tmp_path / "lm.pid"
    f.write_text("".join(f"  {v} 0 0 0\n" for v in ids))
    r = select_landmarks(shape, 0, "user", path=str(f))
    assert list(r.landmarks) == [int(v) for v in ids]
    assert list(r.sample_indices) == [5, 2, 9]
    # a vertex that is not a sample goes to its nearest sample
    v = int(np.setdiff1d(np.arange(shape.geometry.n_vertices), shape.samples)[0])
    r2 = select_landmarks(shape, 0, "user", ids=[int(shape.geometry.ids[v])])
    assert r2.sample_indices[0] < shape.n_samples
    with pytest.raises(InputError):
        select_landmarks(shape, 0, "user", ids=[int(ids[0]), int(ids[0])])
    with pytest.raises(InputError):
        select_landmarks(shape, 0, "user", ids=[10**9])


def test_select_landmarks_result(animal_shape):
    r = select_landmarks(animal_shape, 3, "fps", scores=True)
    d = r.to_dict()
    assert set(d) >= {"landmarks", "scores", "method", "seconds"}
    assert len(d["landmarks"]) == 3 and all(s is not None for s in d["scores"])
    assert r.vertices == tuple(int(animal_shape.samples[i]) for i in r.sample_indices)
    assert select_landmarks(animal_shape, 3, "pls").scores == (None, None, None)
    with pytest.raises(InputError):
        select_landmarks(animal_shape, 3, "magic")
    with pytest.raises(InputError):
        select_landmarks(animal_shape, 0, "fps")


def test_cnbs_local_on_a_small_mesh():
    from shapecond.shapes.synthetic import bumpy_blob

    g = bumpy_blob(subdivisions=2)
    shape = metric_shape(g, n_points=30, target="samples", cache=False)
    r = select_landmarks(shape, 3, "cnbs-local")
    assert r.method == "cnbs-local" and len(set(r.vertices)) == 3
    assert all(b <= a * (1 + 1e-9) for a, b in zip(r.scores, r.scores[1:]))
    assert r.scores[0] <= r.initial_score * (1 + 1e-9)
    D = _dist(np.random.default_rng(0).normal(size=(10, 3)))
    with pytest.raises(InputError):
        select_landmarks(from_distance_matrix(D), 2, "cnbs-local")

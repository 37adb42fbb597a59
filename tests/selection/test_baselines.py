"""Baselines of paper Section 7: FPS, PLS (reimplementation), HKS extrema, user landmarks."""

import numpy as np
import pytest
import scipy.sparse as sp

from shapecond.errors import InputError
from shapecond.selection import LandmarkOptions, select_landmarks
from shapecond.selection.fps import fps_landmarks
from shapecond.selection.hks import _local_maxima, heat_kernel_signature, hks_landmarks
from shapecond.selection.pls import _entropy, distance_histograms, pls_landmarks
from shapecond.shapes.metric import Sampling, build_metric_shape, from_distance_matrix
from shapecond.shapes.synthetic import animal
from shapecond.selection.user import UserLandmarks


def _dist(P):
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    return D / D.max()


@pytest.fixture(scope="module")
def animal_shape():
    """The generated animal, coarse (about 1.8k vertices), 60 samples."""
    return build_metric_shape(animal(delta=0.05, resolution=0.06), n_points=60, sampling=Sampling(cache=False))


def _star(seed=0):
    """Points along three arms of lengths 1, 0.8, 0.6 from the origin of the plane, slightly noisy:
    (distance matrix, indices of the three arm tips)."""
    pts, tips = [[0.0, 0.0]], []
    for angle, length in zip((0.0, 2.1, 4.2), (1.0, 0.8, 0.6)):
        for s in np.linspace(0.05, length, int(round(length / 0.05))):
            pts.append([s * np.cos(angle), s * np.sin(angle)])
        tips.append(len(pts) - 1)
    P = np.array(pts) + 0.005 * np.random.default_rng(seed).normal(size=(len(pts), 2))
    return _dist(P), tips


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


@pytest.mark.parametrize("seed", range(4))
def test_fps_landmarks_cover_the_samples_within_their_spacing(seed):
    """Farthest point sampling's covering property: after k landmarks every sample lies within r_k
    of one of them, and no two landmarks are closer than r_k, so r_k is at most twice the best
    covering radius any k samples achieve (checked against all k-subsets)."""
    import itertools

    rng = np.random.default_rng(seed)
    D = _dist(rng.normal(size=(14, 3)))
    for k in (2, 3, 4):
        got = fps_landmarks(D, 14, k, seed=seed)
        assert len(set(got)) == k
        radius = D[got].min(axis=0).max()
        spacing = min(D[a, b] for a, b in itertools.combinations(got, 2))
        assert spacing >= radius - 1e-12
        best = min(D[list(c)].min(axis=0).max() for c in itertools.combinations(range(14), k))
        assert radius <= 2 * best + 1e-12
    # landmarks added to fixed ones keep the property with the fixed ones counted
    fixed = [3, 9]
    got = fps_landmarks(D, 14, 3, fixed=fixed)
    assert not set(got) & set(fixed)
    everything = fixed + got
    radius = D[everything].min(axis=0).max()
    assert min(D[a, b] for a in got for b in everything if a != b) >= radius - 1e-12


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
    """On a mesh the six HKS maxima are the animal's extremities: its four feet, head and tail."""
    shape = animal_shape
    got, n_peaks = hks_landmarks(shape, 6)
    assert n_peaks == 6 and len(set(got)) == 6
    V = shape.geometry.vertices
    low = V[:, 1] < np.quantile(V[:, 1], 0.1)
    feet = [np.flatnonzero(low & (np.sign(V[:, 0]) == sx) & (np.sign(V[:, 2]) == sz))
            for sx in (-1, 1) for sz in (-1, 1)]
    tips = [V[f[np.argmin(V[f, 1])]] for f in feet] + [V[np.argmin(V[:, 2])], V[np.argmax(V[:, 2])]]
    nearest = [int(np.argmin(np.linalg.norm(np.array(tips) - V[shape.samples[i]], axis=1))) for i in got]
    assert sorted(nearest) == list(range(6))
    assert all(np.linalg.norm(tips[t] - V[shape.samples[i]]) < 0.2 for t, i in zip(nearest, got))
    assert hks_landmarks(shape, 6) == (got, n_peaks)


def test_hks_on_a_matrix_finds_the_arm_tips_whatever_the_sample_order():
    """A distance matrix has no mesh: the heat kernel signature comes from a graph Laplacian on the
    samples, and its maxima are the ends of a star's three arms, found again (same landmarks, same
    order) when the samples are listed in another order, and on every call."""
    D, tips = _star()
    got, n_peaks = hks_landmarks(from_distance_matrix(D), 3)
    assert n_peaks == 3 and sorted(got) == sorted(tips)
    assert hks_landmarks(from_distance_matrix(D), 3) == (got, n_peaks)
    perm = np.random.default_rng(1).permutation(len(D))
    again, _ = hks_landmarks(from_distance_matrix(D[np.ix_(perm, perm)]), 3)
    assert [int(perm[i]) for i in again] == got


def test_user_landmarks_from_file(tmp_path, animal_shape):
    shape = animal_shape
    ids = shape.sample_ids[[5, 2, 9]]
    f = tmp_path / "lm.pid"
    f.write_text("".join(f"  {v} 0 0 0\n" for v in ids))
    r = select_landmarks(shape, 0, "user", LandmarkOptions(own=UserLandmarks(path=str(f))))
    assert list(r.landmarks) == [int(v) for v in ids]
    assert list(r.sample_indices) == [5, 2, 9]
    # a vertex that is not a sample goes to its nearest sample
    v = int(np.setdiff1d(np.arange(shape.geometry.n_vertices), shape.samples)[0])
    r2 = select_landmarks(shape, 0, "user", LandmarkOptions(own=UserLandmarks(ids=[int(shape.geometry.ids[v])])))
    assert r2.sample_indices[0] < shape.n_samples
    with pytest.raises(InputError):
        select_landmarks(shape, 0, "user", LandmarkOptions(own=UserLandmarks(ids=[int(ids[0]), int(ids[0])])))
    with pytest.raises(InputError):
        select_landmarks(shape, 0, "user", LandmarkOptions(own=UserLandmarks(ids=[10**9])))


def test_select_landmarks_result(animal_shape):
    r = select_landmarks(animal_shape, 3, "fps", options=LandmarkOptions(scores=True))
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
    shape = build_metric_shape(g, n_points=30, sampling=Sampling(target="samples", cache=False))
    r = select_landmarks(shape, 3, "cnbs-local")
    assert r.method == "cnbs-local" and len(set(r.vertices)) == 3
    assert all(b <= a * (1 + 1e-9) for a, b in zip(r.scores, r.scores[1:]))
    assert r.scores[0] <= r.initial_score * (1 + 1e-9)
    D = _dist(np.random.default_rng(0).normal(size=(10, 3)))
    with pytest.raises(InputError):
        select_landmarks(from_distance_matrix(D), 2, "cnbs-local")


def test_the_interface_builds_each_method_s_own_options_from_its_keywords():
    """``api.options.landmark_options``: the flat keywords of ``sc.landmarks`` become one
    ``LandmarkOptions`` with the method's own options object; a name the method does not take, a bad
    epsilon or score is refused before any work."""
    from shapecond.api.options import landmark_options
    from shapecond.selection import LocalLandmarkOptions, check_method_options
    from shapecond.selection.hks import HKSOptions

    opts, runtime = landmark_options("hks", 3, {"time_fraction": 0.2, "n_eigs": 12, "effort": "quick"})
    assert opts.own == HKSOptions(time_fraction=0.2, n_eigs=12) and (opts.seed, opts.effort) == (3, "quick")
    assert runtime == {}
    assert landmark_options("cnbs-local", 0, {"alpha": 2.0})[0].own == LocalLandmarkOptions(alpha=2.0)
    assert landmark_options("user", 0, {"ids": [4, 5]})[0].own == UserLandmarks(ids=[4, 5])
    assert landmark_options("fps", 0, {"fixed": [2]})[0] == LandmarkOptions(fixed=(2,))
    cnbs, runtime = landmark_options("cnbs", 1, {"n_kicks": 2, "progress": print})
    assert cnbs.own.n_kicks == 2 and cnbs.seed == 1 and runtime == {"progress": print}
    for method, other in (("hks", "alpha"), ("cnbs-local", "n_eigs"), ("user", "refine"), ("fps", "ids")):
        with pytest.raises(InputError, match=f"{method!r} has no option {other!r}"):
            check_method_options(method, {other: 1})
    with pytest.raises(InputError, match="epsilon"):
        landmark_options("fps", 0, {"epsilon": -1.0})
    with pytest.raises(InputError, match="score"):
        landmark_options("fps", 0, {"score": "sigmaa"})

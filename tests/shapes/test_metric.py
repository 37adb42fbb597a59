"""The metric shape: normalisation, caching, invariances."""

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.shapes import synthetic
from shapecond.shapes.geometry import Geometry
from shapecond.shapes.validate import make_geometry
from shapecond.shapes.metric import Sampling, build_metric_shape, from_distance_matrix


def test_metric_shape_is_a_normalised_metric():
    s = build_metric_shape(synthetic.bumpy_blob(3), n_points=40, sampling=Sampling(cache=False))
    assert s.D.shape == (40, 40) and np.isclose(s.D.max(), 1.0)
    assert np.allclose(s.D, s.D.T) and np.all(np.diag(s.D) == 0)
    assert s.backend == "heat" and s.metric == "geodesic" and s.n_points == s.n_targets == 40
    assert 0 < s.covering_radius < 0.5


def test_cache_returns_the_same_shape(tmp_path, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path))
    g = synthetic.bumpy_blob(3)
    a = build_metric_shape(g, n_points=30)
    assert len(list(tmp_path.glob("metric-*.npz"))) == 1
    b = build_metric_shape(g, n_points=30)
    assert np.array_equal(a.D, b.D) and np.array_equal(a.samples, b.samples)
    c = build_metric_shape(g, n_points=30, sampling=Sampling(seed=1))  # a parameter change is a new entry
    assert len(list(tmp_path.glob("metric-*.npz"))) == 2 and c is not None


def test_invariant_to_relabelling_and_uniform_scaling():
    g = synthetic.bumpy_blob(3)
    perm = np.random.default_rng(0).permutation(g.n_vertices)
    inv = np.argsort(perm)
    relabelled = make_geometry(g.vertices[perm], inv[g.faces])
    scaled = make_geometry(3.7 * g.vertices, g.faces)
    base = build_metric_shape(g, n_points=25, landmarks=[11], sampling=Sampling(cache=False))
    other = build_metric_shape(relabelled, n_points=25, landmarks=[int(inv[11])], sampling=Sampling(cache=False))
    big = build_metric_shape(scaled, n_points=25, landmarks=[11], sampling=Sampling(cache=False))
    assert np.array_equal(perm[other.samples], base.samples)
    assert np.allclose(other.D, base.D, atol=1e-6)
    assert np.array_equal(big.samples, base.samples)
    assert np.allclose(big.D, base.D, atol=1e-6) and np.isclose(big.scale, 3.7 * base.scale)


def test_dense_targets_have_the_samples_as_prefix():
    g = synthetic.bumpy_blob(3)
    dense = build_metric_shape(g, n_points=20, sampling=Sampling(target="dense", target_factor=4, cache=False))
    plain = build_metric_shape(g, n_points=20, sampling=Sampling(cache=False))
    assert dense.n_targets == 80 and dense.n_points == 20
    assert np.array_equal(dense.samples[:20], plain.samples)
    assert np.allclose(dense.D[:20, :20] * dense.scale, plain.D * plain.scale)  # the same geodesics between them


def test_symmetric_animal_samples_are_mirror_closed():
    g = synthetic.animal(resolution=0.05)
    s = build_metric_shape(g, n_points=40, sampling=Sampling(cache=False))
    inv = {v: k for k, v in enumerate(s.samples)}
    mirror = np.array([inv[g.symmetry[v]] for v in s.samples])
    assert np.allclose(s.D[np.ix_(mirror, mirror)], s.D, atol=1e-9)


def test_matrix_input_and_errors():
    pts = np.random.default_rng(2).normal(size=(7, 2))
    D = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    s = from_distance_matrix(D, landmarks=[4, 1])
    assert list(s.samples[:2]) == [4, 1] and np.isclose(s.D.max(), 1)
    assert np.allclose(s.D * s.scale, D[np.ix_(s.samples, s.samples)])
    with pytest.raises(InputError, match="fewer than"):
        build_metric_shape(make_geometry(pts.repeat(2, 1)[:, :3]), n_points=10)
    with pytest.raises(InputError, match="zero"):
        build_metric_shape(Geometry(np.zeros((5, 3)), None, np.arange(5)), n_points=3, sampling=Sampling(metric="euclidean", cache=False))

"""Farthest-point sampling (landmarks first, seeded start, FPS order) and symmetry-consistent sampling
(samples and targets closed under the mirror map)."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from shapecond.errors import InputError
from shapecond.shapes import synthetic
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.validate import make_geometry
from shapecond.shapes.sampling import farthest_point_sampling


def _cloud_solver(seed, n=60):
    pts = np.random.default_rng(seed).normal(size=(n, 3))
    return DistanceSolver(make_geometry(pts), "euclidean"), pts


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), k=st.integers(3, 30))
def test_farthest_point_property_and_prefix_order(seed, k):
    solver, pts = _cloud_solver(seed)
    fps = farthest_point_sampling(solver, k, seed=seed)
    full = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    for i in range(1, k):  # each sample is farthest from the previous ones
        mind = full[fps.samples[:i]].min(axis=0)
        assert np.isclose(mind[fps.samples[i]], mind.max())
    longer = farthest_point_sampling(solver, k + 5, seed=seed)
    assert np.array_equal(longer.samples[:k], fps.samples)  # order kept: prefixes agree
    assert np.allclose(fps.D, full[np.ix_(fps.samples, fps.samples)])


def test_paper_start_and_seeded_determinism():
    solver, pts = _cloud_solver(3)
    a = farthest_point_sampling(solver, 10, seed=7)
    b = farthest_point_sampling(solver, 10, seed=7)
    assert np.array_equal(a.samples, b.samples)
    r = np.random.default_rng(7).integers(pts.shape[0])
    assert a.samples[0] == np.argmax(np.linalg.norm(pts - pts[r], axis=1))


def test_kept_rows_are_the_samples_rows_in_float32_and_change_no_sample():
    """``keep_rows=True`` returns every sample's row as the solver gave it, rounded to float32 (what
    ``matching.sampled.sample_surface`` stores), whatever the budget; the samples are those without."""
    g = synthetic.bumpy_blob(subdivisions=2)
    solver = DistanceSolver(g)  # the heat method: rows fetched ahead in blocks, some never used
    kept = farthest_point_sampling(solver, 40, landmarks=[3, 50], keep_rows=True)
    plain = farthest_point_sampling(solver, 40, landmarks=[3, 50], keep_rows=False)
    assert plain.rows is None and farthest_point_sampling(solver, 5).rows is None  # default: not returned
    assert np.array_equal(kept.samples, plain.samples)
    assert kept.rows.dtype == np.float32 and kept.rows.shape == (40, g.n_vertices)
    np.testing.assert_allclose(kept.rows, solver.distances(kept.samples), rtol=1e-6, atol=1e-7)


def test_landmarks_first_and_voronoi_labels():
    solver, pts = _cloud_solver(4)
    fps = farthest_point_sampling(solver, 12, landmarks=[5, 17, 2])
    assert list(fps.samples[:3]) == [5, 17, 2]
    d = np.linalg.norm(pts[:, None] - pts[fps.samples][None], axis=-1)
    assert np.allclose(d.min(axis=1), fps.min_dist)
    assert np.allclose(d[np.arange(len(pts)), fps.nearest], fps.min_dist)


def test_bad_requests():
    solver, _ = _cloud_solver(5, n=8)
    with pytest.raises(InputError, match="cannot take"):
        farthest_point_sampling(solver, 9)
    with pytest.raises(InputError, match="repeated"):
        farthest_point_sampling(solver, 5, landmarks=[1, 1])
    with pytest.raises(InputError, match="at least 3"):
        farthest_point_sampling(solver, 2)


@pytest.mark.parametrize("stops", [(), (21,)])
def test_symmetric_sampling_is_closed_under_the_map(stops):
    g = synthetic.animal(resolution=0.06)
    fps = farthest_point_sampling(DistanceSolver(g, "euclidean"), 60, symmetry=g.symmetry, stops=stops)
    for k in (60,) + tuple(stops):
        chosen = set(fps.samples[:k].tolist())
        assert {int(g.symmetry[v]) for v in chosen} == chosen

"""Geodesic backends against closed forms."""

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.shapes import synthetic
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.validate import make_geometry


def _great_circle_error(backend, subdivisions):
    g = synthetic.sphere(subdivisions=subdivisions)
    V = g.vertices / np.linalg.norm(g.vertices, axis=1, keepdims=True)
    sources = np.random.default_rng(0).choice(g.n_vertices, 5, replace=False)
    rows = DistanceSolver(g, backend).distances(sources)
    exact = np.arccos(np.clip(V[sources] @ V.T, -1, 1))
    return np.mean(np.abs(rows - exact)) / np.pi  # fraction of the diameter


def test_heat_method_on_sphere_within_one_percent_of_diameter():
    assert _great_circle_error("heat", 5) < 0.01  # about 10k vertices


def test_fast_marching_on_sphere():
    assert _great_circle_error("fmm", 4) < 0.01


def test_euclidean_and_records_backend():
    pts = np.random.default_rng(1).normal(size=(10, 3))
    solver = DistanceSolver(make_geometry(pts), "euclidean")
    assert solver.backend == "euclidean"
    assert np.allclose(solver.distances([3])[0], np.linalg.norm(pts - pts[3], axis=1))


def test_point_cloud_heat_and_refusals():
    g = synthetic.sphere(subdivisions=3)
    cloud = make_geometry(g.vertices)
    d = DistanceSolver(cloud, "heat").distances([0])[0]
    V = g.vertices / np.linalg.norm(g.vertices, axis=1, keepdims=True)
    assert np.mean(np.abs(d - np.arccos(np.clip(V @ V[0], -1, 1)))) / np.pi < 0.05
    with pytest.raises(InputError, match="needs a mesh"):
        DistanceSolver(cloud, "fmm")
    with pytest.raises(InputError, match="unknown geodesic backend"):
        DistanceSolver(g, "dijkstra")


def test_exact_backend_on_sphere():
    pytest.importorskip("gdist")
    assert _great_circle_error("exact", 3) < 0.005

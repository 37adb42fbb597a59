"""The sides of landmark pairs: kept by rotations and bendings, reversed by reflections."""

import numpy as np

from shapecond.matching.orientation import orientation_agreement, orientation_features
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.synthetic import bumpy_blob
from shapecond.shapes.validate import make_geometry


def _rows(g, landmarks):
    return DistanceSolver(g, "heat").distances(landmarks)


def _mirror(g):
    """The blob reflected through x = 0 (faces re-oriented so that the mesh stays outward)."""
    V = g.vertices * [-1.0, 1.0, 1.0]
    return make_geometry(V, g.faces[:, ::-1].copy())


def test_a_reflection_reverses_every_side_and_a_rotation_keeps_them():
    g = bumpy_blob(subdivisions=3)
    lm = [0, 40, 200, 333]
    fs = orientation_features(g, _rows(g, lm))
    assert fs.shape == (g.n_vertices, 6) and np.abs(fs).max() <= 1.0 + 1e-5
    ident = np.arange(g.n_vertices)
    # the mirror image with the same vertex order: vertex i of the copy is the reflection of vertex i
    m = _mirror(g)
    agree = orientation_agreement(g, m, ident, _rows(g, lm), _rows(m, lm))
    assert agree < -0.9
    th = 0.7  # a rotation about z, and the mesh given inside out (faces reversed): still the same sides
    R = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
    r = make_geometry(g.vertices @ R.T, g.faces[:, ::-1].copy())
    assert orientation_agreement(g, r, ident, _rows(g, lm), _rows(r, lm)) > 0.9


def test_no_sides_on_point_clouds_or_with_one_landmark():
    g = bumpy_blob(subdivisions=2)
    assert orientation_features(g, _rows(g, [0])) is None
    cloud = make_geometry(g.vertices, None)
    assert orientation_features(cloud, np.zeros((3, g.n_vertices))) is None

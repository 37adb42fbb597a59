"""Harmonic coordinates of landmarks: a partition of unity pinned on disks, kept by a stretch."""

import numpy as np
import pytest

from shapecond.matching.harmonic import harmonic_coordinates, landmark_disks
from shapecond.matching.zoomout import Anchors, ZoomOutOptions, zoomout
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.laplace import laplace_basis
from shapecond.shapes.synthetic import bumpy_blob, capped_cylinder


def _unit_rows(g, landmarks):
    """Geodesic rows in units of sqrt(area)."""
    area = float(np.linalg.norm(np.cross(g.vertices[g.faces[:, 1]] - g.vertices[g.faces[:, 0]],
                                         g.vertices[g.faces[:, 2]] - g.vertices[g.faces[:, 0]]), axis=1).sum() / 2)
    return DistanceSolver(g, "heat").distances(landmarks) / np.sqrt(area)


def test_a_partition_of_unity_one_on_its_disk_zero_on_the_others():
    g = bumpy_blob(subdivisions=3)
    lm = [0, 40, 200, 333]
    rows = _unit_rows(g, lm)
    H = harmonic_coordinates(g, rows, 0.05)
    label = landmark_disks(rows, 0.05)
    assert H.shape == (g.n_vertices, 4)
    np.testing.assert_allclose(H.sum(axis=1), 1.0, atol=1e-8)
    assert H.min() >= -1e-9 and H.max() <= 1 + 1e-9  # maximum principle
    on = label >= 0
    np.testing.assert_array_equal(H[on].argmax(axis=1), label[on])
    np.testing.assert_array_equal(H[on].max(axis=1), 1.0)
    assert np.all((H[~on] > 1e-6).sum(axis=1) >= 2)  # off the disks every point sees several landmarks
    np.testing.assert_array_equal(label[lm], np.arange(4))


def test_a_uniformly_stretched_tube_keeps_its_coordinates_but_not_its_distances():
    # same vertex order, the second tube 1.5x longer: the true map is the identity of ids;
    # geodesic distances to the landmarks (in sqrt(area)) change, the harmonic coordinates do not
    short = capped_cylinder(height=2.0, sections=24, n_height=30, n_cap_rings=4)
    long = capped_cylinder(height=3.0, sections=24, n_height=30, n_cap_rings=4)
    lm = [0, short.n_vertices - 1, 80]
    rs, rl = _unit_rows(short, lm), _unit_rows(long, lm)
    hs, hl = harmonic_coordinates(short, rs, 0.05), harmonic_coordinates(long, rl, 0.05)
    harmonic_change = np.abs(hs - hl).mean()
    distance_change = np.abs(rs - rl).mean()  # in sqrt(area), the unit the dense stage compares
    assert harmonic_change < 0.5 * distance_change  # 0.023 against 0.074 when written
    assert harmonic_change < 0.03


def test_the_coordinates_converge_with_refinement_on_disks():
    coarse, fine = bumpy_blob(subdivisions=3), bumpy_blob(subdivisions=4)
    # the coarse vertices are the first vertices of the finer icosphere
    np.testing.assert_allclose(fine.vertices[:coarse.n_vertices], coarse.vertices, atol=1e-9)
    lm = [0, 40, 200, 333]
    hc = harmonic_coordinates(coarse, _unit_rows(coarse, lm), 0.08)
    hf = harmonic_coordinates(fine, _unit_rows(fine, lm), 0.08)
    assert np.abs(hc - hf[:coarse.n_vertices]).mean() < 0.02


def test_no_coordinates_with_one_landmark():
    g = bumpy_blob(subdivisions=2)
    assert harmonic_coordinates(g, _unit_rows(g, [0]), 0.05) is None


@pytest.mark.parametrize("harmonic", [False, True])
def test_zoomout_with_the_harmonic_block_still_recovers_the_identity(harmonic):
    g = bumpy_blob(subdivisions=3)
    b = laplace_basis(g, k=60, cache=False)
    rng = np.random.default_rng(0)
    start = np.where(rng.random(g.n_vertices) < 0.3, rng.integers(0, g.n_vertices, g.n_vertices),
                     np.arange(g.n_vertices))
    lm = np.array([0, 100, 400, 555])
    rows = _unit_rows(g, lm)
    anchors = Anchors(lm, lm, rows, rows)
    if harmonic:
        anchors = anchors.harmonic(g, g, 0.05)
        assert anchors.source_harmonic is not None
    T = zoomout(b, b, (g.vertices, g.vertices), start, anchors, ZoomOutOptions(k_start=10, step=10))
    assert np.mean(T == np.arange(g.n_vertices)) > 0.95

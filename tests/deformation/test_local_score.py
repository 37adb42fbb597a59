"""Local symmetry score sigma_inf = sqrt(2 / lambda_min) (deformation/local_score.py)."""

import math

import numpy as np
import pytest
import scipy.linalg as sl

from shapecond.deformation.local_score import (LocalProblem, local_score_of_geometry,
                                               local_symmetry_score)
from shapecond.threads import one_blas_thread
from shapecond.errors import InputError
from shapecond.shapes.validate import make_geometry
from shapecond.shapes.synthetic import bumpy_blob, capped_cylinder, plane_patch, sphere, torus


def test_sphere_has_three_rotational_zero_modes():
    g = sphere(3)
    r = local_symmetry_score(g.vertices, g.faces)
    assert r.score == math.inf
    assert sorted(r.zero_modes) == ["rotation about x", "rotation about y", "rotation about z"]
    assert r.modes.shape == (3 * g.n_vertices, 3)


def test_sphere_landmarks_one_keeps_inf_two_make_finite():
    g = sphere(3)
    P = LocalProblem(g.vertices, g.faces)
    one = P.score([0])
    assert one.score == math.inf and len(one.zero_modes) == 1
    # the remaining mode is the rotation about the axis through the fixed vertex
    axis = g.vertices[0] / np.linalg.norm(g.vertices[0])
    name = one.zero_modes[0]
    assert name.startswith("rotation about axis")
    named = np.array([float(x) for x in name.split("(")[1].split(")")[0].split(",")])
    assert abs(abs(named @ axis) - 1.0) < 1e-2
    non_antipodal = int(np.argmax(g.vertices @ g.vertices[0] < 0.5))
    two = P.score([0, non_antipodal])
    assert math.isfinite(two.score) and two.zero_modes == ()
    antipodal = int(np.argmin(g.vertices @ g.vertices[0]))
    assert P.score([0, antipodal]).score == math.inf  # rotation about the axis through both


def test_capped_cylinder_names_axial_rotation():
    g = capped_cylinder()
    r = local_symmetry_score(g.vertices, g.faces)
    assert r.score == math.inf and r.zero_modes == ("rotation about z",)


def test_rotated_cylinder_axis_is_reported():
    g = capped_cylinder(sections=24, n_height=8, n_cap_rings=4)
    a = np.array([0.48, 0.64, 0.6])
    Q, _ = np.linalg.qr(np.column_stack([a, np.eye(3)[:, :2]]))
    R = np.column_stack([Q[:, 1], Q[:, 2], Q[:, 0]])  # maps z to +-a
    r = local_symmetry_score(g.vertices @ R.T + [1.0, 2.0, 3.0], g.faces)
    assert r.score == math.inf and len(r.zero_modes) == 1
    text = r.zero_modes[0]
    axis = np.array([float(x) for x in text.split("axis (")[1].split(")")[0].split(",")])
    point = np.array([float(x) for x in text.split("through (")[1].split(")")[0].split(",")])
    assert abs(abs(axis @ a) - 1.0) < 1e-2
    assert np.linalg.norm(np.cross(point - [1.0, 2.0, 3.0], a)) < 1e-2  # the axis passes the centre


def test_plane_patch_and_torus_are_inf():
    g = plane_patch(n=21)
    r = local_symmetry_score(g.vertices, g.faces)
    assert r.score == math.inf
    assert sorted(r.zero_modes) == ["rotation about z", "translation x", "translation y"]
    t = torus(n_major=32, n_minor=12)
    assert local_symmetry_score(t.vertices, t.faces).zero_modes == ("rotation about z",)


def test_blob_is_finite_and_matches_dense_eigenproblem():
    g = bumpy_blob(2)
    P = LocalProblem(g.vertices, g.faces)
    for fixed in ([], [3, 40]):
        r = P.score(fixed)
        free = np.array([i for i in range(3 * g.n_vertices) if i // 3 not in fixed])
        with one_blas_thread():  # threaded BLAS thrashes on a loaded 2-core machine
            lam = sl.eigh(P.H.toarray()[np.ix_(free, free)], np.diag(P.mass[free]), eigvals_only=True)[0]
        assert math.isfinite(r.score) and r.zero_modes == ()
        assert np.isclose(r.lambda_min, lam, rtol=1e-7)
        assert np.isclose(r.score, math.sqrt(2.0 / lam), rtol=1e-7)  # sqrt(2/lambda), not 2/sqrt(lambda)


def test_score_invariant_to_scale_and_rigid_motion_and_monotone_in_landmarks():
    g = bumpy_blob(3)
    base = local_symmetry_score(g.vertices, g.faces).score
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    moved = local_symmetry_score(4.0 * g.vertices @ R.T + 2.0, g.faces).score
    assert np.isclose(base, moved, rtol=1e-6)
    P = LocalProblem(g.vertices, g.faces)
    scores = [P.score(g_fixed).score for g_fixed in ([], [10], [10, 200], [10, 200, 400])]
    assert all(a >= b - 1e-9 for a, b in zip(scores, scores[1:]))  # eigenvalue interlacing


def test_resolution_does_not_move_the_score():
    """Same surface at 2.5k and 10k vertices: < 10 % apart (10k vs 41k is in benchmarks/bench_local.py,
    too slow for a unit test on 2 shared cores)."""
    a = bumpy_blob(4)
    b = bumpy_blob(5)
    sa = local_symmetry_score(a.vertices, a.faces).score
    sb = local_symmetry_score(b.vertices, b.faces).score
    assert abs(sa - sb) / sb < 0.10


def test_arap_energy_gives_the_same_zero_modes():
    g = capped_cylinder(sections=24, n_height=8, n_cap_rings=4)
    r = local_symmetry_score(g.vertices, g.faces, energy="arap")
    assert r.zero_modes == ("rotation about z",)
    b = bumpy_blob(2)
    assert math.isfinite(local_symmetry_score(b.vertices, b.faces, energy="arap").score)


def test_to_dict_keys_and_file_ids():
    g = bumpy_blob(2)
    geo = make_geometry(g.vertices, g.faces)
    geo = type(geo)(geo.vertices, geo.faces, geo.ids + 100, "blob")
    r = local_score_of_geometry(geo, [105, 150])
    d = r.to_dict()
    assert list(d) == ["score", "lambda_min", "zero_modes", "n_vertices", "landmarks", "seconds"]
    assert d["landmarks"] == [105, 150] and d["n_vertices"] == g.n_vertices
    with pytest.raises(InputError):
        local_score_of_geometry(geo, [5])  # not a file id


def test_point_cloud_and_bad_landmarks_are_refused():
    g = bumpy_blob(1)
    with pytest.raises(InputError, match="mesh"):
        local_symmetry_score(g.vertices, None)
    with pytest.raises(InputError):
        local_score_of_geometry(make_geometry(g.vertices, None))
    with pytest.raises(InputError):
        local_symmetry_score(g.vertices, g.faces, landmarks=[g.n_vertices])

"""The deformation energy and its exact Hessian at P = 0 (against finite differences)."""

import numpy as np
import pytest

from shapecond.deformation.energy import (energy_value, hessian, mass_diagonal, mesh_edges,
                                          normalized_mesh, vertex_areas)
from shapecond.errors import InputError
from shapecond.shapes.synthetic import bumpy_blob, capped_cylinder, plane_patch


def _second_difference(V, F, alpha, energy, v, t):
    """v^T H v from E(tv) + E(-tv) (E(0) = 0), Richardson-extrapolated to remove the t^2 term."""
    q = lambda h: (energy_value(h * v, V, F, alpha, energy) + energy_value(-h * v, V, F, alpha, energy)) / h ** 2
    return (4.0 * q(t / 2) - q(t)) / 3.0


@pytest.mark.parametrize("energy", ["springs", "arap"])
@pytest.mark.parametrize("shape", ["blob", "cylinder"])
def test_hessian_matches_finite_differences(energy, shape):
    g = bumpy_blob(1) if shape == "blob" else capped_cylinder(sections=8, n_height=3, n_cap_rings=2)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    H = hessian(V, F, alpha=0.7, energy=energy)
    rng = np.random.default_rng(1)
    for _ in range(4):
        v, w = rng.normal(size=V.size), rng.normal(size=V.size)
        # quadratic form and (by polarisation) a bilinear form, relative to the energy scale
        qv = _second_difference(V, F, 0.7, energy, v, 1e-3)
        assert abs(qv - v @ H @ v) <= 1e-4 * abs(v @ H @ v)
        qpw = _second_difference(V, F, 0.7, energy, v + w, 1e-3)
        qmw = _second_difference(V, F, 0.7, energy, v - w, 1e-3)
        scale = np.sqrt((v @ H @ v) * (w @ H @ w))
        assert abs((qpw - qmw) / 4.0 - v @ H @ w) <= 1e-4 * scale


def test_single_vertex_blocks_by_finite_differences():
    """Every entry of the Hessian block of one vertex, one coordinate pair at a time."""
    g = bumpy_blob(1)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    H = hessian(V, F, alpha=1.3).toarray()
    for i in (0, 3 * 7 + 2):
        for j in range(3 * 5, 3 * 5 + 3):
            e_i, e_j = np.eye(V.size)[i], np.eye(V.size)[j]
            fd = (_second_difference(V, F, 1.3, "springs", e_i + e_j, 1e-3)
                  - _second_difference(V, F, 1.3, "springs", e_i - e_j, 1e-3)) / 4.0
            assert abs(fd - H[i, j]) <= 1e-4 * np.abs(H).max()


def test_hessian_symmetric_psd_and_rigid_null():
    g = bumpy_blob(2)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    for energy in ("springs", "arap"):
        H = hessian(V, F, alpha=1.0, energy=energy) - hessian(V, F, alpha=0.0)  # stretching only
        assert abs(H - H.T).max() < 1e-12
        ev = np.linalg.eigvalsh(H.toarray())
        assert ev.min() > -1e-9 * ev.max()
        # rigid motions cost no stretching
        t = np.tile([0.3, -0.2, 0.5], len(V))
        rot = np.cross([0.1, 0.7, -0.2], V).ravel()
        for f in (t, rot):
            assert f @ H @ f < 1e-10 * (f @ f) * ev.max()


def test_normalisation_and_areas():
    g = bumpy_blob(2)
    V, F, scale, c = normalized_mesh(3.0 * g.vertices + 5.0, g.faces)
    assert np.isclose(vertex_areas(V, F).sum(), 1.0)
    assert np.allclose((3.0 * g.vertices + 5.0 - c) * scale, V)
    assert np.allclose(mass_diagonal(V, F)[::3], vertex_areas(V, F))
    edges, w = mesh_edges(V, F)
    assert len(edges) == len(V) + len(F) - 2  # Euler: closed genus-0 surface
    assert np.all(w > 0)


def test_bad_inputs_raise_input_error():
    g = plane_patch(n=5)
    with pytest.raises(InputError):
        normalized_mesh(g.vertices, None)
    with pytest.raises(InputError):
        normalized_mesh(g.vertices, g.faces + 100)
    with pytest.raises(InputError):
        normalized_mesh(np.vstack([g.vertices, [[9.0, 9.0, 9.0]]]), g.faces)  # unreferenced vertex
    V = g.vertices.copy()
    V[1] = V[0]
    with pytest.raises(InputError):
        mesh_edges(V, g.faces)
    with pytest.raises(InputError):
        hessian(g.vertices, g.faces, energy="elastic")
    with pytest.raises(InputError):
        hessian(g.vertices, g.faces, alpha=float("nan"))

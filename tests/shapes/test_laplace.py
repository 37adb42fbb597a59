"""The Laplace–Beltrami basis against the sphere's closed-form spectrum, and its invariances."""

import numpy as np
import scipy.sparse as sp
import pytest

from shapecond.errors import InputError
from shapecond.shapes.validate import make_geometry
from shapecond.shapes.laplace import laplace_basis
from shapecond.shapes.synthetic import bumpy_blob, sphere


def test_sphere_spectrum_is_4pi_l_l_plus_1_on_area_one():
    # a sphere of area 1 has radius R = 1/sqrt(4π): λ = l(l+1)/R² = 4π l(l+1), multiplicity 2l + 1
    b = laplace_basis(sphere(subdivisions=3), k=16, cache=False)
    assert abs(b.evals[0]) < 1e-8
    np.testing.assert_allclose(b.evals[1:4], 8 * np.pi, rtol=0.01)
    np.testing.assert_allclose(b.evals[4:9], 24 * np.pi, rtol=0.02)
    np.testing.assert_allclose(b.evals[9:16], 48 * np.pi, rtol=0.03)
    assert b.mass.sum() == pytest.approx(1.0)


def test_eigenvectors_are_mass_orthonormal_and_the_basis_does_not_depend_on_the_unit():
    g = sphere(subdivisions=2)
    b = laplace_basis(g, k=12, cache=False)
    np.testing.assert_allclose(b.evecs.T @ (b.mass[:, None] * b.evecs), np.eye(12), atol=1e-8)
    big = laplace_basis(make_geometry(g.vertices * 1e4 + 3.0, g.faces), k=12, cache=False)
    np.testing.assert_allclose(big.evals, b.evals, rtol=1e-6, atol=1e-8)
    # eigenvalues 1..3 are one eigenspace: compare the projectors, not the vectors
    for lo, hi in ((0, 1), (1, 4), (4, 9)):
        P, Q = b.evecs[:, lo:hi], big.evecs[:, lo:hi]
        np.testing.assert_allclose(P @ P.T, Q @ Q.T, atol=1e-6)


def test_the_cache_returns_the_same_basis(tmp_path, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path))
    g = sphere(subdivisions=2)
    first = laplace_basis(g, k=8)
    assert list(tmp_path.glob("laplace-*.npz"))
    second = laplace_basis(g, k=8)
    np.testing.assert_array_equal(first.evecs, second.evecs)


def test_a_point_cloud_gets_a_basis_close_to_its_mesh():
    g = sphere(subdivisions=3)
    cloud = laplace_basis(make_geometry(g.vertices, None), k=4, cache=False)
    np.testing.assert_allclose(cloud.evals[1:4], 8 * np.pi, rtol=0.1)


def test_too_few_vertices_is_an_input_error():
    with pytest.raises(InputError, match="at least 4 vertices"):
        laplace_basis(make_geometry(np.eye(3), np.array([[0, 1, 2]])), cache=False)


def test_the_cholesky_route_and_the_lu_fallback_give_one_basis(monkeypatch):
    """The shifted operator's inverse through CHOLMOD, or scipy's LU where CHOLMOD refuses it: the
    same eigenvalues and, up to sign (fixed the same way), the same eigenvectors."""
    import shapecond.shapes.laplace as laplace
    from shapecond.cholesky import NotPositiveDefinite

    g = bumpy_blob(subdivisions=3)
    factors = []
    real = laplace.SparseCholesky
    monkeypatch.setattr(laplace, "SparseCholesky", lambda A: factors.append(real(A)) or factors[-1])
    chol = laplace.laplace_basis(g, k=30, cache=False)
    assert len(factors) == 1  # the Cholesky route was taken (no fallback)

    def refuse(A):
        raise NotPositiveDefinite("refused")

    monkeypatch.setattr(laplace, "SparseCholesky", refuse)
    lu = laplace.laplace_basis(g, k=30, cache=False)
    np.testing.assert_allclose(chol.evals, lu.evals, rtol=1e-7, atol=1e-9)
    overlap = np.abs(np.einsum("ij,ij->j", chol.evecs * chol.mass[:, None], lu.evecs))
    assert overlap[:20].min() > 1 - 1e-6  # (the last pairs may sit in a cluster the two orders split)


def test_the_block_lanczos_route_gives_arpacks_basis(monkeypatch):
    """The block Lanczos process (taken on a shape of 642 vertices for 30 pairs) against ARPACK's
    eigsh through the same factor: the same eigenvalues and the same span, pair by pair."""
    import shapecond.shapes.laplace as laplace

    g = bumpy_blob(subdivisions=3)
    calls = []
    real = laplace._block_lanczos
    monkeypatch.setattr(laplace, "_block_lanczos", lambda *a: calls.append(real(*a)) or calls[-1])
    block = laplace.laplace_basis(g, k=30, cache=False)
    assert len(calls) == 1 and calls[0] is not None  # the block route was taken and converged
    monkeypatch.setattr(laplace, "_block_lanczos", lambda *a: None)
    arpack = laplace.laplace_basis(g, k=30, cache=False)
    np.testing.assert_allclose(block.evals, arpack.evals, rtol=1e-7, atol=1e-9)
    cross = block.evecs.T @ (block.mass[:, None] * arpack.evecs)
    assert np.linalg.svd(cross, compute_uv=False).min() > 1 - 1e-7  # one 30-dimensional span
    assert np.abs(np.diag(cross))[:20].min() > 1 - 1e-6  # the same vectors, signs fixed the same way


def test_the_block_lanczos_gives_up_when_it_cannot_converge(monkeypatch):
    import shapecond.shapes.laplace as laplace

    g = bumpy_blob(subdivisions=3)
    reference = laplace.laplace_basis(g, k=30, cache=False)
    monkeypatch.setattr(laplace, "BLOCK_TOL", 0.0)  # no Ritz pair meets a zero tolerance in 4k columns
    L, mass = laplace.operators(g)
    factor = laplace.SparseCholesky((L - laplace.SHIFT * sp.diags(mass)).tocsc())
    assert laplace._block_lanczos(factor.solve, mass, 30) is None
    fallback = laplace.laplace_basis(g, k=30, cache=False)  # ARPACK then
    np.testing.assert_allclose(fallback.evals, reference.evals, rtol=1e-7, atol=1e-9)


def test_the_operators_are_built_once_per_geometry(monkeypatch):
    import shapecond.shapes.laplace as laplace

    built = []
    real = laplace._build_operators
    monkeypatch.setattr(laplace, "_build_operators", lambda g: built.append(g) or real(g))
    g = sphere(subdivisions=2)
    first = laplace.operators(g)
    assert laplace.operators(g) is first and len(built) == 1
    other = make_geometry(g.vertices * 2.0, g.faces)  # another geometry: its own operators
    L, mass = laplace.operators(other)
    assert len(built) == 2
    np.testing.assert_allclose(L.toarray(), first[0].toarray(), atol=1e-12)  # scale-free
    np.testing.assert_allclose(mass, first[1], atol=1e-15)


def test_the_block_lanczos_finds_eigenspaces_wider_than_its_block(monkeypatch):
    """On an icosphere the eigenspaces of the sphere's degree l have up to 2l + 1 dimensions (23 by
    the 150th pair), wider than the 8 columns of a block: none of ARPACK's eigenvalues is missed."""
    import shapecond.shapes.laplace as laplace

    g = sphere(subdivisions=4)
    calls = []
    real = laplace._block_lanczos
    monkeypatch.setattr(laplace, "_block_lanczos", lambda *a: calls.append(real(*a)) or calls[-1])
    block = laplace.laplace_basis(g, k=150, cache=False)
    assert len(calls) == 1 and calls[0] is not None
    monkeypatch.setattr(laplace, "_block_lanczos", lambda *a: None)
    arpack = laplace.laplace_basis(g, k=150, cache=False)
    np.testing.assert_allclose(block.evals, arpack.evals, rtol=1e-6, atol=1e-9)

"""Factorisation reuse for fixed vertices (deformation/solver.py)."""

import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from shapecond.deformation.energy import hessian, mass_diagonal, normalized_mesh
from shapecond.deformation.local_score import LocalProblem
from shapecond.deformation.solver import BACKENDS, ShiftInvertSolver, nested_dissection, vertex_graph
from shapecond.errors import InputError
from shapecond.shapes.synthetic import bumpy_blob, sphere


def test_nested_dissection_is_a_permutation():
    g = bumpy_blob(3)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    order = nested_dissection(V, vertex_graph(hessian(V, F)), leaf=8)
    assert np.array_equal(np.sort(order), np.arange(len(V)))


@pytest.mark.parametrize("backend", BACKENDS)
def test_bordered_solve_equals_solve_of_the_reduced_matrix(backend):
    g = bumpy_blob(2)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    H, m = hessian(V, F), mass_diagonal(V, F)
    S = ShiftInvertSolver(H, m, V, backend=backend)
    assert S.backend == backend
    fixed = [4, 50, 51]
    C = S.constrained(fixed)
    A = (H + sp.diags(S.shift * m)).tocsc()[C.free][:, C.free]
    b = np.random.default_rng(0).normal(size=len(C.free))
    x = C.solve_free(b)
    assert np.allclose(x, sla.spsolve(A.tocsc(), b), rtol=1e-8, atol=1e-10 * np.abs(x).max())
    n_before = S.n_solves
    S.constrained([4, 50])  # columns of A^{-1} for already-fixed vertices are cached
    assert S.n_solves == n_before


@pytest.mark.parametrize("energy", ["springs", "arap"])
def test_cholmod_and_superlu_give_the_same_spectrum(energy):
    g = bumpy_blob(3)
    a = LocalProblem(g.vertices, g.faces, energy=energy, backend="cholmod")
    b = LocalProblem(g.vertices, g.faces, energy=energy, backend="superlu")
    for fixed in ([], [3, 100, 400]):
        ra, rb = a.score(fixed), b.score(fixed)
        assert math.isfinite(ra.score)
        assert ra.score == pytest.approx(rb.score, rel=1e-8)
        assert np.allclose(ra.eigenvalues, rb.eigenvalues, rtol=1e-8)


def test_cholmod_keeps_the_sphere_zero_modes():
    g = sphere(3)
    r = LocalProblem(g.vertices, g.faces, backend="cholmod").score()
    assert r.score == math.inf and len(r.zero_modes) == 3


def test_block_solve_equals_column_solves():
    g = bumpy_blob(2)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    S = ShiftInvertSolver(hessian(V, F), mass_diagonal(V, F), V)
    B = np.random.default_rng(1).normal(size=(S.n_dof, 5))
    X = S.solve(B)
    assert np.allclose(X, np.column_stack([S.solve(B[:, k]) for k in range(5)]), rtol=1e-10, atol=1e-12)


def test_cholmod_is_used_unless_another_backend_is_asked_for():
    """Without ``backend=`` the solver and the local score factorise with CHOLMOD (the faster
    backend) when A is positive definite; an unknown backend is one InputError."""
    g = bumpy_blob(1)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    H, m = hessian(V, F), mass_diagonal(V, F)
    assert ShiftInvertSolver(H, m, V).backend == "cholmod"
    assert ShiftInvertSolver(H, m, V, backend="superlu").backend == "superlu"
    assert LocalProblem(g.vertices, g.faces).solver.backend == "cholmod"
    with pytest.raises(InputError, match="umfpack"):
        ShiftInvertSolver(H, m, V, backend="umfpack")


def test_not_positive_definite_falls_back_to_superlu():
    g = bumpy_blob(2)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    H, m = hessian(V, F), mass_diagonal(V, F)
    S = ShiftInvertSolver(H, m, V, shift=-0.5)  # A = H - 0.5 M is indefinite: CHOLMOD refuses it
    assert S.backend == "superlu"
    b = np.random.default_rng(2).normal(size=S.n_dof)
    assert np.allclose((H - 0.5 * sp.diags(m)) @ S.solve(b), b, atol=1e-8)

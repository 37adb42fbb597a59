"""Factorisation reuse for fixed vertices (deformation/solver.py)."""

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from shapecond.deformation.energy import hessian, mass_diagonal, normalized_mesh
from shapecond.deformation.solver import ShiftInvertSolver, nested_dissection, vertex_graph
from shapecond.shapes.synthetic import bumpy_blob


def test_nested_dissection_is_a_permutation():
    g = bumpy_blob(3)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    order = nested_dissection(V, vertex_graph(hessian(V, F)), leaf=8)
    assert np.array_equal(np.sort(order), np.arange(len(V)))


def test_bordered_solve_equals_solve_of_the_reduced_matrix():
    g = bumpy_blob(2)
    V, F, _, _ = normalized_mesh(g.vertices, g.faces)
    H, m = hessian(V, F), mass_diagonal(V, F)
    S = ShiftInvertSolver(H, m, V)
    fixed = [4, 50, 51]
    C = S.constrained(fixed)
    A = (H + sp.diags(S.shift * m)).tocsc()[C.free][:, C.free]
    b = np.random.default_rng(0).normal(size=len(C.free))
    x = C.solve_free(b)
    assert np.allclose(x, sla.spsolve(A.tocsc(), b), rtol=1e-8, atol=1e-10 * np.abs(x).max())
    n_before = S.n_solves
    S.constrained([4, 50])  # columns of A^{-1} for already-fixed vertices are cached
    assert S.n_solves == n_before

"""Heat-method geodesics in blocks (shapes.heat) and the intrinsic Delaunay cover (shapes.intrinsic)."""

import numpy as np
import potpourri3d as pp3d
import pytest

from shapecond.shapes import heat, synthetic
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.validate import make_geometry
from shapecond.shapes.intrinsic import DELAUNAY_EPS, intrinsic_delaunay_cover, tufted_cover
from shapecond.shapes.sampling import farthest_point_sampling


def _with_hole_and_flips(g, seed=0):
    """The mesh with the faces around a few vertices removed (boundary) and some faces wound backwards."""
    rng = np.random.default_rng(seed)
    F = g.faces[~np.isin(g.faces, rng.choice(g.n_vertices, 3, replace=False)).any(axis=1)]
    used = np.unique(F)
    remap = np.full(g.n_vertices, -1)
    remap[used] = np.arange(used.size)
    F = remap[F]
    flip = rng.random(F.shape[0]) < 0.1
    F[flip] = F[flip][:, ::-1]
    return make_geometry(g.vertices[used], F)


def _pp3d_rows(g, sources):
    solver = pp3d.MeshHeatMethodDistanceSolver(g.vertices, g.faces)
    return np.stack([np.maximum(solver.compute_distance(int(s)), 0.0) for s in sources])


@pytest.mark.parametrize("make", [lambda: synthetic.bumpy_blob(subdivisions=3),
                                  lambda: synthetic.plane_patch(n=25),
                                  lambda: _with_hole_and_flips(synthetic.bumpy_blob(subdivisions=3))])
def test_same_distances_as_potpourri3d(make):
    """The operators are potpourri3d's (tufted cover, mollification, flips, t): equal up to round-off."""
    g = make()
    sources = np.random.default_rng(1).choice(g.n_vertices, 7, replace=False)
    ours = DistanceSolver(g, "heat").distances(sources)
    ref = _pp3d_rows(g, sources)
    assert np.max(np.abs(ours - ref)) < 1e-6 * ref.max()


def test_block_size_does_not_change_rows(monkeypatch):
    g = synthetic.bumpy_blob(subdivisions=3)
    sources = np.arange(0, g.n_vertices, 97)
    tri = intrinsic_delaunay_cover(g.vertices, g.faces)
    blocked = heat.HeatMethod(tri, g.n_vertices).distances(sources)
    monkeypatch.setattr(heat, "BLOCK", 1)
    single = heat.HeatMethod(tri, g.n_vertices).distances(sources)
    assert np.allclose(blocked, single, rtol=0, atol=1e-9 * single.max())
    assert np.allclose(blocked[np.arange(sources.size), sources], 0.0, atol=1e-12)


def test_orientation_does_not_matter():
    g = synthetic.bumpy_blob(subdivisions=3)
    F = g.faces.copy()
    F[::3] = F[::3, ::-1]
    sources = [0, 50, 400]
    a = DistanceSolver(g, "heat").distances(sources)
    b = DistanceSolver(make_geometry(g.vertices, F), "heat").distances(sources)
    assert np.allclose(a, b, rtol=0, atol=1e-9 * a.max())


def test_cover_is_delaunay_and_keeps_the_area():
    g = _with_hole_and_flips(synthetic.bumpy_blob(subdivisions=3), seed=2)
    tri = intrinsic_delaunay_cover(g.vertices, g.faces)
    assert tri.faces.shape == (2 * g.faces.shape[0], 3)
    L, mass = heat.cotan_laplacian_and_mass(tri, g.n_vertices)
    area = 0.5 * np.linalg.norm(np.cross(g.vertices[g.faces[:, 1]] - g.vertices[g.faces[:, 0]],
                                         g.vertices[g.faces[:, 2]] - g.vertices[g.faces[:, 0]]), axis=1).sum()
    assert np.isclose(mass.sum(), 2 * area, rtol=1e-9)  # flips keep the area of each quad
    offdiag = L - np.diag(L.diagonal())
    assert offdiag.max() <= 2 * DELAUNAY_EPS  # Delaunay: no negative edge weight (L = -weights off the diagonal)
    assert np.allclose(np.asarray(L.sum(axis=1)).ravel(), 0.0, atol=1e-9)


def test_non_manifold_edge_falls_back_to_potpourri3d():
    g = synthetic.plane_patch(n=6)
    extra = np.array([[1, 7, g.n_vertices]])  # a third face on the interior edge (1, 7)
    V = np.vstack([g.vertices, [[0.1, 0.0, 0.5]]])
    F = np.vstack([g.faces, extra])
    assert tufted_cover(F, V.shape[0]) is None
    solver = DistanceSolver(make_geometry(V, F), "heat")
    assert solver.block == 1
    assert np.all(np.isfinite(solver.distances([0, 3])))


class _FixedRows:
    """A solver serving precomputed rows, so that which rows are solved together cannot matter."""

    def __init__(self, solver, block):
        self.n, self.block, self.guess = solver.n, block, solver.guess
        self.rows = solver.distances(np.arange(solver.n))
        self.asked = 0

    def distances(self, sources):
        self.asked += len(sources)
        return self.rows[np.asarray(sources)]


@pytest.mark.parametrize("symmetric", [False, True])
def test_sampling_ahead_gives_the_samples_of_one_at_a_time(symmetric):
    g = synthetic.animal(resolution=0.06)
    solver = DistanceSolver(g, "heat")
    assert solver.block > 1
    kw = dict(symmetry=g.symmetry if symmetric else None, stops=(20,), landmarks=[5, 77])
    ahead, single = _FixedRows(solver, solver.block), _FixedRows(solver, 1)
    a = farthest_point_sampling(ahead, 150, **kw)
    b = farthest_point_sampling(single, 150, **kw)
    for field in ("samples", "D", "min_dist", "nearest"):
        assert np.array_equal(getattr(a, field), getattr(b, field))
    assert single.asked == 150 and ahead.asked < 1.5 * single.asked  # one row per sample; few wasted guesses

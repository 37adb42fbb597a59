"""The dense stage: nearest rows, functional maps, and ZoomOut recovering known maps."""

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.matching.zoomout import Anchors, ZoomOutOptions, farthest_points, functional_map, nearest_rows, zoomout
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.laplace import laplace_basis
from shapecond.shapes.synthetic import bumpy_blob
from shapecond.shapes.validate import make_geometry


def test_nearest_rows_is_the_brute_force_argmin():
    rng = np.random.default_rng(0)
    for n, m, d in ((50, 70, 3), (300, 2500, 40)):  # more rows than one block too
        X, Y = rng.normal(size=(n, d)), rng.normal(size=(m, d))
        brute = np.argmin(((X[:, None, :] - Y[None, :, :]) ** 2).sum(-1), axis=1)
        got = nearest_rows(X, Y)
        # float32 products may swap two near-equal candidates: the chosen one is as near
        dist = lambda idx: ((X - Y[idx]) ** 2).sum(1)  # noqa: E731
        np.testing.assert_allclose(dist(got), dist(brute), rtol=1e-4, atol=1e-5)


def test_nearest_rows_in_small_score_blocks_is_the_same_map(monkeypatch):
    """Large targets (and large search regions) get fewer source rows per block of scores
    (``SCORE_BYTES``): the same nearest rows (a block changes only the products' round-off, which
    may swap near-equal candidates on real shapes), exact ties to the lowest index in every block."""
    from shapecond.matching import zoomout as Z

    rng = np.random.default_rng(1)
    X, Y = rng.normal(size=(700, 30)), rng.normal(size=(900, 30))
    Y[5] = Y[2]  # a tie: the lowest index wins in every block
    X[:3] = Y[2]
    cell = rng.integers(0, 4, size=700)
    regions = [np.sort(rng.choice(900, size=300, replace=False)) for _ in range(4)]
    regions[int(cell[0])] = np.union1d(regions[int(cell[0])], [2, 5])
    whole, in_regions = nearest_rows(X, Y), Z._nearest_in_regions(X, Y, cell, regions)
    assert list(whole[:3]) == [2, 2, 2] and in_regions[0] == 2
    assert all(in_regions[i] in regions[c] for i, c in enumerate(cell))
    for budget in (1, 4 * 900 * 7, 4 * 900 * 9):  # blocks of 1, of 7 rows, of 9 (a shorter last one)
        monkeypatch.setattr(Z, "SCORE_BYTES", budget)
        assert np.array_equal(nearest_rows(X, Y), whole)
        assert np.array_equal(Z._nearest_in_regions(X, Y, cell, regions), in_regions)


def test_functional_map_of_the_identity_is_the_identity_matrix():
    b = laplace_basis(bumpy_blob(subdivisions=3), k=20, cache=False)
    C = functional_map(b.evecs, b.mass, b.evecs)
    np.testing.assert_allclose(C, np.eye(20), atol=1e-8)


@pytest.fixture(scope="module")
def blob():
    g = bumpy_blob(subdivisions=3)  # no symmetry: the identity is the only good self-map
    return g, laplace_basis(g, k=60, cache=False)


def _neighbour_map(g, seed):
    """Every vertex sent to a random vertex of its 1-ring: a noisy start near the identity."""
    rng = np.random.default_rng(seed)
    nbrs = [[] for _ in range(g.n_vertices)]
    for a, b_, c in g.faces:
        nbrs[a] += [b_, c]
        nbrs[b_] += [a, c]
        nbrs[c] += [a, b_]
    return np.array([rng.choice(n) for n in nbrs])


def test_zoomout_recovers_the_identity_from_a_noisy_start_and_keeps_the_landmarks(blob):
    g, b = blob
    start = _neighbour_map(g, 0)
    assert np.mean(start == np.arange(g.n_vertices)) == 0.0
    lm = np.array([0, 100, 400])
    rows = DistanceSolver(g).distances(lm)
    anchors = Anchors(lm, lm, rows, rows)
    T = zoomout(b, b, (g.vertices, g.vertices), start, anchors, ZoomOutOptions(k_start=10, step=10))
    assert np.mean(T == np.arange(g.n_vertices)) > 0.95
    np.testing.assert_array_equal(T[lm], lm)
    again = zoomout(b, b, (g.vertices, g.vertices), start, anchors, ZoomOutOptions(k_start=10, step=10))
    np.testing.assert_array_equal(T, again)  # deterministic


def test_anchors_pull_the_map_to_the_landmarks(blob):
    g, b = blob
    # a start far from the identity everywhere: every vertex sent to vertex 0
    start = np.zeros(g.n_vertices, dtype=np.int64)
    lm = np.array([0, 150, 300, 450, 600])
    rows = DistanceSolver(g).distances(lm)
    plain = zoomout(b, b, (g.vertices, g.vertices), start, None, ZoomOutOptions(k_start=10, step=10))
    anchored = zoomout(b, b, (g.vertices, g.vertices), start, Anchors(lm, lm, rows, rows), ZoomOutOptions(k_start=10, step=10))
    assert np.mean(anchored == np.arange(g.n_vertices)) > np.mean(plain == np.arange(g.n_vertices)) + 0.2


def test_a_map_that_does_not_fit_is_an_input_error(blob):
    g, b = blob
    with pytest.raises(InputError, match="does not fit"):
        zoomout(b, b, (g.vertices, g.vertices), np.zeros(5, dtype=np.int64))
    with pytest.raises(InputError, match="k_start"):
        ZoomOutOptions(k_start=0).levels(50)


@pytest.mark.slow
def test_the_zoomout_matcher_keeps_the_least_distorted_of_its_starts(blob, monkeypatch):
    """With more than 3 landmarks it also starts from the first 3 landmarks' descriptions and keeps the map
    that distorts the sample distances less: a start spoiled by the extra landmarks costs nothing."""
    from shapecond.matching import pipeline
    from shapecond.matching.pipeline import MatchOptions, _least_distorted, match_landmarks_only

    g, _ = blob
    opts = MatchOptions(matcher="zoomout", n_points=60)  # the blob's Laplace basis once, from the session cache
    right, scrambled = np.arange(g.n_vertices), np.random.default_rng(0).permutation(g.n_vertices)
    lm = np.array([0, 100, 400, 250, 600])
    assert _least_distorted(g, g, [scrambled, right], lm, opts, None)[0] == 1
    assert _least_distorted(g, g, [right, scrambled], lm, opts, None)[0] == 0
    assert _least_distorted(g, g, [scrambled], lm, opts, None) == (0, None)  # one start: nothing to compare
    real = pipeline.nearest_rows

    def spoiled(X, Y):  # the description by every landmark goes wrong (3 distances and 3 sides: 6 columns)
        return np.roll(real(X, Y), 17) if X.shape[1] > 6 else real(X, Y)
    monkeypatch.setattr(pipeline, "nearest_rows", spoiled)
    # the dense stage passes its start through: the whitened anchors would repair the spoiled start on
    # this blob, and what is tested here is the choice between the two maps
    monkeypatch.setattr(pipeline, "dense_stage", lambda sg, tg, initial, anchors, options: initial)
    m = match_landmarks_only(g, g, lm, lm, opts)
    assert m.info["start"] == "the first 3 landmarks" and np.mean(m.vertex_map == right) > 0.9
    assert np.array_equal(m.source.samples[:5], lm) and m.source.n_samples == 60   # what the error bar reuses
    three = match_landmarks_only(g, g, lm[:3], lm[:3], opts)
    assert three.info["start"] == "every landmark" and three.source is None


@pytest.mark.parametrize("decimals", [None, 1])
def test_farthest_points_are_the_vectorised_definitions(decimals):
    # the compiled loop must pick exactly the points of the numpy one, ties (rounded points) included
    P = np.random.default_rng(3).standard_normal((1500, 3)) * 40.0
    P = P if decimals is None else np.round(P / 40.0, decimals)
    want, d = [0], np.linalg.norm(P - P[0], axis=1)
    for _ in range(1, 300):
        want.append(int(np.argmax(d)))
        np.minimum(d, np.linalg.norm(P - P[want[-1]], axis=1), out=d)
    np.testing.assert_array_equal(farthest_points(P, 300), want)
    np.testing.assert_array_equal(farthest_points(P[:5], 9), np.arange(5))


def test_the_final_pass_searched_in_cell_regions_finds_what_the_full_search_finds():
    """A deformed copy (a non-rigid bend: a different basis, the identity the true map) refined from a
    noisy start: the final pass's regions give the full search's map on (nearly) every vertex."""
    from shapecond.matching import zoomout as Z

    g = bumpy_blob(subdivisions=4)
    V = g.vertices.copy()
    V[:, 2] += 0.3 * V[:, 0] ** 2  # bend
    h = make_geometry(V, g.faces)
    bg, bh = laplace_basis(g, k=60, cache=False), laplace_basis(h, k=60, cache=False)
    start = _neighbour_map(g, 1)
    opts = ZoomOutOptions(k_start=10, step=10)
    regions = zoomout(bg, bh, (g.vertices, h.vertices), start, None, opts)
    shipped = Z._nearest_in_regions
    Z._nearest_in_regions = lambda X, Y, cell, regions: Z.nearest_rows(X, Y)
    try:
        full = zoomout(bg, bh, (g.vertices, h.vertices), start, None, opts)
    finally:
        Z._nearest_in_regions = shipped
    assert np.mean(regions == full) > 0.995
    error = np.linalg.norm(g.vertices[full] - g.vertices, axis=1)  # the true map is the identity
    assert error.mean() < 0.05 * np.ptp(g.vertices, axis=0).max()  # the comparison is of good maps (4 %)


def test_a_collapsed_map_still_searches_a_cell_worth_of_target_vertices():
    from shapecond.matching.zoomout import CELL_NEIGHBOURS, _search_regions

    g = bumpy_blob(subdivisions=3)
    S = farthest_points(g.vertices, 40)
    regions = _search_regions(g.vertices[S], g.vertices, np.zeros(S.size, dtype=np.int64))
    need = -(-(CELL_NEIGHBOURS + 1) * g.n_vertices // S.size)
    assert all(r.size >= need and 0 in r for r in regions)
    spread = _search_regions(g.vertices[S], g.vertices, S)  # the identity: each region holds its cell
    assert all(s in r for s, r in zip(S, spread))

"""Dense maps end to end on a bent copy with known correspondence; error metrics."""

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.matching.metrics import cumulative_curve, errors_from_rows, normalise, summary
from shapecond.matching.pipeline import MatchOptions
from shapecond.matching.problem import match_shapes
from shapecond.matching.sampled import insert_landmarks, sample_surface
from shapecond.shapes.validate import make_geometry
from shapecond.shapes.synthetic import plane_patch

W, H = 1.0, 0.55  # a rectangle: 3 non-collinear landmarks remove its symmetries


def _patch(n, bend_radius=None, seed=None):
    """A W x H grid; optionally bent onto a cylinder (an isometry) and its vertices shuffled.

    Returns the geometry and the flat (u, v) coordinates of its vertices.
    """
    g = plane_patch(n=n, size=1.0)
    uv = g.vertices[:, :2] * [W, H]
    if bend_radius is None:
        V = np.column_stack([uv, np.zeros(len(uv))])
    else:
        th = uv[:, 0] / bend_radius
        V = np.column_stack([bend_radius * np.sin(th), uv[:, 1], bend_radius * (1 - np.cos(th))])
    faces = g.faces
    if seed is not None:
        perm = np.random.default_rng(seed).permutation(len(V))  # new vertex j = old perm[j]
        V, uv, faces = V[perm], uv[perm], np.argsort(perm)[faces]
    return make_geometry(V, faces, name="patch"), uv


def _nearest(uv_from, uv_to, idx):
    return np.array([int(np.argmin(np.linalg.norm(uv_to - uv_from[i], axis=1))) for i in idx])


@pytest.fixture(scope="module")
def pair():
    src, uv_s = _patch(31)
    tgt, uv_t = _patch(41, bend_radius=0.35, seed=3)  # another resolution, bent, shuffled
    ls = np.array([0, 30, 31 * 20 + 12])               # two corners and an inner point
    lt = _nearest(uv_s, uv_t, ls)
    return src, uv_s, tgt, uv_t, ls, lt


@pytest.fixture(scope="module")
def matched(pair):
    """``matched(matcher, dense)``: the pair's match with these settings, computed once for the tests
    below (several of them check the same match); the Laplace bases come from the session's cache."""
    src, _, tgt, _, ls, lt = pair
    done = {}

    def get(matcher, dense):
        if (matcher, dense) not in done:
            done[matcher, dense] = match_shapes(src, tgt, ls, lt, MatchOptions(matcher=matcher, n_points=120,
                                                                               dense=dense))
        return done[matcher, dense]
    return get


@pytest.mark.parametrize("matcher, dense", [pytest.param("lh05", "zoomout", marks=pytest.mark.slow),
                                           pytest.param("faq", "zoomout", marks=pytest.mark.slow),
                                           pytest.param("zoomout", "zoomout", marks=pytest.mark.slow),
                                           ("lh05", "distances"), ("faq", "nearest")])
def test_bent_copy_is_matched_end_to_end(pair, matched, matcher, dense):
    src, uv_s, tgt, uv_t, ls, lt = pair
    m = matched(matcher, dense)
    assert m.vertex_map.shape == (src.n_vertices,)
    assert list(m.vertex_map[ls]) == list(lt)
    err = np.linalg.norm(uv_t[m.vertex_map] - uv_s, axis=1)   # geodesic = flat distance
    spacing = np.sqrt(W * H / 120)
    assert err.mean() < 1.0 * spacing, (matcher, dense, err.mean() / spacing)
    # the mirror map u -> W - u (the ambiguity landmarks remove) is far from it
    flipped = np.linalg.norm(uv_t[m.vertex_map] - (uv_s * [-1, 1] + [W, 0]), axis=1)
    assert flipped.mean() > 3 * err.mean()


def test_zoomout_beats_the_distance_extension_which_beats_nearest_sample(pair, matched):
    src, uv_s, tgt, uv_t, ls, lt = pair
    errs = {}
    for dense in ("nearest", "distances", "zoomout"):
        m = matched("faq", dense)
        errs[dense] = np.linalg.norm(uv_t[m.vertex_map] - uv_s, axis=1).mean()
    assert errs["zoomout"] < errs["distances"] < errs["nearest"], errs


def test_the_distance_extension_is_the_cost_formula_argmin(pair):
    """Each source vertex goes to the target vertex of its cell's candidates with the least
    ``(|a|² + |b|²) − 2 a·b`` over the anchors' distances, computed in that order, first on ties."""
    from shapecond.matching import dense
    from shapecond.matching.seeded import FAQOptions, faq_match

    src, _, tgt, _, ls, lt = pair
    s, ils = insert_landmarks(sample_surface(src, 60, cache=False), ls)
    t, ilt = insert_landmarks(sample_surface(tgt, 60, cache=False), lt)
    sm = faq_match(s.D, t.D, ils, ilt, FAQOptions())
    near_s, near_t = np.argmin(s.rows, axis=0), np.argmin(t.rows, axis=0)
    assert np.array_equal(s.nearest, near_s) and np.array_equal(t.nearest, near_t)
    anchors = np.argsort(s.D, axis=1, kind="stable")[:, :8]
    expected = np.empty(src.n_vertices, dtype=np.int64)
    for v in range(src.n_vertices):
        A = anchors[near_s[v]]
        W = np.concatenate([np.flatnonzero(near_t == j) for j in sm.t[A]])
        a = s.rows[A, v].astype(np.float64)[:, None] / s.unit
        b = t.rows[np.ix_(sm.t[A], W)].astype(np.float64) / t.unit
        expected[v] = W[np.argmin((a * a).sum(0)[:, None] + (b * b).sum(0)[None, :] - 2.0 * (a.T @ b), axis=1)[0]]
    assert np.array_equal(dense.dense_map(s, t, sm.t), expected)


def test_bad_pairs_are_input_errors(pair):
    src, _, tgt, _, ls, lt = pair
    with pytest.raises(InputError, match="counts differ"):
        match_shapes(src, tgt, ls, lt[:2], MatchOptions(n_points=50))
    with pytest.raises(InputError, match="out of range"):
        match_shapes(src, tgt, ls, [0, 1, 10**6], MatchOptions(n_points=50))
    with pytest.raises(InputError, match="unknown matcher"):
        MatchOptions(matcher="nope")
    with pytest.raises(InputError, match="at least 3 landmark"):
        match_shapes(src, tgt, ls[:2], lt[:2], MatchOptions(matcher="zoomout"))


def test_insert_landmarks_keeps_n_and_puts_landmarks_first(pair):
    src = pair[0]
    surf = sample_surface(src, 40, cache=False)
    lm = [5, int(surf.samples[7]), 600]
    out, idx = insert_landmarks(surf, lm)
    assert out.n_samples == 40 and list(out.samples[:3]) == lm and list(idx) == [0, 1, 2]
    assert np.unique(out.samples).size == 40
    # rows follow their samples: distance of each sample to itself is 0
    assert np.allclose(out.rows[np.arange(40), out.samples], 0.0)


def test_insert_landmarks_shares_the_rows_when_the_landmarks_are_already_first(pair):
    """sample_surface puts the landmarks first: inserting them again copies no row (the match keeps both
    surfaces), and a surface whose rows change is a new one, the original untouched."""
    src = pair[0]
    surf = sample_surface(src, 40, landmarks=[5, 600], cache=False)
    same, idx = insert_landmarks(surf, [5, 600])
    assert same.rows is surf.rows and np.array_equal(same.samples, surf.samples) and list(idx) == [0, 1]
    before = surf.rows.copy()
    moved, _ = insert_landmarks(surf, [600, 7])
    assert list(moved.samples[:2]) == [600, 7] and not np.shares_memory(moved.rows, surf.rows)
    assert np.array_equal(surf.rows, before)


def test_errors_from_rows_and_normalisations():
    rows = np.array([[0.0, 2.0, 4.0], [1.0, 0.0, 3.0]])
    e = errors_from_rows(rows, [2, 0])
    assert list(e) == [4.0, 1.0]
    assert list(normalise(e, diameter=8.0)) == [100.0, 25.0]
    assert np.allclose(normalise(e, 8.0, area=4.0, normalisation="sqrt_area"), [2.0, 0.5])
    with pytest.raises(InputError):
        normalise(e, 8.0, normalisation="sqrt_area")
    with pytest.raises(InputError):
        errors_from_rows(rows, [0, 5])


def test_cumulative_curve_against_brute_force():
    rng = np.random.default_rng(0)
    e = rng.exponential(size=57)
    th = np.linspace(0, 4, 23)
    want = [np.mean(e <= x) for x in th]
    assert np.allclose(cumulative_curve(e, th), want)
    assert summary(e)["mean"] == pytest.approx(e.mean())
    with pytest.raises(InputError):
        summary([])

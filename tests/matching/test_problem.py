"""``MatchProblem``: one pair, its landmark pairs checked once, every stage computed once and kept."""

import numpy as np
import pytest

import shapecond as sc
from shapecond.errors import InputError
from shapecond.matching import pipeline
from shapecond.matching import problem as P
from shapecond.matching.error_bar import bar_surface
from shapecond.matching.pipeline import MatchOptions
from shapecond.matching.problem import MatchProblem
from shapecond.viz import pages

SHAPE = "demo:animal:resolution=0.08"  # 942 vertices
LM = [0, 100, 200, 300]


@pytest.fixture(scope="module")
def pair():
    return sc.load(SHAPE), sc.load("demo:animal:resolution=0.08,delta=0.05")


@pytest.fixture
def samplings(monkeypatch):
    """Every call of ``sample_surface`` made by the problem or the zoomout matcher, by number of samples."""
    calls = []
    real = P.sample_surface

    def counted(geometry, n_points, *args, **kwargs):
        calls.append(n_points)
        return real(geometry, n_points, *args, **kwargs)
    monkeypatch.setattr(P, "sample_surface", counted)
    monkeypatch.setattr(pipeline, "sample_surface", counted)
    return calls


@pytest.mark.parametrize("ls, lt, options, needle", [
    ([0, 1, 2], [0, 1], MatchOptions(), "landmark counts differ"),
    ([0, 1, 5000], [0, 1, 2], MatchOptions(), "source landmark 5000 is out of range"),
    ([0, 1, 2], [0, 2, 2], MatchOptions(), "target landmarks contain repeated ids"),
    ([0, 1], [0, 1], MatchOptions(matcher="zoomout"), "at least 3 landmark pairs"),
    ([0, 1, 2], [0, 1, 3], MatchOptions(samples="same-ids"), "must be the source's vertex ids"),
    ([0, 1, 2], [0, 1, 2], MatchOptions(n_points=5000), "5000 samples requested"),
    (list(range(50)), list(range(50)), MatchOptions(n_points=40), "50 landmarks but only 40 samples"),
])
def test_a_bad_landmark_pair_is_refused_by_the_constructor_before_any_work(pair, samplings, ls, lt, options,
                                                                           needle):
    with pytest.raises(InputError, match=needle):
        MatchProblem(*pair, ls, lt, options)
    assert samplings == []


def test_the_landmark_pair_is_checked_once_per_match(pair, monkeypatch):
    checks = []
    real = P.check_landmarks
    monkeypatch.setattr(P, "check_landmarks", lambda *a: checks.append(a) or real(*a))
    r = sc.match(*pair, LM, LM, n_points=40, dense="nearest", cache=False, suggest=1)
    assert len(checks) == 1 and r.summary["suggestions"]


@pytest.mark.parametrize("matcher, landmarks, sampled", [
    ("faq", LM, [40, 40]),           # both shapes, once each
    pytest.param("zoomout", LM, [40], marks=pytest.mark.slow),  # the source, where its two starts are compared
    ("zoomout", LM[:3], [40]),       # one start: the source sampled once, for the bar
])
def test_the_bar_and_the_suggestions_read_the_samples_the_problem_holds(pair, samplings, matcher, landmarks,
                                                                        sampled):
    p = MatchProblem(*pair, landmarks, landmarks, MatchOptions(matcher=matcher, n_points=40, dense="nearest"
                                                               if matcher != "zoomout" else "zoomout", cache=False))
    p.dense_match
    bar, doubt, eps, (first,) = p.error_bar, p.doubt, p.epsilon_hat, p.suggest(1)
    assert samplings == sampled
    assert eps == bar.epsilon_hat and doubt.shape == (pair[0].n_vertices,)
    coarse = bar_surface(p.source, len(landmarks))
    assert np.array_equal(doubt, bar.doubt[coarse.nearest])  # each vertex takes its nearest bar sample's doubt
    assert np.array_equal(p.source.samples[:len(landmarks)], landmarks)   # the held samples, landmarks first
    assert bar.n_samples == p.source.n_samples and first.vertex in p.source.samples


def test_results_are_computed_once_and_kept(pair, monkeypatch):
    p = MatchProblem(*pair, LM, LM, MatchOptions(matcher="lh05", n_points=40, dense="nearest", cache=False))
    calls = {"match": 0, "bar": 0, "suggest": 0, "truth": 0}

    def counting(name, f):
        def wrapped(*a, **kw):
            calls[name] += 1
            return f(*a, **kw)
        return wrapped
    monkeypatch.setattr(P, "match_samples", counting("match", P.match_samples))
    monkeypatch.setattr(P, "bar_and_samples", counting("bar", P.bar_and_samples))
    monkeypatch.setattr(P, "suggest_landmarks", counting("suggest", P.suggest_landmarks))
    monkeypatch.setattr(P, "_truth_raw", counting("truth", P._truth_raw))
    truth = np.arange(pair[0].n_vertices)
    for _ in range(2):
        assert p.dense_match is p.dense_match and p.sample_map is p.dense_match.sample_map
        assert p.error_bar is p.error_bar and p.doubt is p.doubt
        assert p.suggest(2) is p.suggest(2)
        assert np.array_equal(p.truth_errors(truth)[0], p.truth_errors(truth.copy())[0])
        assert p.truth_summary(truth) == p.truth_summary(truth)
    assert calls == {"match": 1, "bar": 1, "suggest": 1, "truth": 1}
    err, samples = p.truth_errors(truth)
    assert samples.size == P.TRUTH_SAMPLES and np.all(err >= 0) and err.max() > 0


def test_the_truth_summary_is_the_geodesic_error_in_both_units(pair):
    """Against the geodesic distance from each sample's image to its true image, computed here."""
    from shapecond.matching.sampled import surface_unit
    from shapecond.shapes.geodesics import DistanceSolver

    p = MatchProblem(*pair, LM, LM, MatchOptions(matcher="faq", n_points=40, dense="nearest", cache=False))
    truth = np.roll(np.arange(pair[0].n_vertices), 7)  # a wrong "truth": large, known errors
    s = p.truth_summary(truth)
    _, samples = p.truth_errors(truth)
    rows = DistanceSolver(pair[1], "heat").distances(truth[samples])
    raw = rows[np.arange(samples.size), p.vertex_map[samples]]
    unit = surface_unit(pair[1], float(rows.max()))
    assert s["n_points"] == samples.size and s["unit"] == "sqrt(area)"
    assert np.isclose(s["mean"], raw.mean() / unit) and np.isclose(s["worst"], raw.max() / unit)
    assert np.isclose(s["mean_percent_half_diameter"], 100 * raw.mean() / (0.5 * rows.max()))
    assert s["within_0.05"] == np.mean(raw / unit <= 0.05) < 1
    exact = p.truth_summary(p.vertex_map)  # the map itself as the truth: no error
    assert exact["mean"] == exact["worst"] == 0.0 and exact["within_0.05"] == 1.0


def test_a_point_cloud_truth_summary_is_in_diameters(pair):
    from shapecond.shapes.validate import make_geometry

    clouds = [make_geometry(g.vertices, None, g.name) for g in pair]
    p = MatchProblem(*clouds, LM, LM, MatchOptions(matcher="faq", n_points=40, dense="nearest", cache=False))
    s = p.truth_summary(np.arange(clouds[0].n_vertices))
    assert s["unit"] == "diameter" and 0 <= s["mean"] <= s["worst"] < 1


def test_the_sides_of_the_landmark_pairs_are_computed_once_for_both_stages(pair, monkeypatch):
    """The sample matcher reads the landmark pairs' sides at the samples, the dense stage's anchors at
    every vertex: one ``orientation_features`` call per shape, and the anchors hold those sides."""
    from shapecond.matching import zoomout

    computed, anchored = [], []
    real = pipeline.orientation_features
    monkeypatch.setattr(pipeline, "orientation_features", lambda g, rows: computed.append(g) or real(g, rows))
    monkeypatch.setattr(zoomout, "orientation_features", None)  # the anchors must not compute them again
    real_zoomout = pipeline.zoomout
    monkeypatch.setattr(pipeline, "zoomout", lambda *a: anchored.append(a[4]) or real_zoomout(*a))
    p = MatchProblem(*pair, LM, LM, MatchOptions(n_points=40, cache=False))
    assert p.vertex_map.shape == (pair[0].n_vertices,)
    assert computed == [pair[0], pair[1]]
    assert anchored[0].source_sides is p._sides[0] and anchored[0].target_sides is p._sides[1]


def test_the_match_page_draws_the_errors_its_problem_computed(pair, tmp_path, monkeypatch):
    r = sc.match(*pair, LM, LM, n_points=40, dense="nearest", cache=False)
    assert isinstance(r.problem, MatchProblem) and r.advice == r.problem.suggest

    def no_work(*a, **kw):
        raise AssertionError("the page computed the errors itself")
    monkeypatch.setattr(pages, "truth_errors", no_work)
    r.to_html(tmp_path / "a.html", truth="same-ids")
    r.to_html(tmp_path / "b.html", truth="same-ids")
    assert len(r.problem._truth_errors) == 1  # one truth, its errors computed once
    errors = r.truth_errors("same-ids")  # the same errors, in the summary
    assert r.summary["truth"] is errors and len(r.problem._truth_errors) == 1 and errors["mean"] >= 0
    with pytest.raises(InputError, match="one target vertex id per source vertex id"):
        r.truth_errors(np.zeros(3, dtype=np.int64))  # not one id per source id
    assert (tmp_path / "a.html").read_bytes() == (tmp_path / "b.html").read_bytes()


def test_same_ids_samples_know_the_true_sample_map(pair):
    p = MatchProblem(*pair, LM[:3], LM[:3], MatchOptions(matcher="faq", n_points=40, samples="same-ids",
                                                        dense="nearest", cache=False))
    truth = p.sample_truth
    assert np.array_equal(p.target.samples[truth], p.source.samples)   # carried by vertex id, shuffled
    assert not np.array_equal(truth, np.arange(40))
    info = p.dense_match.info
    assert info["exact"] == np.mean(p.sample_map.t == truth) and info["sample_error"] >= 0
    with pytest.raises(InputError, match="same-ids"):
        MatchProblem(*pair, LM[:3], LM[:3], MatchOptions(n_points=40, cache=False)).sample_map_errors

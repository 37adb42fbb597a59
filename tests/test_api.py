"""``import shapecond as sc``: one API for every input form, JSON-ready results, the README example."""

import functools
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

import shapecond as sc
from shapecond.matching.sampled import sample_surface
from shapecond.errors import InputError
from shapecond.shapes.io import write_mesh

README = Path(__file__).resolve().parents[1] / "README.md"


def _readme_example() -> str:
    text = README.read_text()
    section = text[text.index("## Python API"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.fixture(scope="module")
def readme_shape(tmp_path_factory):
    """The README example's shape as a file, and its score read from that file (the reference of every
    input form below, computed once)."""
    g = sc.load("demo:animal:delta=0.2,resolution=0.06")
    path = tmp_path_factory.mktemp("readme") / "animal.off"
    write_mesh(path, g.vertices, g.faces)
    return g, path, sc.score(str(path), n_points=24)


@pytest.mark.parametrize("form", ["path", "trimesh", "(V, F)"])
def test_readme_example_runs_on_a_path_a_trimesh_and_arrays(readme_shape, form):
    g, path, ref = readme_shape
    shapes = {"path": str(path), "trimesh": trimesh.Trimesh(g.vertices, g.faces, process=False),
              "(V, F)": (g.vertices, g.faces)}
    code = _readme_example().replace('"cat0.off"', "SHAPE").replace("n_points=400", "n_points=24")
    scope = {"SHAPE": shapes[form], "print": lambda *a: None}
    exec(compile(code, "README.md", "exec"), scope)
    result, marks = scope["result"], scope["marks"]
    assert result.verdict and result.sigma[0] > 0 and len(marks.landmarks) == 5
    assert all(0 <= v < g.n_vertices for v in marks.landmarks)
    assert result.sigma == ref.sigma and np.array_equal(result.witness_ids, ref.witness_ids)


NON_SYMMETRIC = np.array([[0, 1, 2, 1.5], [1, 0, 1, 1], [2.5, 1, 0, 1], [1.5, 1, 1, 0]])
NEGATIVE = -(np.ones((5, 5)) - np.eye(5))


def _low_level():
    from shapecond.selection.cnbs import heat_map
    from shapecond.symmetry.condition import kappa_probes
    from shapecond.symmetry.exact import exact_sigma
    from shapecond.symmetry.paper_bound import paper_eigen_diagnostic
    from shapecond.symmetry.relax import lp_upper_bound
    from shapecond.symmetry.score import symmetry_score
    from shapecond.symmetry.search import best_single_swap, witness_search

    return {"symmetry_score": symmetry_score, "witness_search": witness_search, "exact_sigma": exact_sigma,
            "lp_upper_bound": lp_upper_bound, "kappa_probes": kappa_probes, "heat_map": heat_map,
            "best_single_swap": best_single_swap, "paper_eigen_diagnostic": paper_eigen_diagnostic}


@pytest.mark.parametrize("bad", [NON_SYMMETRIC, NEGATIVE], ids=["non-symmetric", "negative"])
def test_no_function_returns_a_number_for_an_invalid_matrix(bad):
    calls = {name: (lambda f=f: f(bad)) for name, f in _low_level().items()}
    calls.update({
        "load": lambda: sc.load(bad), "metric_shape": lambda: sc.metric_shape(bad),
        "score": lambda: sc.score(bad), "local_score": lambda: sc.local_score(bad),
        "landmarks": lambda: sc.landmarks(bad, 1, "fps"), "heatmap": lambda: sc.heatmap(bad),
        "match": lambda: sc.match(bad, bad, [0], [0]), "SymmetryProblem": lambda: sc.SymmetryProblem(bad),
        "deformation_level": lambda: sc.deformation_level(bad, bad),
    })
    for name, call in calls.items():
        with pytest.raises(InputError) as info:
            call()
        assert str(info.value) and "\n" not in str(info.value), name


@pytest.mark.slow
def test_every_function_takes_a_trimesh_a_tuple_and_a_mesh_with_an_unreferenced_vertex():
    g = sc.load("demo:sphere:subdivisions=2")
    V = np.vstack([[[9.0, 9.0, 9.0]], g.vertices])  # row 0 is referenced by no face
    F = g.faces + 1
    forms = {"tuple": (V, F), "trimesh": trimesh.Trimesh(V, F, process=False)}
    for name, x in forms.items():
        loaded = sc.load(x)
        assert loaded.n_vertices == g.n_vertices and loaded.ids[0] == 1, name
        res = sc.score(x, 12, cache=False)
        assert res.sigma == (np.inf, np.inf) and 0 not in set(res.witness_ids)
        lm = sc.landmarks(x, 2, "fps", 12, cache=False)
        assert 0 not in lm.landmarks and all(1 <= v <= g.n_vertices for v in lm.landmarks)
        loc = sc.local_score(x, [1, 2])
        assert loc.landmarks == (1, 2)
        hm = sc.heatmap(x, n_points=12, cache=False)
        assert hm.values.shape == (12,) and hm.best in set(hm.samples)
        m = sc.match(x, x, [1, 5, 9], [1, 5, 9], n_points=20)  # one Laplace basis for both forms (session cache)
        assert m.map.shape == (g.n_vertices + 1,) and m.map[0] == -1 and m.map[1] == 1
        with pytest.raises(InputError, match="not a vertex"):
            sc.local_score(x, [0])


@pytest.mark.slow
def test_results_serialise_to_json_and_print_readably(tmp_path):
    shape = "demo:animal:delta=0.1,resolution=0.06"
    problem = sc.SymmetryProblem(shape, 20, cache=False)
    results = [sc.score(shape, 20, cache=False), problem.score(), problem.heatmap(), problem.landmarks(2),
               sc.local_score("demo:sphere:subdivisions=1"),
               sc.match(shape, shape, [0, 50], [0, 50], n_points=20),  # one Laplace basis (session cache)
               sc.score("demo:sphere:subdivisions=1", 8, cache=False)]
    for r in results:
        text = json.dumps(r.to_dict(), allow_nan=False)
        assert "Infinity" not in text and "NaN" not in text
        assert len(repr(r)) < 400 and "array(" not in repr(r)
    assert json.loads(json.dumps(results[-1].to_dict()))["sigma"]["lower"] == "inf"
    assert "SymmetryProblem(animal, N=20" in repr(problem)


def test_the_pictures_take_their_style_by_name():
    """A landmark picture names its options (``up``, ``title``, ``dpi``...); a field picture (the local score's
    doubt, a match's) checks its style against ``viz.render.Look`` and the colouring, in one line."""
    from matplotlib.figure import Figure

    marks = sc.landmarks(NON_SYMMETRIC_8, 2, "fps")
    fig = marks.plot(title="two by FPS", views=((20, 30),), dpi=50)
    assert isinstance(fig, Figure) and fig._suptitle.get_text() == "two by FPS" and len(fig.axes) == 1
    local = sc.local_score("demo:sphere:subdivisions=1")
    assert len(local.plot(views=((0, 0), (90, 0)), cmap="magma", vmax=2.0).axes) >= 2
    with pytest.raises(InputError, match=r"plot\(\) got an unknown option 'colour' \(its options: .*cmap"):
        local.plot(colour="red")


def test_symmetry_problem_reuses_its_searches_and_agrees_with_the_one_off_functions():
    shape = "demo:animal:delta=0.1,resolution=0.06"
    problem = sc.SymmetryProblem(shape, 30, target="samples", cache=False)
    first = problem.score()
    kept = problem.search()
    assert problem.search() is kept and first.sigma == sc.score(shape, 30, target="samples", cache=False).sigma
    hm = problem.heatmap()
    assert problem.search() is kept  # the heat map started from the kept search
    after = problem.score(landmarks=[hm.best])
    assert after.sigma[0] <= first.sigma[0] and after.landmarks == (hm.best,)
    with pytest.raises(InputError, match="not one of the samples"):
        problem.score(landmarks=[int(np.setdiff1d(np.arange(5000), problem.sample_ids)[0])])


def test_pictures_draw_onto_a_figure_without_changing_the_backend():
    code = """
import matplotlib
matplotlib.use("svg")
import importlib, pkgutil, shapecond
for m in pkgutil.walk_packages(shapecond.__path__, "shapecond."):
    if not m.name.endswith("__main__"):
        importlib.import_module(m.name)
from matplotlib.figure import Figure
r = shapecond.score("demo:sphere:subdivisions=1", 8, cache=False)
fig = r.plot()
mine = Figure()
assert r.plot(fig=mine) is mine and isinstance(fig, Figure)
print(matplotlib.get_backend())
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-500:]
    assert out.stdout.strip() == "svg"


def test_sample_archives_read_back_as_inputs(tmp_path, capsys):
    from tests.helpers import run_cli

    path = tmp_path / "s.npz"
    code, _, err = run_cli(capsys, "sample", "demo:blob:subdivisions=2", "--points", "12", "-o", path)
    assert code == 0, err
    D = sc.load(path)
    with np.load(path) as z:
        assert np.array_equal(D, z["D"])
    assert sc.score(path).score.n_points == 12
    code, out, err = run_cli(capsys, "score", path, "--json")
    assert code == 0 and json.loads(out)["n_points"] == 12


SCALE_FREE_LANDMARKS = [0, 300, 600, 900]


@pytest.fixture(scope="module")
def unscaled_match():
    """A mesh pair and its dense map at the file's own scale (computed once for both scales below).

    1318 vertices (resolution 0.07), not 2538 (0.05): what is tested is the coordinates' scale, which
    no step treats differently with the vertex count; a match costs 3.7 s of CPU instead of 12 s, and
    the test's 0.999 then allows one differing vertex instead of two."""
    src = sc.load("demo:animal:delta=0.1,resolution=0.07")
    tgt = sc.load("demo:animal:delta=0.3,resolution=0.07")
    lm = SCALE_FREE_LANDMARKS
    return src, tgt, sc.match((src.vertices, src.faces), (tgt.vertices, tgt.faces), lm, lm, n_points=60, cache=False)


@pytest.mark.slow
@pytest.mark.parametrize("scale", [1e-30, 1e20])
def test_match_is_scale_free(unscaled_match, scale):
    """The same dense map for a mesh pair and its copy scaled by 1e-30 or 1e20."""
    src, tgt, ref = unscaled_match
    lm = SCALE_FREE_LANDMARKS
    got = sc.match((src.vertices * scale, src.faces), (tgt.vertices * scale, tgt.faces), lm, lm, n_points=60,
                   cache=False)
    assert np.mean(got.map == ref.map) > 0.999  # distance rows are float32: ties may round apart


G = "demo:sphere:subdivisions=1"


@pytest.mark.parametrize("call,needle", [
    (lambda: sc.match(G, G, [0], [0], n_points=8, cache=False, refin=False), "unknown option 'refin'"),
    (lambda: sc.match(G, G, [0], [0], matcher="faq", n_points=8, cache=False, k=3), "unknown option 'k'"),
    (lambda: sc.landmarks(G, 2, "cnbs", 8, cache=False, methd="fps"),
     "unknown option 'methd' for method 'cnbs' (did you mean 'method'?)"),
    (lambda: sc.landmarks(G, 2, "fps", 8, cache=False, resolve_fraction=0.2),
     "unknown option 'resolve_fraction' for method 'fps'"),
    (lambda: sc.landmarks(G, 2, "hks", 8, cache=False, alpha=1.0), "unknown option 'alpha' for method 'hks'"),
    (lambda: sc.heatmap(G, n_points=8, cache=False, resolve_fractio=0.2),
     "heatmap() got unknown option 'resolve_fractio' (did you mean 'resolve_fraction'?)"),
    (lambda: sc.heatmap(G, n_points=8, cach=False), "heatmap() got unknown option 'cach' (did you mean 'cache'?)"),
    (lambda: sc.kappa(G, trial=3), "kappa() got unknown option 'trial' (did you mean 'trials'?)"),
    (lambda: sc.kappa(G, scale=20), "scale must be a finite number in (0, 10], got 20"),
    (lambda: sc.metric_shape(G, 8, taget="samples"),
     "metric_shape() got unknown option 'taget' (did you mean 'target'?)"),
    (lambda: sc.SymmetryProblem(G, 8, efort="quick"),
     "SymmetryProblem() got unknown option 'efort' (did you mean 'effort'?)"),
    (lambda: sc.score(G, 8, exact="yes", cache=False), "exact must be 'auto', True or False"),
    (lambda: sc.deformation_level(G, G, n_points=8, error_bar=False), "unknown option 'error_bar'"),
    (lambda: sc.deformation_level(G, [G], n_points=8, refin=False), "unknown option 'refin'"),
    (lambda: sc.deformation_level(G, G, matcher="zoomout"), "not 'zoomout'"),
    (lambda: sc.deformation_level(G, [G, G], landmarks=[0], landmarks_others=[[0]]), "2 other shapes"),
], ids=["match refin", "faq k", "landmarks methd", "fps resolve_fraction", "hks alpha", "heatmap resolve_fractio",
        "heatmap cach", "kappa trial", "kappa scale=20", "metric_shape taget", "SymmetryProblem efort",
        "score exact=yes", "level error_bar", "level refin", "level zoomout", "level landmark lists"])
def test_unknown_keywords_are_one_input_error_before_any_work(monkeypatch, call, needle):
    """They raised TypeError (or a plain ValueError) after the geodesics had been computed."""
    def no_work(*args, **kwargs):
        raise AssertionError("the shape was loaded before the keywords were checked")

    from shapecond.api import inputs

    monkeypatch.setattr(inputs, "_loaded", no_work)  # every input is read through it
    with pytest.raises(InputError, match=re.escape(needle)):
        call()


#: Distances of 8 points on a line, spaced unevenly (a matrix input: no geodesics to compute).
NON_SYMMETRIC_8 = np.abs(np.subtract.outer(np.arange(8.0) ** 1.5, np.arange(8.0) ** 1.5))


@pytest.mark.parametrize("bad,needle", [
    ({"time_limit": -1}, "time_limit must be a finite number > 0"), ({"time_limit": 0}, "> 0, got 0"),
    ({"time_limit": float("nan")}, "time_limit"), ({"upper": "no"}, "upper must be True or False"),
    ({"upper": 1}, "upper must be True or False"), ({"exact": "yes"}, "exact must be 'auto', True or False"),
    ({"epsilon": -0.1}, "epsilon must be a finite number >= 0"),
], ids=["time_limit=-1", "time_limit=0", "time_limit=nan", "upper=no", "upper=1", "exact=yes", "epsilon<0"])
def test_a_symmetry_problem_refuses_the_score_settings_sc_score_refuses(bad, needle):
    """SymmetryProblem.score took time_limit=-1 and upper="no"; both scores now share one validator."""
    with pytest.raises(InputError, match=re.escape(needle)) as one_off:
        sc.score(NON_SYMMETRIC_8, **bad)
    problem = sc.SymmetryProblem(NON_SYMMETRIC_8)
    with pytest.raises(InputError) as kept:
        problem.score(**bad)
    assert str(kept.value) == str(one_off.value) and "0 searches kept" in repr(problem)  # before any work


@pytest.mark.parametrize("call,needle", [
    (lambda p: p.heatmap(resolve_fraction=2), "resolve_fraction must be a finite number in [0, 1], got 2"),
    (lambda p: p.heatmap(score="delta"), "score must be one of"),
    (lambda p: p.landmarks(2, scors=True),
     "SymmetryProblem.landmarks() got unknown option 'scors' for method 'cnbs' (did you mean 'scores'?)"),
    (lambda p: p.landmarks(2, "fps", resolve_fraction=0.2), "unknown option 'resolve_fraction' for method 'fps'"),
    (lambda p: p.landmarks(2, effort="quick"), "unknown option 'effort' for method 'cnbs'"),  # the problem's
    (lambda p: p.landmarks(2, "fps", scores="yes"), "scores must be True or False"),
    (lambda p: p.landmarks(-1, "fps"), "k must be an integer in [0, 100000], got -1"),
], ids=["resolve_fraction=2", "score=delta", "scors", "fps resolve_fraction", "effort", "scores=yes", "k=-1"])
def test_a_symmetry_problem_checks_its_methods_options_by_the_table_rows(call, needle):
    """Its heat map and landmarks check their keywords by the rows of ``heatmap``'s and ``landmarks``'s tables
    (``resolve_fraction``, ``score``, ``scores``, ``k``...), a misspelt one named with the nearest."""
    problem = sc.SymmetryProblem(NON_SYMMETRIC_8)
    with pytest.raises(InputError, match=re.escape(needle)):
        call(problem)
    assert "0 searches kept" in repr(problem)  # before any work


def test_the_zoomout_dense_stage_is_in_the_estimate_before_any_work(monkeypatch):
    """match --matcher zoomout on 163k vertices estimated 66 s (the geodesics alone) and ran past
    300 s: the Laplace bases and nearest-neighbour products of the dense stage were not counted."""
    import warnings

    import shapecond.limits as limits
    from shapecond.matching.problem import MatchProblem

    sizes = [2_562, 10_242, 40_962, 163_842]
    dense = [limits.dense_stage_seconds(n, n) for n in sizes]
    # several minutes at 163k vertices (the two bases alone are estimated at about 250 s), seconds at 2.5k
    assert dense == sorted(dense) and dense[-1] > 4 * limits.WARN_SECONDS > dense[0] > 0

    def no_work(*args, **kwargs):
        raise AssertionError("matching started before the cost check")

    monkeypatch.setattr(MatchProblem, "dense_match", property(no_work))  # the first work of a match
    monkeypatch.setattr(limits, "WARN_SECONDS", 10.0)
    shape = "demo:sphere:subdivisions=2"
    with pytest.raises(AssertionError, match="before the cost check"), warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        sc.match(shape, shape, [0, 5, 11], [0, 5, 11], matcher="zoomout", cache=False)
    assert any("ZoomOut dense stage) will take about" in str(w.message) for w in said)  # the bases' fixed part
    said.clear()
    with pytest.raises(AssertionError), warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        sc.match(shape, shape, [0, 5, 11], [0, 5, 11], dense="nearest", n_points=20, cache=False)
    assert not any("will take about" in str(w.message) for w in said)  # no dense stage: geodesics only


def test_lh05s_affinity_is_in_the_estimate_and_refused_before_the_geodesics(monkeypatch):
    """match cat0 cat0 -n 5000 warned '2 min', computed 33 s at 3.5 GB, then LH05 refused a 37 GB matrix."""
    from shapecond.limits import lh05_affinity_bytes
    from shapecond.matching.problem import MatchProblem
    from shapecond.matching.spectral import MAX_AFFINITY_BYTES

    assert lh05_affinity_bytes(5000, 1) / 2**30 == pytest.approx(37.2, abs=0.1)

    def no_work(*args, **kwargs):
        raise AssertionError("matching started before the cost check")

    monkeypatch.setattr(MatchProblem, "dense_match", property(no_work))
    big = "demo:sphere:subdivisions=6"
    for force in (False, True):  # the matcher refuses beyond its limit whatever force says
        with pytest.raises(sc.TooLargeError, match="37.2 GB"):
            sc.match(big, big, [0], [0], n_points=5000, cache=False, force=force)
    # 12 landmarks at N = 1425 would fit (2.98 GB), but LH05 also matches with the first 3 (3.01 GB)
    assert lh05_affinity_bytes(1425, 12) < MAX_AFFINITY_BYTES < lh05_affinity_bytes(1425, 3)
    with pytest.raises(sc.TooLargeError, match="affinity"):
        sc.match(big, big, list(range(12)), list(range(12)), n_points=1425, cache=False)


def _points_matrix(n: int) -> np.ndarray:
    from scipy.spatial.distance import cdist

    P = np.random.default_rng(0).random((n, 3))
    return cdist(P, P)


def test_landmarks_and_heatmap_refuse_an_over_budget_request_unless_forced(monkeypatch):
    from shapecond.selection import cnbs

    def no_work(*args, **kwargs):
        raise AssertionError("the search started before the cost check")

    monkeypatch.setattr(cnbs, "heat_map", no_work)
    monkeypatch.setattr(cnbs, "cnbs_landmarks", no_work)
    D = _points_matrix(600)
    with pytest.raises(sc.TooLargeError, match=r"cnbs with 200 landmarks at N = 600 would take about .* force=True"):
        sc.landmarks(D, 200, "cnbs")
    with pytest.raises(AssertionError, match="before the cost check"):  # forced: the work starts
        sc.landmarks(D, 200, "cnbs", force=True)
    big = _points_matrix(2800)
    with pytest.raises(sc.TooLargeError, match=r"heat map at N = 2800"):
        sc.heatmap(big)


def test_the_deformation_level_is_zero_for_a_shape_against_itself_and_read_off_a_deformed_one():
    """ε̂ of the map found without landmarks: the same shape is matched onto itself isometrically; a
    bent copy with other vertex ids distorts its samples' distances, and δ at that level is taken."""
    same = sc.deformation_level(G, G, n_points=30, cache=False)
    assert same.epsilon == pytest.approx(0.0, abs=1e-9) and same.pairs == (same.epsilon_area,)
    level = sc.deformation_level("demo:animal", ["demo:animal:delta=0.1", "demo:animal"], n_points=40, cache=False)
    assert len(level.pairs) == 2 and level.pairs[1] == pytest.approx(0.0, abs=1e-9) and level.pairs[0] > 1e-3
    assert level.epsilon_area == pytest.approx(np.median(level.pairs))       # the median over the pairs
    g = sc.load("demo:animal")
    src = sample_surface(g, 40, cache=False)
    assert level.epsilon == pytest.approx(level.epsilon_area * src.unit / src.diameter)   # in diameters
    r = sc.score("demo:animal", 40, epsilon=level.epsilon, cache=False)
    assert r.scale.epsilon == level.epsilon and "2 matched map(s) (faq)" in level.sentence()


def test_the_error_bar_reads_the_target_with_the_solver_it_was_sampled_with(monkeypatch):
    """One distance solver (heat-method factorisation) per shape in a match with its error bar, and
    the same bar as with a solver of its own for the bar."""
    from shapecond.matching.problem import MatchProblem

    import shapecond.matching.sampled as sampled

    built = []
    real = sampled.DistanceSolver
    monkeypatch.setattr(sampled, "DistanceSolver", lambda g, b: built.append(g) or real(g, b))
    src, tgt = "demo:animal:resolution=0.08", "demo:animal:delta=0.3,resolution=0.08"
    shared = sc.match(src, tgt, [0, 100, 200], [0, 100, 200], n_points=40, cache=False)
    assert len(built) == 2 and built[0] is not built[1]
    assert shared.problem._sampling_solver is None  # not kept once the bar has read with it
    sampled_map = MatchProblem.sample_map.func

    def forgetting(self):  # the sampling solver dropped before the bar: the bar makes its own
        out = sampled_map(self)
        self._sampling_solver = None
        return out
    monkeypatch.setattr(MatchProblem, "sample_map", functools.cached_property(forgetting))
    MatchProblem.sample_map.__set_name__(MatchProblem, "sample_map")
    own = sc.match(src, tgt, [0, 100, 200], [0, 100, 200], n_points=40, cache=False)
    assert len(built) == 5  # the bar's own solver of the target
    timeless = [{k: v for k, v in r.summary["error_bar"].items() if k != "seconds"} for r in (shared, own)]
    assert timeless[0] == timeless[1]
    np.testing.assert_array_equal(shared.map, own.map)

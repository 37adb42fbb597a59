"""Class evaluation and the ``evaluate`` command on generated class folders."""

import importlib.util
import json

import numpy as np
import pytest

from shapecond.cli import main
from shapecond.errors import InputError
from shapecond.evaluation import Evaluation, EvaluationOptions, MatchRecord, evaluate_dataset
from shapecond.evaluation.datasets import off_vertex_count, read_class
from shapecond.evaluation.landmark_sets import ShapeSetup, landmark_task
from shapecond.evaluation.report import correlation, markdown, write_report
from shapecond.shapes.synthetic import plane_patch

from tests.helpers import write_off, write_strip_class


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    """One class 'strip': a flat 1 x 0.55 grid (strip0) and two bent copies, same vertex order."""
    return write_strip_class(tmp_path_factory.mktemp("data"))


def test_null_shape_is_the_lowest_number(dataset):
    names = [p.stem for p in read_class(dataset / "strip").shapes]
    assert names == ["strip0", "strip7", "strip12"]
    assert off_vertex_count(dataset / "strip" / "strip0.off") == 19 * 19


@pytest.mark.slow
def test_evaluation_of_an_isometric_class(dataset, tmp_path):
    ev = evaluate_dataset(dataset, options=EvaluationOptions(methods=("fps",), matchers=("lh05", "faq"), n_points=60, protocol="both"))
    # 2 targets x counts {3, 10} x 2 matchers x 2 protocols
    assert len(ev.records) == 16
    assert {r.n_landmarks for r in ev.records} == {3, 10}
    for r in ev.records:
        assert r.errors.shape == (60,)
        if r.protocol == "corresponding":
            # bending is an isometry and the samples correspond: once landmarks break the
            # strip's symmetries every sample is matched exactly, by both matchers
            assert r.error == 0.0 and r.exact == 1.0, r
        else:  # independent samples: errors near the sample spacing (~ 10 % of half diameter)
            assert r.error < 15.0, r
    lh05 = [r for r in ev.records if r.protocol == "corresponding" and r.matcher == "lh05"]
    # the exact map: every candidate list holds the truth, and LH05's objective is the truth's
    assert len(lh05) == 4 and all(r.recall == 1.0 and r.objective_ratio == pytest.approx(1.0, abs=1e-9)
                                  for r in lh05)
    lm = ev.landmarks[0]
    assert set(lm["scores"]) == {1, 3, 10} and len(lm["ids"]) == 10
    text = markdown(ev)
    assert "| strip | 10 |" in text and "Spearman" in text
    assert "corresponding protocol, matcher lh05" in text and "independent protocol, matcher faq" in text
    report = write_report(ev, tmp_path / "out")
    for prot in ("corresponding", "independent"):
        assert (tmp_path / "out" / f"score_vs_error_{prot}.png").stat().st_size > 1000
    data = json.loads((tmp_path / "out" / "results.json").read_text())
    assert len(data["records"]) == 16 and set(data["correlation_by_protocol"]) == {"corresponding", "independent"}
    # δ at the class's own deformation level, beside the default ε
    assert set(ev.settings["class_epsilon"]) == {"strip"} and set(lm["scale_class"]) == {1, 3, 10}
    assert "scale_class" in data["correlation"]["faq"]
    # and at the level read off the matched maps (no ground truth): the median ε̂ of the class's matchings
    eh = sorted(r.epsilon_hat for r in ev.records)
    assert set(ev.settings["class_epsilon_hat"]) == {"strip"} and set(lm["scale_hat"]) == {1, 3, 10}
    assert all(0 < e < 0.01 for e in eh)  # the bend is an isometry: the maps barely distort (sqrt(area) units)
    # the median ε̂, from units of sqrt(area) (the strip is 1 x 0.55) into diameters (its diagonal)
    to_diameters = np.sqrt(0.55) / np.hypot(1.0, 0.55)
    assert ev.settings["class_epsilon_hat"]["strip"] == pytest.approx(np.median(eh) * to_diameters, rel=0.03)
    assert "scale_hat" in data["correlation"]["faq"] and "read off its matched maps" in text


def test_class_with_different_vertex_counts_is_refused(dataset, tmp_path):
    (tmp_path / "odd").mkdir()
    for name in ("odd0.off", "odd1.off"):
        (tmp_path / "odd" / name).write_bytes((dataset / "strip" / "strip0.off").read_bytes())
    g = plane_patch(n=9)
    write_off(tmp_path / "odd" / "odd2.off", g.vertices, g.faces)
    with pytest.raises(InputError, match="different vertex counts"):
        evaluate_dataset(tmp_path, options=EvaluationOptions(methods=("fps",), n_points=20))


@pytest.mark.parametrize("case", ["unreferenced", "renumbered"])
def test_class_with_a_different_vertex_order_is_refused(dataset, tmp_path, capsys, case):
    """Same vertex count, but one shape leaves a vertex unreferenced (the ids differ), or the same
    surface has its vertices renumbered (ids equal, triangles not: TOSCA's david and michael): the
    identity is no ground truth, in the independent protocol as in the corresponding one."""
    (tmp_path / "odd").mkdir()
    (tmp_path / "odd" / "odd0.off").write_bytes((dataset / "strip" / "strip0.off").read_bytes())
    g = plane_patch(n=19)
    V = g.vertices * [1.0, 0.55, 0.0]
    if case == "unreferenced":
        F = g.faces[~np.any(g.faces == 0, axis=1)]  # vertex 0 unreferenced
    else:
        perm = np.random.default_rng(0).permutation(len(V))
        V, F = V[perm], np.argsort(perm)[g.faces]
    write_off(tmp_path / "odd" / "odd1.off", V, F)
    for protocol in ("corresponding", "independent"):
        with pytest.raises(SystemExit) as ex:
            main(["evaluate", str(tmp_path), "--methods", "fps", "--matchers", "faq", "--points", "20",
                  "--protocol", protocol, "--out", str(tmp_path / "rep")])
        _, err = capsys.readouterr()
        assert ex.value.code == 2 and err.count("\n") == 1, err
        assert "do not share their vertex order" in err
    assert not (tmp_path / "rep").exists()


def test_unknown_class_and_method_are_input_errors(dataset):
    with pytest.raises(InputError, match="not found"):
        evaluate_dataset(dataset, options=EvaluationOptions(classes=["horse"], methods=("fps",)))
    with pytest.raises(InputError):
        evaluate_dataset(dataset, options=EvaluationOptions(methods=("no-such-method",), n_points=20))


def _fake(scores_errors):
    """An Evaluation with one cell per (method, score, error)."""
    lms, recs = [], []
    for i, (s, e) in enumerate(scores_errors):
        lms.append(dict(cls="c", method=f"m{i}", ids=[], scores={3: s}, seconds=0.0))
        recs.append(MatchRecord("c", "t", f"m{i}", 3, "faq", e, e, e, 0.0, np.zeros(1)))
    settings = dict(dataset="d", classes=["c"], methods=[f"m{i}" for i in range(len(lms))],
                    matchers=["faq"], n_points=10, seed=0, backend="heat", quick=False,
                    landmark_counts={"c": 3})
    return Evaluation(lms, recs, settings)


_KILLED_REPORT = """
import os, signal, sys
import numpy as np
from shapecond.evaluation import Evaluation, MatchRecord
from shapecond.evaluation.report import write_report
from shapecond.viz import pages

def ev(errors):
    recs = [MatchRecord("c", "t", f"m{i}", 3, "faq", e, e, e, 0.0, np.zeros(1)) for i, e in enumerate(errors)]
    lms = [dict(cls="c", method=f"m{i}", ids=[], scores={3: 0.1 * (i + 1)}, seconds=0.0) for i in range(len(errors))]
    return Evaluation(lms, recs, dict(dataset="d", classes=["c"], methods=[f"m{i}" for i in range(len(errors))],
                                      matchers=["faq"], n_points=10, seed=0, backend="heat", quick=False,
                                      landmark_counts={"c": 3}))

pages.write_evaluation_html = lambda *a, **k: os.kill(os.getpid(), signal.SIGKILL)  # killed at the page
write_report(ev([5.0, 6.0, 7.0]), sys.argv[1])
"""


def test_a_report_killed_while_written_leaves_the_earlier_report_whole(tmp_path):
    """A kill -9 between results.json and report.html left the folder mixing two runs (the new numbers
    beside the earlier run's page); now the new files appear together, or none of them."""
    import subprocess
    import sys

    def files():
        return {p.name: p.read_bytes() for p in out.iterdir() if not p.name.startswith(".")}

    out = tmp_path / "out"
    write_report(_fake([(0.1, 1.0), (0.2, 2.0), (0.3, 3.0)]), out)
    earlier = files()
    assert {"results.json", "report.md", "report.html"} <= set(earlier)
    proc = subprocess.run([sys.executable, "-c", _KILLED_REPORT, str(out)], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == -9, proc.stderr
    assert files() == earlier
    write_report(_fake([(0.1, 5.0), (0.2, 6.0), (0.3, 7.0)]), out)  # the next run clears what the kill left
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == []
    assert [r["error"] for r in json.loads((out / "results.json").read_text())["records"]] == [5.0, 6.0, 7.0]


def test_a_failing_figure_still_leaves_the_results(tmp_path, monkeypatch):
    from shapecond.evaluation import report

    def broken(*args):
        raise RuntimeError("the figure failed")

    monkeypatch.setattr(report, "plot", broken)
    with pytest.raises(RuntimeError):
        write_report(_fake([(0.1, 1.0), (0.2, 2.0), (0.3, 3.0)]), tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["results.json"]


def test_spearman_against_known_orderings():
    same = _fake([(0.1, 1.0), (0.5, 2.0), (2.0, 3.0), (float("inf"), 9.0)])
    assert correlation(same, "faq")[0] == pytest.approx(1.0)
    assert correlation(same, "faq")[2] == 4
    rev = _fake([(0.1, 9.0), (0.5, 3.0), (2.0, 2.0), (3.0, 1.0)])
    assert correlation(rev, "faq")[0] == pytest.approx(-1.0)
    assert "ρ = 1" in markdown(same)


def test_evaluate_command_with_two_jobs(dataset, tmp_path, capsys):
    with pytest.raises(SystemExit) as ex:
        main(["evaluate", str(dataset), "--methods", "fps", "--matchers", "faq", "--points", "40",
              "--jobs", "2", "--out", str(tmp_path / "rep"), "--json"])
    out, err = capsys.readouterr()
    assert ex.value.code == 0, err
    summary = json.loads(out)
    assert summary["matchings"] == 4 and (tmp_path / "rep" / "report.md").exists()


def test_evaluate_command_errors(dataset, tmp_path, capsys):
    with pytest.raises(SystemExit) as ex:
        main(["evaluate", str(dataset), "--matchers", "lh06", "--out", str(tmp_path / "r")])
    _, err = capsys.readouterr()
    assert ex.value.code == 2 and "unknown matcher 'lh06'" in err


@pytest.mark.skipif(importlib.util.find_spec("distributed") is None,
                    reason="dask.distributed is not installed (optional extra 'dask')")
def test_dask_backend_on_a_local_cluster(dataset):
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False) as cluster, \
            Client(cluster) as client:
        ev = evaluate_dataset(dataset, options=EvaluationOptions(methods=("fps",), matchers=("faq",), n_points=40, scheduler=client))
    assert len(ev.records) == 4


@pytest.mark.skipif(importlib.util.find_spec("distributed") is not None,
                    reason="dask.distributed is installed; the missing-dask message cannot be shown")
def test_scheduler_without_dask_is_an_input_error(dataset, tmp_path, capsys):
    with pytest.raises(SystemExit) as ex:
        main(["evaluate", str(dataset), "--methods", "fps", "--points", "20",
              "--scheduler", "tcp://127.0.0.1:1", "--out", str(tmp_path / "r")])
    _, err = capsys.readouterr()
    assert ex.value.code == 2 and "needs dask" in err


def test_landmark_selection_is_cached(dataset, tmp_path, monkeypatch):
    # a cache folder of its own: the session's is shared with the other test worker, whose landmark
    # entries may appear between the two listings below
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path / "cache"))
    args = ("strip", dataset / "strip" / "strip0.off", "fps", 4, ShapeSetup(30, 0, "heat", True), True)
    from shapecond.cache import cache_dir

    first = landmark_task(*args)
    cached = list(cache_dir().glob("landmarks-*.json"))
    assert cached
    second = landmark_task(*args)
    assert list(cache_dir().glob("landmarks-*.json")) == cached
    assert first["ids"] == second["ids"] and first["scores"] == second["scores"]
    assert set(second["scores"]) == {1, 3, 4}


def test_cnbs_scale_at_the_class_level_read_off_its_matched_maps(dataset, monkeypatch):
    """cnbs-scale-hat is CNBS-scale at the level ``collection_level`` reads off the null shape's maps to its
    targets (no ground truth): the same landmarks as CNBS-scale called with that ε."""
    import shapecond as sc
    from shapecond.evaluation import deformation_level as dl

    seen = {}
    real = dl.matched_level_task

    def spy(*args):
        seen.update(real(*args))
        return seen
    monkeypatch.setattr("shapecond.evaluation.run.matched_level_task", spy)
    ev = evaluate_dataset(dataset, options=EvaluationOptions(methods=("cnbs-scale-hat",), matchers=("faq",), n_points=40, counts=(3,), error_bars=False, cache=False))
    lm = ev.landmarks[0]
    assert lm["method"] == "cnbs-scale-hat" and seen["cls"] == "strip" and seen["epsilon"] > 0
    null = dataset / "strip" / "strip0.off"
    ref = sc.landmarks(null, len(lm["ids"]), "cnbs-scale", 40, epsilon=seen["epsilon"], target="samples", cache=False)
    assert list(ref.landmarks) == lm["ids"]
    assert {r.method for r in ev.records} == {"cnbs-scale-hat"}
    with pytest.raises(InputError, match="cnbs-scale-hat"):
        evaluate_dataset(dataset, options=EvaluationOptions(methods=("cnbs-scale-ht",)))

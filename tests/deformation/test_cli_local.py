"""``shapecond local`` (cli/cmd_local.py)."""

import json

import numpy as np

from tests.helpers import run_cli as run


def test_local_json_keys_and_inf(capsys):
    code, out, _ = run(capsys, "local", "demo:sphere:subdivisions=2", "--json")
    assert code == 0
    d = json.loads(out)
    assert list(d) == ["score", "lambda_min", "zero_modes", "n_vertices", "landmarks", "seconds"]
    assert d["score"] == "inf" and len(d["zero_modes"]) == 3 and d["n_vertices"] == 162


def test_local_landmarks_file_ids_and_heatmap(tmp_path, capsys):
    png = tmp_path / "hm.png"
    code, out, err = run(capsys, "local", "demo:sphere:subdivisions=2", "--landmarks", "0,5", "--json",
                         "--heatmap-png", str(png), "--energy", "arap", "--alpha", "2")
    assert code == 0, err
    d = json.loads(out)
    assert d["landmarks"] == [0, 5] and np.isfinite(d["score"]) and d["zero_modes"] == []
    assert png.stat().st_size > 1000


def test_local_refuses_point_clouds_and_unknown_ids(tmp_path, capsys):
    cloud = tmp_path / "c.npy"
    np.save(cloud, np.random.default_rng(0).normal(size=(50, 3)))
    code, _, err = run(capsys, "local", str(cloud))
    assert code == 2 and "mesh" in err
    code, _, err = run(capsys, "local", "demo:sphere:subdivisions=2", "--landmarks", "100000")
    assert code == 2 and err.startswith("error:")


def test_the_estimate_grows_with_the_vertices_and_with_the_doubt_field_and_page():
    """`local` on 41k vertices with --html ran past 300 s with no estimate: the cost model now
    covers the score, its doubt field and the HTML page."""
    from shapecond.limits import local_seconds

    sizes = [2_562, 10_242, 40_962, 163_842]
    plain = [local_seconds(n) for n in sizes]
    assert plain == sorted(plain) and plain[-1] > 4 * plain[-2] > 0
    for n in sizes:
        assert local_seconds(n) < local_seconds(n, doubt=True) < local_seconds(n, doubt=True, html=True)


def test_the_estimate_is_printed_before_any_work(capsys, monkeypatch, tmp_path):
    import shapecond.limits as limits
    from shapecond.deformation import local_score as module

    calls = []
    real = module.LocalProblem.__init__

    def spy(self, *a, **kw):  # the warning must already be on stderr when the work starts
        calls.append(capsys.readouterr().err)
        real(self, *a, **kw)

    monkeypatch.setattr(limits, "WARN_SECONDS", 0.0)
    monkeypatch.setattr(module.LocalProblem, "__init__", spy)
    code, _, err = run(capsys, "local", "demo:sphere:subdivisions=2", "--html", str(tmp_path / "p.html"))
    assert code == 0, err
    said = calls[0] + err
    assert "the local score of 162 vertices with its doubt field and HTML page will take about" in calls[0]
    assert said.count("will take about") == 1  # the total, not each part again

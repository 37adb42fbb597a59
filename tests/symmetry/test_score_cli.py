"""``shapecond score``: JSON keys (bracket, witness, resolution report, δ(ε)), landmarks in input ids, errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from shapecond.cli import cli

from tests.helpers import near_symmetric_instance


def run(*args):
    return CliRunner().invoke(cli, ["score", *args], catch_exceptions=False)


def test_matrix_input_json(tmp_path):
    D = near_symmetric_instance(np.random.default_rng(1), 8, 2, 0.05)
    path = tmp_path / "d.npy"
    np.save(path, D)
    out = run(str(path), "--landmarks", "5", "--json")
    assert out.exit_code == 0, out.output
    d = json.loads(out.stdout)
    keys = {"n_points", "landmarks", "sigma", "sigma_hat", "kappa", "witness", "samples", "seconds",
            "target", "n_targets", "resolution", "witness_vertices"}
    assert keys <= set(d)
    assert d["landmarks"] == [5] and d["samples"][0] == 5  # landmark rows come first
    assert d["witness"][0] == 0 and d["resolution"] is None and d["witness_vertices"] is None
    assert d["sigma"]["lower"] == d["sigma"]["upper"] == d["sigma"]["exact"]  # N = 8: exact
    assert d["kappa"]["upper"] == 2 * d["sigma"]["upper"] + 1


def test_mesh_dense_json_reports_resolution_and_vertex_ids():
    out = run("demo:animal", "--points", "30", "--target", "dense", "--target-factor", "4", "--effort", "quick",
              "--json")
    assert out.exit_code == 0, out.output
    d = json.loads(out.stdout)
    assert d["target"] == "dense" and d["n_targets"] == 120 and d["n_points"] == 30
    assert d["resolution"]["flag"] in {"symmetric", "symmetric within resolution", "converged", "undecided"}
    assert d["resolution"]["covering_radius"] > 0
    assert len(d["witness_vertices"]) == 30 and len(set(d["witness_vertices"])) == 30


def test_bad_landmark_is_one_error_line(tmp_path, capsys):
    from shapecond.cli import main

    path = tmp_path / "d.npy"
    np.save(path, near_symmetric_instance(np.random.default_rng(1), 6, 2, 0.05))
    with pytest.raises(SystemExit) as exc:
        main(["score", str(path), "--landmarks", "9"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and "landmark 9" in err[0]


def test_delta_at_the_level_read_off_another_shape_says_where_its_epsilon_comes_from():
    base = ["demo:animal", "--points", "40", "--no-cache", "--json"]
    default = json.loads(run(*base).stdout)
    assert default["epsilon_source"] == "the median sample spacing (default)"
    given = json.loads(run(*base, "--epsilon", "0.05").stdout)
    assert given["epsilon_source"] == "given (--epsilon)" and given["scale"]["epsilon"] == 0.05
    out = run(*base, "--epsilon-from", "demo:animal:delta=0.1")
    assert out.exit_code == 0, out.output
    d = json.loads(out.stdout)
    assert d["epsilon_source"].startswith("read off 1 matched map(s) (faq)")
    assert d["scale"]["epsilon"] == d["deformation_level"]["epsilon"] > 0
    assert d["scale"]["epsilon"] != default["scale"]["epsilon"]


def test_the_verdict_names_the_vertex_a_landmark_should_fix():
    """The sample the witness moves farthest, by its input id; fixing it there ends the exact symmetry."""
    import shapecond as sc
    from shapecond.symmetry.verdict import farthest_moved

    r = sc.score("demo:animal", 40, cache=False)
    D, w = r.shape.D, r.score.witness
    v = farthest_moved(D, w, r.shape.sample_ids)
    i = list(r.shape.sample_ids).index(v)
    assert D[i, w[i]] == max(D[j, w[j]] for j in range(len(w))) > 0
    assert r.verdict.startswith("exact symmetry") and f"near vertex {v} (moved farthest)" in r.verdict
    assert sc.score("demo:animal", 40, landmarks=[v], cache=False).sigma[0] < r.sigma[0]

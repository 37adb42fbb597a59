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

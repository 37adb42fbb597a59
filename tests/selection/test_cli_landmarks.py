"""`shapecond landmarks` and `shapecond heatmap`."""

import json

import matplotlib.image as mpimg
import numpy as np

from tests.helpers import run_cli as run


def _matrix(tmp_path, n=12, seed=0):
    P = np.random.default_rng(seed).normal(size=(n, 3))
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    path = tmp_path / "d.npy"
    np.save(path, D)
    return str(path)


def test_landmarks_json_keys_and_pictures(tmp_path, capsys):
    png, ply = tmp_path / "l.png", tmp_path / "l.ply"
    code, out, err = run(capsys, "landmarks", "demo:animal:delta=0.05", "-n", "40", "--target", "samples",
                         "-k", "2", "--method", "cnbs", "--json", "--png", str(png), "--ply", str(ply),
                         "--no-cache")
    assert code == 0, err
    d = json.loads(out)
    assert set(d) == {"landmarks", "scores", "method", "seconds", "score"}
    assert d["method"] == "cnbs" and len(d["landmarks"]) == 2 and len(d["scores"]) == 2
    assert d["scores"][1] <= d["scores"][0] + 1e-12 or d["scores"][1] == "inf"
    assert mpimg.imread(png).shape[1] > 400 and ply.stat().st_size > 1000


def test_landmarks_baselines_on_a_matrix(tmp_path, capsys):
    path = _matrix(tmp_path)
    for method in ("fps", "pls", "hks"):
        code, out, err = run(capsys, "landmarks", path, "-k", "3", "--method", method, "--json")
        assert code == 0, err
        d = json.loads(out)
        assert len(set(d["landmarks"])) == 3 and d["scores"] == [None, None, None]
    code, out, err = run(capsys, "landmarks", path, "-k", "0", "--method", "user", "--user-landmarks", "4,7",
                         "--json", "--scores")
    assert code == 0, err
    d = json.loads(out)
    assert d["landmarks"] == [4, 7] and all(isinstance(s, float) for s in d["scores"])


def test_landmarks_bad_input(tmp_path, capsys):
    path = _matrix(tmp_path)
    code, _, err = run(capsys, "landmarks", path, "-k", "50", "--method", "fps")
    assert code == 2 and err.startswith("error:")
    code, _, err = run(capsys, "landmarks", path, "-k", "2", "--method", "user")
    assert code == 2
    code, _, err = run(capsys, "landmarks", path, "-k", "0", "--method", "user", "--user-landmarks", "99")
    assert code == 2 and err.startswith("error:")


def test_heatmap_json_and_png(tmp_path, capsys):
    path = _matrix(tmp_path, n=10, seed=2)
    png = tmp_path / "h.png"
    code, out, err = run(capsys, "heatmap", path, "--landmarks", "3", "--png", str(png), "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["landmarks"] == [3] and len(d["values"]) == 10
    vals = [v for v in d["values"] if v is not None]
    assert len(vals) == 9 and d["best_value"] == min(vals)
    assert mpimg.imread(png).size > 0

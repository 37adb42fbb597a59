"""``shapecond kappa``: JSON keys, the Theorem 4.1 bracket, and one-line refusals."""

import json

import numpy as np
import pytest

from tests.helpers import run_cli as run
from tests.helpers import random_instance


def test_kappa_json_on_a_matrix(tmp_path, capsys):
    path = tmp_path / "d.npy"
    np.save(path, random_instance(np.random.default_rng(0), 7, 2))
    code, out, _ = run(capsys, "kappa", str(path), "--trials", "5", "--landmarks", "2", "--json")
    assert code == 0
    r = json.loads(out)
    for key in ("n_points", "trials", "probes", "kappa_probe_max", "sigma", "kappa", "seconds"):
        assert key in r
    assert r["n_points"] == 7 and r["trials"] == 5 and len(r["probes"]) == 5
    assert r["landmarks"] == [2] and r["samples"][0] == 2
    assert r["kappa"]["lower"] == r["sigma"] and r["kappa"]["upper"] == pytest.approx(2 * r["sigma"] + 1)
    assert r["sigma"] <= r["kappa_probe_max"] * (1 + 1e-9)
    assert all(p <= r["kappa"]["upper"] for p in r["probes"])


@pytest.mark.parametrize("argv,match", [
    (["kappa", "MATRIX", "--trials", "0"], "--trials"),
    (["kappa", "BIG"], "at most 9 points"),
    (["kappa", "demo:blob", "--points", "12"], "at most 9 points"),
    (["kappa", "MATRIX", "--target", "dense"], "dense"),
])
def test_kappa_refusals_are_one_error_line(tmp_path, capsys, argv, match):
    small, big = tmp_path / "small.npy", tmp_path / "big.npy"
    np.save(small, random_instance(np.random.default_rng(0), 6, 2))
    np.save(big, random_instance(np.random.default_rng(0), 12, 2))
    argv = [str(small) if a == "MATRIX" else str(big) if a == "BIG" else a for a in argv]
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and match in lines[0]

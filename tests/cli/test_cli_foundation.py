"""The command line of the foundation: info, sample, demo and the error contract."""

import json

import numpy as np
import pytest

from tests.helpers import run_cli as run


def test_info_json_on_generated_shape(capsys):
    code, out, err = run(capsys, "info", "demo:sphere", "--json")
    assert code == 0
    report = json.loads(out)
    assert report["n_vertices"] == 2562 and report["components"] == 1 and report["problems"] == []


def test_info_reports_problems_without_failing(tmp_path, capsys):
    path = tmp_path / "two.off"
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5], [6, 5, 5], [5, 6, 5], [9, 9, 9]], float)
    F = [[0, 1, 2], [3, 4, 5]]
    path.write_text("OFF\n7 2 0\n" + "\n".join(" ".join(map(str, v)) for v in V) + "\n"
                    + "\n".join(f"3 {a} {b} {c}" for a, b, c in F) + "\n")
    code, out, _ = run(capsys, "info", str(path), "--json")
    report = json.loads(out)
    assert code == 0 and report["components"] == 2 and report["isolated_vertices"] == 1
    assert report["boundary_edges"] == 6 and any("2 connected" in p for p in report["problems"])


def test_sample_writes_npz_with_file_ids(tmp_path, capsys):
    out_path = tmp_path / "s.npz"
    code, out, _ = run(capsys, "sample", "demo:blob:subdivisions=3", "--points", "30", "--landmarks", "7,3",
                       "-o", str(out_path), "--json")
    assert code == 0 and json.loads(out)["n_points"] == 30
    with np.load(out_path) as z:
        assert z["D"].shape == (30, 30) and list(z["samples"][:2]) == [7, 3]


@pytest.mark.parametrize("argv,match", [
    (["sample", "demo:sphere", "--points", "5000", "-o", "OUT"], "fewer than"),
    (["sample", "demo:sphere", "--points", "10", "--landmarks", "999999", "-o", "OUT"], "not a vertex"),
    (["sample", "demo:sphere", "--points", "10", "--landmarks", "4,4", "-o", "OUT"], "repeated"),
    (["sample", "demo:sphere", "--points", "2", "-o", "OUT"], "--points must be an integer in [3,"),
    (["sample", "demo:nosuchshape", "-o", "OUT"], "unknown generated shape"),
    (["sample", "demo:sphere", "--bogus", "-o", "OUT"], "No such option"),
    (["match", "demo:sphere", "demo:sphere", "--landmarks-source", "0", "--landmarks-target", "0", "--refin",
      "-o", "OUT"], "No such option '--refin'"),
    (["landmarks", "demo:sphere", "-k", "2", "--resolve-fractio", "0.2"], "No such option '--resolve-fractio'"),
    (["heatmap", "demo:sphere", "--resolve-fractio", "0.2"], "No such option '--resolve-fractio'"),
    (["info", "missing.off"], "no such file"),
])
def test_bad_input_is_one_error_line_exit_2_and_no_file(tmp_path, capsys, argv, match):
    argv = [str(tmp_path / "out.npz") if a == "OUT" else a for a in argv]
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and match in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_demo_json(tmp_path, capsys):
    code, out, _ = run(capsys, "demo", "--points", "60", "--landmark-points", "30", "--out", str(tmp_path), "--json")
    summary = json.loads(out)
    assert code == 0 and summary["n_points"] == 60 and summary["covering_radius"] > 0
    assert summary["sigma"]["lower"] == "inf" and summary["witness_is_mirror_map"]
    assert len(summary["landmarks"]) == 3 and all(isinstance(s, float) for s in summary["scores"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo.html", "heatmap.png", "landmarks.png", "witness.png"]
    assert summary["pictures"]["html"] == str(tmp_path / "demo.html")
    assert (tmp_path / "demo.html").read_text().count('class="sc-data"') == 3  # witness, heat map, landmarks


def test_every_command_checks_its_outputs_against_its_inputs():
    """The one rule for outputs (cli.common.Command, output.check_distinct) holds for every command."""
    import click

    from shapecond.cli import cli
    from shapecond.cli.common import Command, OutputFile

    ctx = click.Context(cli)
    for name in cli.list_commands(ctx):
        command = cli.get_command(ctx, name)
        if isinstance(command, click.Group):
            assert not any(isinstance(p.type, OutputFile) for c in command.commands.values() for p in c.params)
            continue
        assert isinstance(command, Command), name
        for p in command.params:  # every file option that writes is an OutputFile
            if isinstance(p.type, click.Path) and p.type.dir_okay is False and p.name not in (
                    "symmetry_map", "epsilon_from", "landmark_table", "pairs_file"):  # inputs
                assert isinstance(p.type, OutputFile), (name, p.name)

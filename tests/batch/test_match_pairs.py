"""Matching listed pairs (``--pairs``), both directions (``--both-directions``) and the cycle error."""

import json
import re

import numpy as np
import pytest
import shapecond as sc
from shapecond.api.collection import cycle_error
from shapecond.batch import run_batch
from shapecond.batch.matches import read_view
from shapecond.batch.run import BatchRun
from shapecond.batch.table import Table
from shapecond.errors import InputError
from shapecond.shapes.io import write_mesh
from tests.batch.test_match_collection import _write
from tests.helpers import run_cli

OPTIONS = {"points": 16}


@pytest.fixture(scope="module")
def strips(tmp_path_factory):
    """A template strip and two differently meshed, bent and renumbered strips, each with 4 landmarks."""
    root = tmp_path_factory.mktemp("strips")
    n = {"template": _write(root, "template", 11), "s1": _write(root, "s1", 12, 0.5, 1),
         "s2": _write(root, "s2", 10, 0.35, 2)}
    return root, n


def _rows(out):
    with Table(out, "resume") as table:
        return table.rows


@pytest.mark.slow
def test_listed_pairs_matched_both_ways_with_their_cycle_error(strips, tmp_path, capsys):
    root, n = strips
    pairs = tmp_path / "pairs.txt"
    pairs.write_text("# first matched to second\ns1 s2\ns2.off, template  # a suffix and a comma\n")
    out = tmp_path / "t.jsonl"
    shapes = [root / f"{k}.off" for k in ("s1", "s2", "template")]
    code, stdout, err = run_cli(capsys, "batch", *shapes, "--pairs", pairs, "--both-directions", "--points", 16,
                                "--out", out, "--json")
    assert code == 0, err
    rows = _rows(out)
    got = {(r["match_source"].rsplit("/", 1)[-1], r["match_target"].rsplit("/", 1)[-1]): r for r in rows}
    assert sorted(got) == [("s1.off", "s2.off"), ("s2.off", "s1.off"), ("s2.off", "template.off"),
                           ("template.off", "s2.off")]
    assert json.loads(stdout)["shapes"] == 4
    for (source, target), r in got.items():
        assert r["error"] is None and r["match_template"] is None and r["landmark_pairs"] == 4
        first = (source, target) in (("s1.off", "s2.off"), ("s2.off", "template.off"))
        assert r["match_direction"] == ("first to second" if first else "second to first")
        assert r["file"].endswith("/s2.off" if "s1.off" in (source, target) else "/template.off")
        assert r["map_file"] == str(tmp_path / "maps" / f"{source[:-4]}.to.{target[:-4]}.txt")
        vmap = np.loadtxt(r["map_file"], dtype=np.int64)
        assert vmap.shape == (n[source[:-4]],) and 0 <= vmap.min() and vmap.max() < n[target[:-4]]
        assert 0 <= r["cycle_error"] < 0.5 and r["bar"] > 0
    assert len({r["params"] for r in rows}) == 4  # each row its own key
    assert json.loads(got[("s1.off", "s2.off")]["params"])["reference"] == str(root / "s1.off")
    report = (tmp_path / "report.html").read_text()
    assert "<th>cycle</th>" in report and "s1 → s2" in report and "listed pairs" in report
    again = run_batch(shapes, out, {**OPTIONS, "pairs": pairs, "both_directions": True}, what=["match"], how=BatchRun(resume=True))
    assert (again.scored, again.resumed) == (0, 4) and len(out.read_text().splitlines()) == 4


@pytest.fixture(scope="module")
def both_ways(strips, tmp_path_factory):
    """The template matched both ways to s1: the table (CSV) and its batch summary."""
    root, _ = strips
    out = tmp_path_factory.mktemp("both") / "t.csv"
    summary = run_batch([root / "s1.off"], out, {**OPTIONS, "both_directions": True},
                        what=[f"match:{root / 'template.off'}"])
    return out, summary


@pytest.mark.slow
def test_a_template_matched_both_ways_keeps_the_one_way_names(strips, both_ways):
    root, n = strips
    out, s = both_ways
    assert (s.shapes, s.scored, s.failed) == (2, 2, 0)
    there, back = _rows(out)
    assert (there["match_direction"], back["match_direction"]) == ("template to shape", "shape to template")
    assert there["map_file"].endswith("maps/s1.txt") and back["map_file"].endswith("maps/s1.to_template.txt")
    assert back["match_source"] == there["match_target"] == str(root / "s1.off")
    assert back["match_target"] == there["match_source"] == there["match_template"] == str(root / "template.off")
    assert np.loadtxt(back["map_file"]).shape == (n["s1"],) and np.loadtxt(there["map_file"]).shape == (n["template"],)
    assert there["cycle_error"] >= 0 and back["cycle_error"] >= 0
    assert [json.loads(r["params"])["direction"] for r in (there, back)] == ["template to shape", "shape to template"]
    # each map its own view, of its own target
    assert [read_view(r)["vertices"] for r in (there, back)] == [n["s1"], n["template"]]


def test_one_way_has_no_cycle_error_and_keeps_its_key(strips, tmp_path):
    root, _ = strips
    one = run_batch([root / "s1.off"], tmp_path / "one.csv", OPTIONS, what=[f"match:{root / 'template.off'}"])
    row = _rows(tmp_path / "one.csv")[0]
    assert one.shapes == 1 and row["cycle_error"] is None and row["match_direction"] == "template to shape"
    assert not {"both_directions", "direction", "reference"} & set(json.loads(row["params"]))


@pytest.mark.slow
def test_killed_between_the_two_rows_of_a_shape_adds_only_the_missing_one(strips, both_ways, tmp_path):
    root, _ = strips
    lines = both_ways[0].read_text().splitlines(keepends=True)
    out = tmp_path / "t.csv"
    out.write_text("".join(lines[:-1]))  # the forward row only
    again = run_batch([root / "s1.off"], out, {**OPTIONS, "both_directions": True}, what=[f"match:{root / 'template.off'}"], how=BatchRun(resume=True))
    assert (again.scored, again.resumed, again.failed) == (1, 1, 0)
    rows = _rows(out)
    assert out.read_text().splitlines(keepends=True)[:2] == lines[:2] and len(rows) == 2
    assert [r["match_direction"] for r in rows] == ["template to shape", "shape to template"]
    assert (tmp_path / "maps" / "s1.to_template.txt").exists()


@pytest.mark.slow
def test_the_cycle_error_is_zero_for_a_copy_and_large_for_a_scrambled_map(strips, tmp_path):
    root, _ = strips
    g = sc.load(root / "s1.off")
    for name in ("t", "copy"):
        write_mesh(tmp_path / f"{name}.off", g.vertices, g.faces)
        (tmp_path / f"{name}.lmk").write_bytes((root / "s1.lmk").read_bytes())
    table, maps = sc.match_collection(tmp_path / "t.off", [tmp_path / "copy.off"], both_directions=True,
                                      n_points=20, cache=False)
    rows = table if isinstance(table, list) else table.to_dict("records")
    assert [(r["map"], r["direction"]) for r in rows] == [("copy", "template to shape"),
                                                          ("copy.to_template", "shape to template")]
    assert all(r["error"] is None and r["cycle_error"] < 0.01 for r in rows), rows
    assert list(maps) == ["copy", "copy.to_template"]
    identity = np.arange(g.n_vertices)
    scrambled = np.random.default_rng(0).permutation(g.n_vertices)
    assert cycle_error(g, identity, identity, n_points=20, cache=False) == 0.0
    assert cycle_error(g, maps["copy"], maps["copy.to_template"], n_points=20, cache=False) == pytest.approx(
        rows[1]["cycle_error"], abs=0.01)
    assert cycle_error(g, identity, scrambled, n_points=20, cache=False) > 0.3


def _bad(capsys, tmp_path, root, *extra):
    out = tmp_path / "t.csv"
    code, stdout, err = run_cli(capsys, "batch", root / "s1.off", root / "s2.off", "--out", out, *extra)
    assert (code, stdout) == (2, "") and err.startswith("error: ") and len(err.splitlines()) == 1, err
    assert not out.exists() and not (tmp_path / "maps").exists() and not (tmp_path / "report.html").exists()
    return err


@pytest.mark.parametrize("text, message", [
    ("s1 nothing\n", "names 'nothing', which is not one of the input shapes"),
    ("# only a comment\n\n", "no pairs"),
    ("s1 s1.off\n", "s1 is paired with itself"),
    ("s1 s2\ns1 s2\n", "the pair s1 s2 is listed twice"),
    ("s1 s2 s3\n", "line 1: expected two shape names, got 3"),
])
def test_a_bad_pairs_list_is_one_line_and_nothing_written(strips, tmp_path, capsys, text, message):
    root, _ = strips
    (tmp_path / "p.txt").write_text(text)
    assert message in _bad(capsys, tmp_path, root, "--pairs", tmp_path / "p.txt")


def test_pairs_options_that_do_not_fit_are_refused(strips, tmp_path, capsys):
    root, _ = strips
    (tmp_path / "p.txt").write_text("s1 s2\ns2 s1\n")
    assert "in either order" in _bad(capsys, tmp_path, root, "--pairs", tmp_path / "p.txt", "--both-directions")
    assert "--what match (not match:TEMPLATE)" in _bad(capsys, tmp_path, root, "--pairs", tmp_path / "p.txt",
                                                       "--what", f"match:{root / 'template.off'}")
    assert "--what match needs --pairs FILE" in _bad(capsys, tmp_path, root, "--what", "match")
    assert "--both-directions needs" in _bad(capsys, tmp_path, root, "--both-directions")
    assert "no such file" in _bad(capsys, tmp_path, root, "--pairs", tmp_path / "missing.txt")


# --- the API: sc.match_collection(None, shapes, pairs=...) -----------------------------------------

def _records(table):
    return table if isinstance(table, list) else table.to_dict("records")


@pytest.mark.slow
def test_match_collection_matches_listed_pairs_from_a_file_or_a_list(strips, tmp_path):
    root, n = strips
    shapes = [root / f"{k}.off" for k in ("s1", "s2", "template")]
    pairs = tmp_path / "pairs.txt"
    pairs.write_text("# first matched to second\ns1 s2\ns2.off, template\n")
    table, maps = sc.match_collection(None, shapes, pairs=pairs, maps_dir=tmp_path / "maps", n_points=16)
    rows = _records(table)
    assert [(r["map"], r["direction"], r["source"], r["target"], r["shape"]) for r in rows] == [
        ("s1.to.s2", "first to second", "s1", "s2", "s2"),
        ("s2.to.template", "first to second", "s2", "template", "template")]
    assert all(r["error"] is None and r["landmark_pairs"] == 4 and r["bar"] > 0 for r in rows), rows
    assert rows[0]["file"] == str(root / "s2.off")
    assert maps.path("s1.to.s2") == tmp_path / "maps" / "s1.to.s2.txt"
    for name, (source, target) in {"s1.to.s2": ("s1", "s2"), "s2.to.template": ("s2", "template")}.items():
        assert maps[name].shape == (n[source],) and 0 <= maps[name].min() and maps[name].max() < n[target]
    # the same pairs as a list (names, a file name, a path as given), both ways: the first maps are the same
    listed = [("s1", root / "s2.off"), ("s2.off", "template")]
    table, again = sc.match_collection(None, shapes, pairs=listed, both_directions=True, n_points=16)
    rows = _records(table)
    assert [(r["map"], r["direction"]) for r in rows] == [
        ("s1.to.s2", "first to second"), ("s2.to.s1", "second to first"),
        ("s2.to.template", "first to second"), ("template.to.s2", "second to first")]
    assert all(r["error"] is None and r["cycle_error"] >= 0 for r in rows), rows
    assert np.array_equal(again["s1.to.s2"], maps["s1.to.s2"]) and again["s2.to.s1"].shape == (n["s2"],)


@pytest.mark.parametrize("pairs, message", [
    ([("s1", "nothing")], "pairs: the pairs list names 'nothing', which is not one of the input shapes"),
    ([("s1", "s1.off")], "s1 and s1.off are one shape, paired with itself"),
    ([("s1", "s2"), ("s1", "s2")], "the pair s1 s2 is listed twice"),
    ([], "pairs: no pairs"),
    ([("s1",)], "pairs: item 1 is not two shape names"),
    (["s1 s2"], "pairs: item 1 is not two shape names"),
    ({"s1": "s2"}, "pairs must be the path of a pairs list or a list"),
    (3, "pairs must be the path of a pairs list or a list"),
])
def test_match_collection_refuses_a_bad_pairs_list_before_any_work(strips, pairs, message):
    root, _ = strips
    with pytest.raises(InputError, match=re.escape(message)):
        sc.match_collection(None, [root / "s1.off", root / "s2.off"], pairs=pairs, n_points=16)


def test_match_collection_refuses_a_bad_pairs_file_a_template_with_pairs_and_neither(strips, tmp_path):
    root, _ = strips
    shapes = [root / "s1.off", root / "s2.off"]
    (tmp_path / "p.txt").write_text("s1 s2\ns2 s1\n")
    with pytest.raises(InputError, match="in either order"):
        sc.match_collection(None, shapes, pairs=tmp_path / "p.txt", both_directions=True)
    (tmp_path / "self.txt").write_text("s1 s1.off\n")
    with pytest.raises(InputError, match="s1 is paired with itself"):
        sc.match_collection(None, shapes, pairs=tmp_path / "self.txt")
    with pytest.raises(InputError, match="no such file"):
        sc.match_collection(None, shapes, pairs=tmp_path / "missing.txt")
    with pytest.raises(InputError, match="not both"):
        sc.match_collection(root / "template.off", shapes, pairs=[("s1", "s2")])
    with pytest.raises(InputError, match="template=None"):
        sc.match_collection(None, shapes)


def test_a_pairs_first_shape_without_usable_landmarks_is_its_rows_error(strips, tmp_path):
    root, _ = strips
    _write(tmp_path, "bare", 8, labels="")
    _write(tmp_path, "far", 8, labels="abc")
    (tmp_path / "far.lmk").write_text("a 0\nb 1\nc 100000\n")  # an id out of range
    shapes = [tmp_path / "bare.off", tmp_path / "far.off", root / "s1.off"]
    table, maps = sc.match_collection(None, shapes, pairs=[("bare", "s1"), ("far", "s1")], both_directions=True,
                                      n_points=16)
    rows = _records(table)
    assert [r["map"] for r in rows] == ["bare.to.s1", "s1.to.bare", "far.to.s1", "s1.to.far"]
    assert [r["error"].split(":")[0] for r in rows] == ["the pair's first shape bare"] * 2 + [
        "the pair's first shape far"] * 2
    assert "no landmarks" in rows[0]["error"] and "landmark vertex id 100000 is out of range" in rows[2]["error"]
    assert len(maps) == 0

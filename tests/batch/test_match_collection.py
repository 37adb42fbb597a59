"""A collection matched to a template: landmark files, batch rows and maps, resume, report, the API."""

import json
import re

import numpy as np
import pytest
import shapecond as sc
from shapecond.batch import run_batch
from shapecond.batch.matches import read_view
from shapecond.batch.run import BatchRun
from shapecond.batch.table import Table
from shapecond.errors import InputError
from shapecond.shapes.landmark_files import landmarks_of, pair_by_label, read_landmark_csv, read_lmk
from tests.helpers import bent_strip, run_cli

# bent_strip: a 1 x 0.55 rectangle; landmarks off its axes remove its symmetries
POINTS = {"a": (0.1, 0.1), "b": (0.85, 0.2), "c": (0.3, 0.45), "d": (0.6, 0.4)}
OPTIONS = {"points": 30}


def _write(folder, name, n, bend=None, seed=None, labels="abcd"):
    V, F, uv = bent_strip(n, bend, seed)
    (folder / f"{name}.off").write_text(f"OFF\n{len(V)} {len(F)} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V)
                                        + "".join(f"3 {a} {b} {c}\n" for a, b, c in F))
    if labels:
        ids = {k: int(np.argmin(((uv - POINTS[k]) ** 2).sum(1))) for k in labels}
        (folder / f"{name}.lmk").write_text("# generated\n" + "".join(f"{k} {v}  # {k}\n" for k, v in ids.items()))
    return len(V)


@pytest.fixture(scope="module")
def collection(tmp_path_factory):
    """A template strip, two differently meshed, bent and renumbered strips, one without landmarks and
    one sharing only two labels with the template."""
    root = tmp_path_factory.mktemp("collection")
    n = {"template": _write(root, "template", 13)}
    n["s1"] = _write(root, "s1", 15, 0.5, 1)
    n["s2"] = _write(root, "s2", 11, 0.35, 2)
    _write(root, "bare", 12, labels="")
    _write(root, "two", 12, 0.6, 3, labels="ab")
    return root, n


# --- landmark files ------------------------------------------------------------------------------

@pytest.mark.parametrize("text, message", [
    ("nose 1\nnose 2\n", "lmk:2: the label 'nose' is given twice"),
    ("nose 1.5\n", "lmk:1: the vertex id '1.5' is not an integer"),
    ("# c\nnose -3\n", "lmk:2: the vertex id -3 is negative"),
    ("nose\n", "lmk:1: expected 'LABEL VERTEX_ID', found 1 words"),
])
def test_a_bad_lmk_line_is_one_error_naming_file_and_line(tmp_path, text, message):
    path = tmp_path / "cat.lmk"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_lmk(path)


def test_lmk_comments_and_label_pairing(tmp_path):
    (tmp_path / "t.lmk").write_text("# template\nnose 3\n\ntail 9 # end\near 4\n")
    (tmp_path / "s.lmk").write_text("ear 40\nnose 30\npaw 7\n")
    t, s = read_lmk(tmp_path / "t.lmk"), read_lmk(tmp_path / "s.lmk")
    assert t == {"nose": 3, "tail": 9, "ear": 4}
    assert pair_by_label(t, s) == (["nose", "ear"], [3, 4], [30, 40])


def test_a_fifo_is_refused_as_a_landmark_file(tmp_path):
    import os

    os.mkfifo(tmp_path / "x.lmk")
    with pytest.raises(InputError):
        read_lmk(tmp_path / "x.lmk")


def test_landmark_csv(tmp_path):
    path = tmp_path / "landmarks.csv"
    path.write_text("shape,label,vertex\ns1.off,nose,3\ns1,ear,4\n\ns2,nose,5\n")
    table = read_landmark_csv(path)
    assert table == {"s1.off": {"nose": 3}, "s1": {"ear": 4}, "s2": {"nose": 5}}
    assert landmarks_of(tmp_path / "s2.off", table)[0] == {"nose": 5}
    assert landmarks_of(tmp_path / "s3.off", table) is None
    path.write_text("shape,label,vertex\ns1,nose,3\ns1,nose,4\n")
    with pytest.raises(InputError, match=r"landmarks.csv:3: the label 'nose' is given twice"):
        read_landmark_csv(path)
    path.write_text("name,label,vertex\n")
    with pytest.raises(InputError, match=r"landmarks.csv:1: expected the header"):
        read_landmark_csv(path)


# --- batch ---------------------------------------------------------------------------------------

def _rows(out):
    with Table(out, "resume") as table:
        return {r["file"].rsplit("/", 1)[-1]: r for r in table.rows}


@pytest.mark.slow
def test_batch_matches_a_collection_and_resumes(collection, tmp_path):
    root, n = collection
    out = tmp_path / "table.jsonl"
    shapes = [str(root / f"{k}.off") for k in ("s1", "s2", "bare", "two")]
    s = run_batch(shapes, out, OPTIONS, what=[f"match:{root / 'template.off'}"])
    assert (s.shapes, s.scored, s.failed) == (4, 4, 2)
    rows = _rows(out)
    for name in ("s1", "s2"):
        r = rows[f"{name}.off"]
        assert r["error"] is None and r["landmark_pairs"] == 4 and r["landmark_labels"] == "a b c d"
        assert r["match_direction"] == "template to shape" and r["bar"] > 0 and r["bar_epsilon_hat"] >= 0
        assert r["suggest_source_id"] is not None and 0 <= r["suggest_image_id"] < n[name]
        vmap = np.loadtxt(r["map_file"], dtype=np.int64)
        assert r["map_file"] == str(tmp_path / "maps" / f"{name}.txt")
        assert vmap.shape == (n["template"],) and vmap.min() >= 0 and vmap.max() < n[name]
        assert json.loads(r["params"])["pairs"][0][0] == "a"
    assert "no landmarks for this shape" in rows["bare.off"]["error"]
    assert "2 landmark labels shared" in rows["two.off"]["error"] and rows["two.off"]["map_file"] is None
    assert not (tmp_path / "maps" / "bare.txt").exists()
    report = (tmp_path / "report.html").read_text()
    assert "data:image/png;base64," in report and "Annotate more" in report and "bare" in report
    # each map's view beside it (of the shape, its target), in the report once
    assert sorted(p.name for p in (tmp_path / "views").iterdir()) == ["s1.json", "s2.json"]
    assert [read_view(rows[f"{k}.off"])["vertices"] for k in ("s1", "s2")] == [n["s1"], n["s2"]]
    assert len(re.findall(r'class="sc-mapdata" data-view="\d+"', report)) == 2
    stamp = {p.name: p.stat().st_mtime_ns for d in ("maps", "views") for p in (tmp_path / d).iterdir()}
    again = run_batch(shapes, out, OPTIONS, what=[f"match:{root / 'template.off'}"], how=BatchRun(resume=True))
    assert (again.scored, again.resumed) == (0, 4)
    assert {p.name: p.stat().st_mtime_ns for d in ("maps", "views") for p in (tmp_path / d).iterdir()} == stamp
    assert len(re.findall(r'class="sc-mapdata" data-view="\d+"', (tmp_path / "report.html").read_text())) == 2
    assert len(out.read_text().splitlines()) == 4  # no row twice


@pytest.mark.slow
def test_changed_landmarks_recompute_only_that_shape(collection, tmp_path):
    root, _ = collection
    folder = tmp_path / "c"
    folder.mkdir()
    for name in ("template", "s2", "two"):
        for suffix in (".off", ".lmk"):
            (folder / f"{name}{suffix}").write_bytes((root / f"{name}{suffix}").read_bytes())
    out = tmp_path / "t.csv"
    what = [f"match:{folder / 'template.off'}"]
    first = run_batch([folder / "s2.off", folder / "two.off"], out, OPTIONS, what=what)
    assert (first.scored, first.failed) == (2, 1)
    (folder / "two.lmk").write_text("c 3\nd 30\n" + (folder / "two.lmk").read_text())
    second = run_batch([folder / "s2.off", folder / "two.off"], out, OPTIONS, what=what, how=BatchRun(resume=True))
    assert (second.scored, second.resumed, second.failed) == (1, 1, 0)


def test_template_problems_stop_the_command(collection, tmp_path, capsys):
    root, _ = collection
    base = ["batch", root / "s1.off", "--out", tmp_path / "t.csv", "--what"]
    code, out, err = run_cli(capsys, *base, f"match:{root / 'bare.off'}")
    assert (code, out) == (2, "") and err.startswith("error: ") and "the template has no landmarks" in err
    code, _, err = run_cli(capsys, *base, f"match:{tmp_path / 'nothing.off'}")
    assert code == 2 and "no such file" in err and len(err.splitlines()) == 1
    (tmp_path / "t.off").write_bytes((root / "template.off").read_bytes())
    (tmp_path / "t.lmk").write_text("a 0\nb 100000\nc 2\n")
    code, _, err = run_cli(capsys, *base, f"match:{tmp_path / 't.off'}")
    assert code == 2 and "t.off: landmark vertex id 100000 is out of range" in err
    assert not (tmp_path / "t.csv").exists() and not (tmp_path / "maps").exists()


def test_a_shape_id_out_of_range_is_its_row_error(collection, tmp_path):
    root, _ = collection
    for name in ("s1", "s2"):
        (tmp_path / f"{name}.off").write_bytes((root / f"{name}.off").read_bytes())
    (tmp_path / "s1.lmk").write_text("a 1\nb 2\nc 99999\n")
    (tmp_path / "s2.lmk").write_text("a 1\na 2\n")
    out = tmp_path / "t.jsonl"
    s = run_batch([tmp_path / "s1.off", tmp_path / "s2.off"], out, OPTIONS, what=[f"match:{root / 'template.off'}"])
    assert s.failed == 2
    rows = _rows(out)
    assert "s1.lmk: landmark vertex id 99999 is out of range" in rows["s1.off"]["error"]
    assert "s2.lmk:2: the label 'a' is given twice" in rows["s2.off"]["error"]


def test_match_what_is_parsed_and_keeps_older_keys():
    from shapecond.batch.rows import params_key, parse_what

    assert parse_what("match:x.off").match.endswith("/x.off")
    assert parse_what("match:demo:animal").match == "demo:animal"  # a demo shape is no path
    with pytest.raises(InputError, match="one match:TEMPLATE"):
        parse_what(["match:a.off", "match:b.off"])
    assert "matcher" not in params_key({"what": ["score"]})  # a score table's key is unchanged


def test_a_template_named_by_one_of_the_inputs(tmp_path):
    from shapecond.batch.matches import template_path

    names = {str(tmp_path / "shapes" / "cow0.off"): "cow0", str(tmp_path / "dog.ply"): "dog"}
    assert template_path(str(tmp_path / "cow0"), names) == str(tmp_path / "shapes" / "cow0.off")
    assert template_path(str(tmp_path / "horse"), names) == str(tmp_path / "horse")  # none: load says why
    (tmp_path / "cow0").write_text("")  # a file of that name is what the user gave
    assert template_path(str(tmp_path / "cow0"), names) == str(tmp_path / "cow0")
    assert template_path("demo:animal", names) == "demo:animal"
    from shapecond.batch.matches import MatchPlan  # the table's key and the rows' params name the file
    options = MatchPlan(str(tmp_path / "shapes" / "cow0.off")).with_template({"what": "score,match:cow0", "seed": 1})
    assert options == {"what": ["score", f"match:{tmp_path / 'shapes' / 'cow0.off'}"], "seed": 1}


# --- the API -------------------------------------------------------------------------------------

@pytest.mark.slow
def test_match_collection_api(collection, tmp_path):
    root, n = collection
    table, maps = sc.match_collection(root / "template.off", [root / "s1.off", root / "bare.off"],
                                      maps_dir=tmp_path / "maps", n_points=30)
    rows = table if isinstance(table, list) else table.to_dict("records")
    assert [r["shape"] for r in rows] == ["s1", "bare"]
    assert rows[0]["error"] is None and rows[0]["landmark_pairs"] == 4 and rows[0]["bar"] > 0
    assert isinstance(rows[0]["annotate_more"], bool)
    assert "no landmarks" in rows[1]["error"]
    assert list(maps) == ["s1"] and maps.path("s1") == tmp_path / "maps" / "s1.txt"
    assert maps["s1"].shape == (n["template"],)
    with pytest.raises(InputError, match="named 's1'"):
        sc.match_collection(root / "template.off", [root / "s1.off", tmp_path / "s1.off"])


def test_match_collection_refuses_a_bad_match_option_before_any_work(collection, monkeypatch):
    """A misspelt keyword of ``match`` was each shape's row error, after the template had been loaded; it is
    refused once, naming the nearest, before anything is read."""
    from shapecond.api import collection as api_collection

    def no_work(*args, **kwargs):
        raise AssertionError("a shape was loaded before the options were checked")

    monkeypatch.setattr(api_collection, "load", no_work)
    root, _ = collection
    with pytest.raises(InputError, match=r"match_collection\(\) got unknown option 'n_point' for matcher 'lh05' "
                                         r"\(did you mean 'n_points'\?\)"):
        sc.match_collection(root / "template.off", [root / "s1.off"], n_point=30)
    with pytest.raises(InputError, match="suggest must be an integer"):
        sc.match_collection(root / "template.off", [root / "s1.off"], suggest=-1)


def test_a_landmark_table_through_the_command_line(collection, tmp_path, capsys):
    root, _ = collection
    table = tmp_path / "landmarks.csv"
    table.write_text("shape,label,vertex\ntemplate,a,0\ntemplate,b,5\ntemplate,c,9\ns1.off,a,3\ns1.off,c,4\n")
    out = tmp_path / "t.jsonl"
    code, stdout, _ = run_cli(capsys, "batch", root / "s1.off", root / "bare.off", "--what",
                              f"match:{root / 'template.off'}", "--landmarks", table, "--matcher", "zoomout",
                              "--out", out, "--json")
    assert code == 3
    summary = json.loads(stdout)
    assert summary["failed"] == 2 and summary["annotate_more"] == [] and summary["report"].endswith("report.html")
    assert summary["collection_landmark"] is None
    rows = _rows(out)
    assert "2 landmark labels shared with the template (the landmark table's rows of s1.off)" in rows["s1.off"]["error"]
    assert "no landmarks for this shape" in rows["bare.off"]["error"]
    assert json.loads(rows["s1.off"]["params"])["matcher"] == "zoomout"

"""``shapecond batch``: inputs, the row of one shape, the output table, resuming, errors."""

import fcntl
import json
import math
import os
import re
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from shapecond.batch import schema
from shapecond.batch.inputs import content_hash, expand_inputs
from shapecond.batch.rows import DEFAULT_OPTIONS, params_key, parse_what, shape_keywords, shape_row, with_defaults
from shapecond.batch.run import BatchRun, run_batch
from shapecond.batch.table import Table
from shapecond.errors import InputError

from tests.helpers import read_table, run_cli, table_row

# --- inputs ------------------------------------------------------------------------------

def test_folders_globs_and_files_expand_once_each(shape_dir, tmp_path):
    (shape_dir / "notes.txt").write_text("not a point cloud")
    (shape_dir / ".hidden.off").write_text("OFF")
    names = expand_inputs([shape_dir, str(shape_dir / "blob*.off"), shape_dir / "blob0.off", "demo:sphere"])
    rel = [os.path.relpath(n, shape_dir) if not n.startswith("demo:") else n for n in names]
    assert rel == ["blob0.off", "blob1.off", "blob2.off", "sub/ball.off", "demo:sphere"]
    assert expand_inputs([tmp_path / "missing.off"]) == [str(tmp_path / "missing.off")]  # becomes an error row
    with pytest.raises(InputError, match="no file matches"):
        expand_inputs([str(tmp_path / "*.ply")])
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no shape files"):
        expand_inputs([tmp_path / "empty"])


def test_tosca_pairs_hash_both_files(tmp_path):
    (tmp_path / "a.vert").write_text("0 0 0\n1 0 0\n0 1 0\n")
    (tmp_path / "a.tri").write_text("1 2 3\n")
    assert expand_inputs([tmp_path]) == [str(tmp_path / "a.vert")]
    before = content_hash(str(tmp_path / "a.vert"))
    (tmp_path / "a.tri").write_text("1 3 2\n")
    assert content_hash(str(tmp_path / "a.vert")) != before
    with pytest.raises(InputError, match="no such file"):
        content_hash(str(tmp_path / "none.off"))
    (tmp_path / "a.tri").unlink()
    with pytest.raises(InputError, match=r"a\.tri: no such file"):
        content_hash(str(tmp_path / "a.vert"))


def test_what_is_parsed_and_checked():
    w = parse_what(["score,local", "landmarks:4:fps"])
    assert (w.score, w.local, w.landmarks) == (True, True, (4, "fps"))
    assert parse_what(["local"]).items() == ["local"]
    for bad in ("landmarks:0:fps", "landmarks:3:nope", "landmarks:3", "sigma"):
        with pytest.raises(InputError, match="--what"):
            parse_what([bad])
    # the key does not depend on how --what was spelled
    assert params_key({"what": ["local", "score"]}) == params_key({"what": ["score,local"]})


def test_the_stored_options_keep_their_names_and_defaults():
    """A batch's defaults come from the commands' parameter rows (``api.params``) but keep the names and values
    the tables written so far hold in their ``params`` column (written by shapecond 0.x before the rows): a table
    of those still resumes, and a default cannot drift from the commands' without this test failing."""
    assert params_key({"what": ["score"]}) == (
        '{"effort":"default","geodesic_backend":"heat","largest_component":false,"metric":"geodesic","points":null,'
        '"seed":0,"symmetry_map":null,"target":null,"target_factor":8,"what":["score"]}')
    given = {"what": ["score", "landmarks:5:fps"], "points": 50, "no_cache": True, "geodesic_backend": "fmm",
             "epsilon": 0.1}
    assert params_key(given) == (
        '{"effort":"default","epsilon":0.1,"geodesic_backend":"fmm","largest_component":false,"metric":"geodesic",'
        '"points":50,"seed":0,"symmetry_map":null,"target":null,"target_factor":8,"what":["score","landmarks:5:fps"]}')
    assert shape_keywords(with_defaults(given)) == {
        "metric": "geodesic", "backend": "fmm", "seed": 0, "largest_component": False, "cache": False,
        "target": None, "target_factor": 8, "symmetry_map": None, "force": False}


def test_the_batch_command_s_defaults_are_the_stored_defaults(capsys, monkeypatch, tmp_path):
    """``shapecond batch`` with no option hands ``run_batch`` the defaults a stored table's key holds."""
    import shapecond.cli.cmd_batch as cmd_batch

    seen = {}

    def spy(inputs, out, options, what, how):
        seen.update(options)
        raise InputError("stop")

    monkeypatch.setattr(cmd_batch, "run_batch", spy)
    run_cli(capsys, "batch", "demo:sphere", "-o", tmp_path / "never-written.csv")
    assert with_defaults({**seen, "what": ["score"]}) == with_defaults({}) and set(seen) <= set(DEFAULT_OPTIONS)
    assert {k: seen[k] for k in ("points", "geodesic_backend", "no_cache", "effort")} == {
        "points": None, "geodesic_backend": "heat", "no_cache": False, "effort": "default"}


# --- one row is what the single-shape commands print ---------------------------------------

def test_a_row_holds_what_info_score_local_and_landmarks_print(shape_dir, capsys):
    path = shape_dir / "blob1.off"
    opts = {"points": 24, "seed": 3, "effort": "quick", "what": ["score", "local", "landmarks:3:fps"]}
    row = shape_row(str(path), content_hash(str(path)), opts, params_key(opts))
    assert row["error"] is None and set(row) == set(schema.NAMES)
    _, out, _ = run_cli(capsys, "info", path, "--json")
    info = json.loads(out)
    assert (row["vertices"], row["faces"], row["components"]) == (info["n_vertices"], info["n_faces"],
                                                                  info["components"])
    _, out, _ = run_cli(capsys, "score", path, "--points", 24, "--seed", 3, "--effort", "quick", "--json")
    sc = json.loads(out)
    assert row["sigma_lower"] == pytest.approx(sc["sigma"]["lower"], rel=1e-12)
    assert row["sigma_hat"] == pytest.approx(sc["sigma_hat"]["lower"], rel=1e-12)
    assert row["resolution"] == sc["resolution"]["flag"]
    assert (row["n_points"], row["n_targets"]) == (sc["n_points"], sc["n_targets"])
    moved = sum(w != s for w, s in zip(sc["witness_vertices"], sc["samples"])) / sc["n_points"]
    assert row["witness_moved"] == pytest.approx(moved)
    assert 0 < row["witness_displacement"] <= 1
    _, out, _ = run_cli(capsys, "local", path, "--json")
    assert row["local_score"] == pytest.approx(json.loads(out)["score"], rel=1e-9)
    _, out, _ = run_cli(capsys, "landmarks", path, "-k", 3, "--method", "fps", "--points", 24, "--seed", 3,
                        "--effort", "quick", "--scores", "--json")
    lm = json.loads(out)
    assert row["landmarks"] == lm["landmarks"]
    assert row["landmark_scores"] == pytest.approx(lm["scores"], rel=1e-12)
    assert row["peak_memory_mib"] > 10 and row["seconds"] > 0 and row["cpu_seconds"] > 0


def test_bad_inputs_become_error_rows_and_exit_3(broken_dir, tmp_path, capsys):
    out = tmp_path / "t.jsonl"
    status, stdout, err = run_cli(capsys, "batch", broken_dir, "--points", 16, "--out", out, "--json")
    assert status == 3, err
    summary = json.loads(stdout)
    rows = {Path(r["file"]).name: r for r in read_table(out)}
    assert summary["shapes"] == len(rows) == 8 and summary["failed"] == 7
    assert rows["good.off"]["error"] is None and rows["good.off"]["sigma_lower"] > 0
    for name, pattern in {"empty.off": "empty", "garbage.off": "not an OFF file",
                          "binary.ply": "binary.ply: ", "wrong_shape.npy": r"\(4, 5\)",
                          "nan.off": "NaN", "two_parts.off": "2 connected components",
                          "dangling.off": "a symbolic link to a missing file"}.items():
        assert re.search(pattern, rows[name]["error"]), (name, rows[name]["error"])
        assert "\n" not in rows[name]["error"]
    # info's columns are kept when only scoring failed
    assert rows["two_parts.off"]["components"] == 2 and "2 connected components" in rows["two_parts.off"]["problems"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads files whatever their permissions")
def test_an_unreadable_file_is_an_error_row(shape_dir, tmp_path):
    locked = tmp_path / "locked.off"
    locked.write_bytes((shape_dir / "blob0.off").read_bytes())
    locked.chmod(0)
    summary = run_batch([locked], tmp_path / "t.csv", {"points": 16})
    assert summary.failed == 1 and "ermission" in summary.failures[0]["error"]


# --- the table ---------------------------------------------------------------------------

@pytest.mark.parametrize("suffix", [".parquet", ".csv", ".jsonl"])
def test_rows_survive_a_round_trip_and_one_writer_at_a_time(tmp_path, suffix):
    path = tmp_path / f"t{suffix}"
    rows = [table_row(1), table_row(2, error="boom")]
    with Table(path) as table:
        for r in rows:
            table.append(r)
        with pytest.raises(InputError, match="being written by another batch"):
            with Table(path, "resume"):
                pass
    with Table(path, "resume") as table:
        again = table.rows
    assert [{k: r[k] for k in schema.NAMES} for r in again] == [schema.coerce_row(r) for r in rows]
    assert again[0]["sigma_lower"] == math.inf and again[0]["landmarks"] == [1, 7]
    assert read_table(path) == again
    with pytest.raises(InputError, match="already holds 2 rows"):
        with Table(path):
            pass
    with Table(path, "overwrite") as table:
        assert table.rows == []
    assert read_table(path) == [] and not list(tmp_path.glob(".*"))  # no lock or journal left


@pytest.mark.parametrize("suffix", [".csv", ".jsonl"])
def test_a_torn_last_line_is_cut(tmp_path, suffix):
    path = tmp_path / f"t{suffix}"
    with Table(path) as table:
        table.append(table_row(1))
    with open(path, "a") as fh:
        fh.write('"/s/2.off",h2,{' if suffix == ".csv" else '{"file": "/s/2.off", "content_')  # died mid-line
    with pytest.warns(UserWarning, match="cut its incomplete last line"), Table(path, "resume") as table:
        assert [r["file"] for r in table.rows] == ["/s/1.off"]
        table.append(table_row(3))
    assert [r["file"] for r in read_table(path)] == ["/s/1.off", "/s/3.off"]


def test_a_parquet_journal_left_by_a_killed_batch_is_folded_in(tmp_path):
    path = tmp_path / "t.parquet"
    with Table(path) as table:
        table.append(table_row(1))
    journal = tmp_path / ".t.parquet.journal"
    with open(journal, "w") as fh:  # row 1 again (killed between rewrite and journal reset) and row 2
        for r in (table_row(1), table_row(2)):
            fh.write(json.dumps({k: r[k] for k in schema.NAMES}).replace("Infinity", '"inf"') + "\n")
    with Table(path, "resume") as table:
        assert [r["file"] for r in table.rows] == ["/s/1.off", "/s/2.off"]
        assert [r["file"] for r in read_table(path)] == ["/s/1.off", "/s/2.off"]  # rewritten on opening
    assert not journal.exists()


def test_output_errors_are_refused_before_any_work(shape_dir, tmp_path, capsys):
    for args, message in [(["--out", tmp_path / "t.xlsx"], "unknown table format"),
                          (["--out", tmp_path / "no" / "t.csv"], "does not exist"),
                          (["--out", tmp_path / "t.csv", "--resume", "--overwrite"], "exclude each other"),
                          (["--out", tmp_path / "t.csv", "--what", "landmarks:2:magic"], "unknown method"),
                          (["--out", tmp_path / "t.csv", "--scheduler", "local:0"], "local:W"),
                          (["--out", tmp_path / "t.csv", "--jobs", "2", "--scheduler", "local:2"],
                           "exclude each other")]:
        status, _, err = run_cli(capsys, "batch", shape_dir / "blob0.off", *args)
        assert status == 2 and message in err and err.count("\n") == 1, (args, err)
    (tmp_path / "notes.csv").write_text("a,b\n1,2\n")
    status, _, err = run_cli(capsys, "batch", shape_dir / "blob0.off", "--out", tmp_path / "notes.csv",
                             "--resume")
    assert status == 2 and "columns are not those" in err


# --- resuming ----------------------------------------------------------------------------

def test_resume_skips_done_shapes_and_rescores_changed_ones(shape_dir, tmp_path):
    work = tmp_path / "in"
    work.mkdir()
    for name in ("blob0.off", "blob1.off"):
        (work / name).write_bytes((shape_dir / name).read_bytes())
    out = tmp_path / "t.parquet"
    first = run_batch([work], out, {"points": 16})
    assert (first.scored, first.failed) == (2, 0)
    again = run_batch([work], out, {"points": 16}, how=BatchRun(resume=True))
    assert (again.scored, again.resumed, again.where) == (0, 2, "nothing to do")
    (work / "blob1.off").write_bytes((shape_dir / "blob2.off").read_bytes())  # new content, same name
    third = run_batch([work], out, {"points": 16}, how=BatchRun(resume=True))
    assert (third.scored, third.resumed) == (1, 1)
    other = run_batch([work], out, {"points": 18}, how=BatchRun(resume=True))  # other parameters: other rows
    assert other.scored == 2
    assert len(read_table(out)) == 5


def test_the_batch_page_documents_every_column():
    readme = (Path(__file__).parents[2] / "docs" / "batch.md").read_text()  # linked from the README's batch section
    table = readme[readme.index("| column |"):]
    table = table[:table.index("\n\n", table.index("| column |"))]
    assert all(f"`{name}`" in table for name in schema.NAMES), [n for n in schema.NAMES if f"`{n}`" not in table]


def test_delta_at_a_given_level_or_at_the_collections_own_level(tmp_path, capsys):
    """``--epsilon`` for every shape, or ``--epsilon-from-collection``: the first shape matched to the next
    ones, the median distortion of the maps; the default keeps the key of the tables written before."""
    assert "epsilon" not in json.loads(params_key({}))
    shapes = ["demo:animal", "demo:animal:delta=0.1", "demo:animal:delta=0.05"]
    base = ["--points", 30, "--effort", "quick", "--no-cache", "--json"]
    code, out, err = run_cli(capsys, "batch", *shapes, "-o", tmp_path / "given.csv", *base, "--epsilon", 0.05)
    s = json.loads(out)
    assert code == 0, err
    assert s["epsilon"] == 0.05 and s["epsilon_source"] == "given (--epsilon)"
    assert [r["delta_epsilon"] for r in read_table(tmp_path / "given.csv")] == [0.05] * 3
    code, out, err = run_cli(capsys, "batch", *shapes, "-o", tmp_path / "coll.csv", *base, "--epsilon-from-collection")
    s = json.loads(out)
    assert code == 0, err
    assert s["epsilon_source"].startswith("the collection's level, read off 2 matched map(s) (faq)")
    import shapecond as sc
    level = sc.deformation_level(shapes[0], shapes[1:], n_points=30, cache=False)
    assert s["epsilon"] == pytest.approx(level.epsilon) and s["epsilon"] > 0
    rows = read_table(tmp_path / "coll.csv")
    assert all(r["delta_epsilon"] == pytest.approx(s["epsilon"]) for r in rows)
    assert all(json.loads(r["params"])["epsilon"] == pytest.approx(s["epsilon"]) for r in rows)
    code, out, err = run_cli(capsys, "batch", shapes[0], "-o", tmp_path / "one.csv", *base, "--epsilon-from-collection")
    assert code == 2 and "at least two readable shapes" in err and not (tmp_path / "one.csv").exists()


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_a_lock_whose_named_batch_is_dead_is_taken_over(tmp_path, suffix):
    """A process left by a killed batch (e.g. a helper it forked) held its lock: every --resume was refused,
    naming the dead batch."""
    path = tmp_path / f"t{suffix}"
    lock = tmp_path / f".t{suffix}.lock"
    lock.write_text(f"host {socket.gethostname()}, pid {_dead_pid()}\n")
    fd = os.open(lock, os.O_RDWR)
    fcntl.flock(fd, fcntl.LOCK_EX)  # the left process's hold on the dead batch's lock
    try:
        with pytest.warns(UserWarning, match="took over the lock of a batch that is no longer running"):
            with Table(path, "resume") as table:
                table.append(table_row(1))
                assert f"pid {os.getpid()}" in lock.read_text()
        assert len(read_table(path)) == 1
        lock.write_text(f"host {socket.gethostname()}, pid {os.getpid()}\n")  # a live holder: refused
        fd2 = os.open(lock, os.O_RDWR)
        fcntl.flock(fd2, fcntl.LOCK_EX)
        try:
            with pytest.raises(InputError, match="being written by another batch"):
                with Table(path, "resume"):
                    pass
        finally:
            os.close(fd2)
    finally:
        os.close(fd)


@pytest.mark.slow
def test_the_collections_level_comes_from_its_first_readable_shapes(tmp_path, capsys):
    """batch bad.off a.off b.off --epsilon-from-collection stopped the whole batch on bad.off."""
    (tmp_path / "bad.off").write_text("this is not a mesh\n")
    shapes = [tmp_path / "bad.off", "demo:animal", "demo:animal:delta=0.1"]
    code, out, err = run_cli(capsys, "batch", *shapes, "-o", tmp_path / "t.csv", "--points", 30, "--effort",
                             "quick", "--no-cache", "--json", "--epsilon-from-collection")
    assert code == 3, err  # the bad shape's error row; the others scored at the level of the two readable ones
    s = json.loads(out)
    assert s["epsilon_source"].startswith("the collection's level, read off 1 matched map(s)")
    assert "bad.off: not used for the collection's level" in err
    rows = read_table(tmp_path / "t.csv")
    assert [bool(r["error"]) for r in rows] == [True, False, False]
    assert all(r["delta_epsilon"] == pytest.approx(s["epsilon"]) for r in rows[1:])


def test_links_loops_and_fifos_in_a_folder_are_never_dropped_without_a_word(tmp_path):
    """A link to a folder (a loop among them) was skipped without a word; a FIFO or a file link loop is listed
    and becomes an error row that says what it is."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.off").write_text("OFF\n")
    (tmp_path / "sub" / "b.off").write_text("OFF\n")
    os.symlink(".", tmp_path / "sub" / "self")
    os.symlink(tmp_path / "sub", tmp_path / "linkdir")
    os.mkfifo(tmp_path / "fifo.off")
    os.symlink("loop.off", tmp_path / "loop.off")
    with pytest.warns(UserWarning) as caught:
        found = expand_inputs([tmp_path])
    assert [os.path.relpath(p, tmp_path) for p in found] == ["a.off", "fifo.off", "loop.off", "sub/b.off"]
    said = sorted(str(w.message).split(":")[0] for w in caught)
    assert said == [str(tmp_path / "linkdir"), str(tmp_path / "sub" / "self")]
    assert all("a link to a folder, not followed" in str(w.message) for w in caught)

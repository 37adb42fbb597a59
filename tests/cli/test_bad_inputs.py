"""Every bad input gets one line: the table of ``bad_inputs`` through every sub-command and function.

Each command-line case must end with exit status 2, exactly one ``error:``
line on stderr (no traceback, no "internal failure"), nothing on stdout, no
file written and none of the table's files changed (a batch output must not
touch a user's file), within its time limit (10 s for FIFOs, devices and batch
outputs, which used to hang); each Python case must raise one ``InputError``
with a one-line message.
"""

import os
import shutil
import stat

import pytest

from shapecond.errors import InputError
from tests.cli.bad_inputs import api_cases, cli_cases, make_files, time_limit
from tests.helpers import deadline, run_cli


def files_state(folder) -> dict:
    """Kind, size, mtime, inode and link target of every file the table made (not out/, not the cache)."""
    state = {}
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if not (root == str(folder) and d in ("out", "cache"))]
        for name in dirs + files:
            p = os.path.join(root, name)
            st = os.lstat(p)
            state[p] = (st.st_mode, st.st_size, st.st_mtime_ns, st.st_ino,
                        os.readlink(p) if stat.S_ISLNK(st.st_mode) else None)
    return state

def test_the_table_covers_every_class_and_command(tmp_path):
    CASES = cli_cases(tmp_path)
    classes = {c.split(" ")[0] + " " + c.split(" ")[1] for c, _ in CASES}
    assert len(CASES) >= 500
    for kind in ("shape file", "generated shape", "id file", "id list", "option --seed", "option --alpha",
                 "symmetry map", "evaluate dataset", "batch output"):
        assert any(c.startswith(kind) for c in classes), kind
    commands = {argv[0] for _, argv in CASES}
    assert commands == {"info", "sample", "score", "kappa", "local", "landmarks", "heatmap", "match", "evaluate",
                        "demo", "batch"}


def test_every_bad_command_line_is_one_error_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path / "cache"))
    failures = []
    cases = cli_cases(tmp_path)
    before = files_state(tmp_path)
    for cls, argv in cases:
        out_dir = tmp_path / "out"
        with deadline(time_limit(cls)):  # a hang ends as "internal failure: TimeoutError"
            code, out, err = run_cli(capsys, *argv)
        lines = err.strip().splitlines()
        ok = (code == 2 and out == "" and len(lines) == 1 and lines[0].startswith("error: ")
              and "Traceback" not in err and "internal failure" not in err)
        written = sorted(p.name for p in out_dir.rglob("*")) if out_dir.exists() else []
        shutil.rmtree(out_dir, ignore_errors=True)
        after = files_state(tmp_path)
        changed = sorted(os.path.relpath(p, tmp_path) for p in set(before) | set(after)
                         if before.get(p) != after.get(p))
        if not ok or written or changed:
            failures.append(f"{cls}: exit {code}, stderr {err.strip()[:160]!r}, written {written}, changed {changed}")
        before = after
    assert not failures, f"{len(failures)} cases:\n" + "\n".join(failures[:40])


def test_every_bad_python_call_raises_one_input_error(tmp_path, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path / "cache"))
    failures = []
    for cls, call in api_cases(tmp_path):
        try:
            call()
        except InputError as exc:
            if not str(exc) or "\n" in str(exc):
                failures.append(f"{cls}: message {str(exc)!r}")
        except Exception as exc:  # noqa: BLE001 - the point is to catch anything else
            failures.append(f"{cls}: {exc.__class__.__name__}: {str(exc)[:120]}")
        else:
            failures.append(f"{cls}: no error")
    assert not failures, f"{len(failures)} cases:\n" + "\n".join(failures[:40])


@pytest.mark.parametrize("argv,needle", [
    (["score", "demo:torus:minor=0"], "minor"),
    (["score", "demo:plane:n=1000"], "--force"),
    (["score", "demo:sphere:subdivisions=14"], "subdivisions must be an integer in [0, 8]"),
    (["local", "demo:sphere:subdivisions=1", "--alpha", "0"], "--alpha must be"),
    (["score", "demo:sphere:subdivisions=1", "--seed", "-1"], "--seed must be an integer"),
])
def test_messages_name_the_value_and_what_is_allowed(capsys, argv, needle):
    code, _, err = run_cli(capsys, *argv)
    assert code == 2 and needle in err


def test_binary_content_is_named_not_quoted(tmp_path, capsys, monkeypatch):
    """evaluate's vertex-count probe quoted the first 'word' of a binary file: '\\x00ÿ\\x00ÿ...'."""
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path / "cache"))
    f = make_files(tmp_path)
    for argv in (["evaluate", f["dataset_binary"], "--out", tmp_path / "out", "--no-cache"],
                 ["score", f["off_binary.off"], "--no-cache"]):
        code, _, err = run_cli(capsys, *argv)
        assert code == 2 and "binary data" in err and "\\x00" not in err and "ÿ" not in err, err

"""The one atomic writer: every output survives a kill, never follows a planted link, handles streams."""

import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest

import shapecond.output as output
from shapecond.errors import OutputError
from shapecond.output import atomic_open, write_bytes
from tests.helpers import run_cli

GOOD = "demo:sphere:subdivisions=2"


def test_failure_inside_the_block_keeps_the_old_file_and_leaves_nothing(tmp_path):
    target = write_bytes(tmp_path / "out.bin", b"old")
    with pytest.raises(RuntimeError):
        with atomic_open(target) as fh:
            fh.write(b"half")
            raise RuntimeError("boom")
    assert target.read_bytes() == b"old" and os.listdir(tmp_path) == ["out.bin"]


@pytest.mark.parametrize("tmpfile", [True, False], ids=["O_TMPFILE", "named temporary"])
def test_killed_mid_write_keeps_the_previous_file_and_no_temporary(tmp_path, tmpfile):
    """A child writes a new sample file and is SIGKILLed on its first write."""
    target = tmp_path / "s.npz"
    target.write_bytes(b"previous good file")
    script = textwrap.dedent(f"""
        import os, signal, sys
        import shapecond.output as output
        output.USE_TMPFILE = {tmpfile}
        real = os.fdopen
        class Killer:
            def __init__(self, f): self.f = f
            def write(self, data):
                os.kill(os.getpid(), signal.SIGKILL)
            def __getattr__(self, name): return getattr(self.f, name)
        output.os.fdopen = lambda *a, **k: Killer(real(*a, **k))
        from shapecond.cli import main
        main(["sample", "{GOOD}", "--points", "10", "--no-cache", "-o", r"{target}"])
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=300)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.decode()[-400:]
    assert target.read_bytes() == b"previous good file"
    leftovers = [p for p in os.listdir(tmp_path) if p != "s.npz"]
    if tmpfile:
        assert leftovers == []
    else:  # a named temporary file cannot be removed by a process killed with SIGKILL
        assert all(p.startswith(".s.npz.") and p.endswith(".tmp") for p in leftovers)


@pytest.mark.parametrize("tmpfile", [True, False], ids=["O_TMPFILE", "named temporary"])
def test_a_kill_between_link_and_rename_leaves_a_temporary_that_the_next_write_removes(tmp_path, tmpfile):
    """SIGKILL at the rename: the complete temporary file has its name; the next write of the target
    (any writer: here the library's) removes it."""
    target = tmp_path / "m.txt"
    target.write_text("previous")
    script = textwrap.dedent(f"""
        import os, signal
        import shapecond.output as output
        output.USE_TMPFILE = {tmpfile}
        output.os.replace = lambda *a: os.kill(os.getpid(), signal.SIGKILL)
        output.write_text(r"{target}", "new map")
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=120)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.decode()[-400:]
    (left,) = [p for p in os.listdir(tmp_path) if p != "m.txt"]
    assert re.fullmatch(r"\.m\.txt\.[0-9a-f]{16}\.tmp", left) and (tmp_path / left).read_text() == "new map"
    output.write_text(target, "newer")
    assert os.listdir(tmp_path) == ["m.txt"] and target.read_text() == "newer"


def test_a_live_writers_temporary_file_and_planted_names_are_left_alone(tmp_path, monkeypatch):
    monkeypatch.setattr(output, "USE_TMPFILE", False)
    target = tmp_path / "m.txt"
    fd, live = output._open_temp(tmp_path, "m.txt")  # another process writing the same target right now
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    planted = tmp_path / ".m.txt.0123456789abcdef.tmp"
    planted.symlink_to(victim)
    fifo = tmp_path / ".m.txt.fedcba9876543210.tmp"
    os.mkfifo(fifo)
    try:
        output.write_text(target, "mine")
        assert live.exists() and planted.is_symlink() and stat.S_ISFIFO(os.lstat(fifo).st_mode)
    finally:
        os.close(fd)  # the writer dies: its file is stale now
    output.write_text(target, "mine again")
    assert not live.exists() and planted.is_symlink() and victim.read_text() == "precious"


WRITERS = {
    "sample -o": lambda d: ["sample", GOOD, "--points", "10", "--no-cache", "-o", d / "s.npz"],
    "match -o": lambda d: ["match", GOOD, GOOD, "--landmarks-source", "0", "--landmarks-target", "0",
                           "--points", "10", "--no-cache", "-o", d / "m.txt"],
    "score --witness-png": lambda d: ["score", GOOD, "--points", "10", "--no-cache", "--witness-png", d / "w.png"],
    "landmarks --png --ply": lambda d: ["landmarks", GOOD, "-k", "2", "--method", "fps", "--points", "10",
                                        "--no-cache", "--png", d / "l.png", "--ply", d / "l.ply"],
    "heatmap --png --ply": lambda d: ["heatmap", GOOD, "--points", "10", "--no-cache", "--png", d / "h.png",
                                      "--ply", d / "h.ply"],
    "local --heatmap-png": lambda d: ["local", "demo:sphere:subdivisions=1", "--heatmap-png", d / "lh.png"],
    "demo": lambda d: ["demo", "--points", "20", "--landmark-points", "10", "--out", d],
    "cache (score)": lambda d: ["score", GOOD, "--points", "10"],
}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n == "demo" else n for n in WRITERS])
@pytest.mark.parametrize("tmpfile", [True, False], ids=["O_TMPFILE", "named temporary"])
def test_a_symlink_planted_at_the_temporary_name_is_never_followed(tmp_path, capsys, monkeypatch, name, tmpfile):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "out"
    out.mkdir()
    monkeypatch.setenv("SHAPECOND_CACHE", str(out))
    monkeypatch.setattr(output, "USE_TMPFILE", tmpfile)
    planted = []
    real = output._temp_name

    def plant_first(folder, base):
        link = real(folder, base)
        os.symlink(victim, link)  # the attacker guessed this name
        planted.append(link)
        monkeypatch.setattr(output, "_temp_name", real)
        return link

    monkeypatch.setattr(output, "_temp_name", plant_first)
    code, _, err = run_cli(capsys, *WRITERS[name](out))
    assert code == 0, err
    assert victim.read_text() == "precious" and planted
    written = [p for p in out.rglob("*") if p.is_file() and not p.is_symlink()]
    assert written and all(p.stat().st_size > 0 for p in written)


def test_a_symlink_at_the_target_is_replaced_not_followed(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    link = tmp_path / "out.txt"
    link.symlink_to(victim)
    output.write_text(link, "new")
    assert victim.read_text() == "precious" and not link.is_symlink() and link.read_text() == "new"


def test_streams_are_written_not_replaced(tmp_path, capsys):
    fifo = tmp_path / "fifo.npz"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(open(fifo, "rb").read()))
    reader.start()
    code, _, err = run_cli(capsys, "sample", GOOD, "--points", "10", "--no-cache", "-o", fifo)
    reader.join(timeout=60)
    assert code == 0, err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and got and got[0][:2] == b"PK"  # a zip archive came through
    link = tmp_path / "null.txt"
    link.symlink_to(os.devnull)
    code, _, err = run_cli(capsys, "match", GOOD, GOOD, "--landmarks-source", "0", "--landmarks-target", "0",
                           "--points", "10", "--no-cache", "-o", link)
    assert code == 0 and link.is_symlink() and stat.S_ISCHR(os.stat(link).st_mode)


def test_a_fifo_nobody_reads_is_refused_in_one_line(tmp_path, capsys):
    fifo = tmp_path / "lonely.npz"
    os.mkfifo(fifo)
    code, out, err = run_cli(capsys, "sample", GOOD, "--points", "10", "--no-cache", "-o", fifo)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "no process is reading" in err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_a_folder_or_a_missing_parent(tmp_path):
    with pytest.raises(OutputError, match="is a folder"):
        output.write_text(tmp_path, "x")
    with pytest.raises(OutputError, match="does not exist"):
        output.write_text(tmp_path / "no" / "x.txt", "x", make_parents=False)
    assert output.write_text(tmp_path / "made" / "x.txt", "x").read_text() == "x"


def _full_disk_command(folder: Path, argv) -> list[str] | None:
    """argv run with a 64 kB tmpfs mounted at ``folder`` (a private mount namespace), or None."""
    unshare = shutil.which("unshare")
    if unshare is None:
        return None
    probe = subprocess.run([unshare, "-Urm", "sh", "-c", f"mount -t tmpfs -o size=64k tmpfs {folder}"],
                           capture_output=True)
    if probe.returncode != 0:
        return None
    cmd = " ".join(f"'{a}'" for a in argv)
    return [unshare, "-Urm", "sh", "-c", f"mount -t tmpfs -o size=64k tmpfs {folder} && exec {cmd}"]


def test_a_full_file_system_is_one_clean_error_and_no_partial_output(tmp_path):
    folder = tmp_path / "small"
    folder.mkdir()
    target = folder / "s.npz"  # N = 120 samples: a 115 kB matrix does not fit in 64 kB
    argv = [sys.executable, "-m", "shapecond", "sample", GOOD, "--points", "120", "--no-cache", "-o", str(target)]
    env = dict(os.environ, SHAPECOND_CACHE=str(tmp_path / "cache"))
    cmd = _full_disk_command(folder, argv)
    if cmd is not None:  # a real full file system
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)
        reason = "No space left on device"
        listing = subprocess.run(["ls", "-A", str(folder)], capture_output=True, text=True).stdout
    else:  # no mount namespace here: a file-size limit gives the same path through the writer (EFBIG)
        import resource

        def limit():
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (64 * 1024, 64 * 1024))

        proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=300, preexec_fn=limit)
        reason = "File too large"
        listing = "\n".join(os.listdir(folder))
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and lines[0].startswith("error: ") and reason in lines[0] and "s.npz" in lines[0]
    assert "Traceback" not in proc.stderr and listing.strip() == ""
    if cmd is None:
        assert not target.exists()


def test_the_cache_folder_is_written_through_the_writer(tmp_path, monkeypatch):
    from shapecond import cache

    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path))
    cache.save_arrays("x", "k" * 32, {"a": np.arange(3)})
    assert cache.load_arrays("x", "k" * 32, {"a": (3,)})["a"].tolist() == [0, 1, 2]
    assert sorted(p.name for p in tmp_path.iterdir()) == [cache.SECRET_NAME, f"x-{'k' * 32}.npz"]


def test_what_a_compiled_library_writes_to_fd_1_is_diverted_and_python_stdout_is_kept():
    script = textwrap.dedent("""
        import ctypes, os, sys
        from shapecond.output import stdout_fd_diverted
        libc = ctypes.CDLL(None)
        with stdout_fd_diverted(keep_python_stdout=True):
            os.write(1, b"raw\\n")
            libc.printf(b"c-stdio\\n")
            print("python")
            with stdout_fd_diverted(os.devnull):
                os.write(1, b"dropped\\n")
        print("after")
        os.write(1, b"raw-after\\n")
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "python\nafter\nraw-after\n"
    assert proc.stderr == "raw\nc-stdio\n"


def _listing(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def test_a_staged_set_appears_together_or_not_at_all(tmp_path):
    out = tmp_path / "out"
    with output.staged_outputs(out) as stage:
        output.write_text(stage / "a.json", "1")
        output.write_text(stage / "b.md", "one")
        assert not (out / "a.json").exists()
    assert _listing(out) == {"a.json": b"1", "b.md": b"one"}
    with pytest.raises(RuntimeError):  # a failure: the earlier set stays, nothing of the new one
        with output.staged_outputs(out) as stage:
            output.write_text(stage / "a.json", "2")
            raise RuntimeError("the figure failed")
    assert _listing(out) == {"a.json": b"1", "b.md": b"one"}
    with pytest.raises(RuntimeError):  # unless what was written must outlive the failure
        with output.staged_outputs(out, publish_on_error=True) as stage:
            output.write_text(stage / "a.json", "3")
            raise RuntimeError("the figure failed")
    assert _listing(out) == {"a.json": b"3", "b.md": b"one"}
    (out / "c.png").mkdir()  # a folder in the way: refused before any file is moved
    with pytest.raises(OutputError, match="c.png: is a folder"):
        with output.staged_outputs(out) as stage:
            output.write_text(stage / "a.json", "4")
            output.write_text(stage / "c.png", "x")
    assert (out / "a.json").read_text() == "3"
    (out / "c.png").rmdir()
    (out / "d.md").symlink_to(os.devnull)  # a stream is written to, as by atomic_open, not replaced
    with output.staged_outputs(out) as stage:
        output.write_text(stage / "d.md", "to the stream")
    assert (out / "d.md").is_symlink()
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


def test_a_killed_writers_staging_folder_is_removed_by_the_next_and_a_live_ones_kept(tmp_path):
    import fcntl

    out = tmp_path / "out"
    (out / ".staged-00000000000000aa").mkdir(parents=True)  # left by a kill -9
    (out / ".staged-00000000000000aa" / "results.json").write_text("half")
    live = out / ".staged-00000000000000bb"
    live.mkdir()
    fd = os.open(live, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX)  # another writer, still running
    (out / ".staged-notours").mkdir()  # not a staging name: left alone
    try:
        output.write_text(out / "x", "untouched by staged writes")
        with output.staged_outputs(out) as stage:
            output.write_text(stage / "a.json", "1")
        assert sorted(p.name for p in out.iterdir()) == [".staged-00000000000000bb", ".staged-notours", "a.json", "x"]
    finally:
        os.close(fd)


def test_check_distinct_refuses_an_input_or_a_repeated_output_through_links(tmp_path):
    from shapecond.errors import InputError
    from shapecond.output import check_distinct

    mesh = tmp_path / "in.off"
    mesh.write_text("OFF\n")
    (tmp_path / "link.off").symlink_to(mesh)
    os.link(mesh, tmp_path / "hard.off")
    for out in ("in.off", "link.off", "hard.off", "sub/../in.off"):
        (tmp_path / "sub").mkdir(exist_ok=True)
        with pytest.raises(InputError, match="an output may not overwrite an input"):
            check_distinct([("--html", tmp_path / out)], [("INPUT", str(mesh))])
    with pytest.raises(InputError, match="give each output its own file"):
        check_distinct([("-o", tmp_path / "new.txt"), ("--html", tmp_path / "sub" / ".." / "new.txt")])
    check_distinct([("-o", tmp_path / "a.txt"), ("--html", tmp_path / "b.html")], [("INPUT", "demo:blob")])
    check_distinct([("-o", "/dev/null"), ("--html", "/dev/null")])  # streams are never replaced

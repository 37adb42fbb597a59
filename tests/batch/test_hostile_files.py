"""``shapecond batch`` among hostile files: FIFOs, devices and dangling links as inputs; links, FIFOs,
foreign files, a read-only folder and a full disk at the output.  Every case ends within 10 s, exits 2
with one line (or gives error rows, exit 3, for bad inputs) and leaves every file that is not the
batch's own exactly as it was."""

import base64
import os
import resource
import shutil
import signal
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers import deadline, read_table, run_cli, run_shapecond, table_row

GOOD = "demo:sphere:subdivisions=1"


def test_fifos_devices_and_dangling_links_among_the_inputs_are_error_rows_not_hangs(tmp_path):
    fifo = tmp_path / "pipe.off"
    os.mkfifo(fifo)
    dangling = tmp_path / "gone.off"
    dangling.symlink_to(tmp_path / "no-such-target.off")
    status, _, err = run_shapecond("batch", fifo, "/dev/zero", dangling, "--points", 12, "--out", tmp_path / "t.jsonl")
    assert status == 3, err
    rows = {r["file"]: r["error"] for r in read_table(tmp_path / "t.jsonl")}
    assert "is a FIFO" in rows[str(fifo)] and "is a device" in rows["/dev/zero"]
    assert "a symbolic link to a missing file" in rows[str(dangling)]
    assert not any("on worker" in e for e in rows.values())  # this process could not read them either


# --- the output: only the batch's own table is ever written ------------------------------------------

FORMATS = [".csv", ".jsonl", ".parquet"]


def state(folder: Path) -> dict:
    """Everything about the files of ``folder``: kind, bytes or link target, size and mtime."""
    out = {}
    for p in sorted(folder.rglob("*")):
        st = p.lstat()
        if stat.S_ISLNK(st.st_mode):
            out[p.name] = ("link", os.readlink(p))
        elif stat.S_ISREG(st.st_mode):
            out[p.name] = ("file", p.read_bytes(), st.st_mtime_ns, st.st_nlink)
        else:
            out[p.name] = (stat.S_IFMT(st.st_mode), st.st_mtime_ns)
    return out


def refused(capsys, folder, out, *extra, needle=""):
    """Run a batch onto ``out``; assert exit 2, one error line containing ``needle``, nothing changed."""
    before = state(folder)
    with deadline(10):
        status, stdout, err = run_cli(capsys, "batch", GOOD, "--points", 8, "--no-cache", "--out", out, *extra)
    lines = err.strip().splitlines()
    assert status == 2 and stdout == "" and len(lines) == 1 and lines[0].startswith("error: "), err
    assert needle in lines[0], lines[0]
    assert state(folder) == before


def foreign(path: Path) -> None:
    """A user's file at ``path`` whose last line is torn: notes, another program's table."""
    if path.suffix == ".parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        pq.write_table(pa.table({"file": ["a"], "score": [1.0]}), path)
    elif path.suffix == ".csv":
        path.write_text("a,b\n1,2\n3,")
    else:
        path.write_text('{"note": 1}\n{"note": 2}\n{"tor')


@pytest.mark.parametrize("mode", [[], ["--resume"], ["--overwrite"]], ids=["new", "resume", "overwrite"])
@pytest.mark.parametrize("suffix", FORMATS)
def test_a_foreign_file_at_the_output_is_refused_and_left_as_it_was(tmp_path, capsys, suffix, mode):
    foreign(tmp_path / f"notes{suffix}")
    refused(capsys, tmp_path, tmp_path / f"notes{suffix}", *mode, needle="batch table")


@pytest.mark.parametrize("suffix", FORMATS)
def test_an_old_or_foreign_journal_or_lock_is_refused_and_left_as_it_was(tmp_path, capsys, suffix):
    (tmp_path / f".t{suffix}.lock").write_text("my shopping list\n")
    refused(capsys, tmp_path, tmp_path / f"t{suffix}", needle="not a lock file")
    (tmp_path / f".t{suffix}.lock").unlink()
    (tmp_path / "mine.txt").write_text("")
    os.link(tmp_path / "mine.txt", tmp_path / f".t{suffix}.lock")  # an empty file of the user's, hard-linked
    refused(capsys, tmp_path, tmp_path / f"t{suffix}", needle="not a lock file")
    (tmp_path / f".t{suffix}.lock").unlink()
    if suffix == ".parquet":
        (tmp_path / ".t.parquet.journal").write_text("a,b\n1,2\n")
        refused(capsys, tmp_path, tmp_path / "t.parquet", "--resume", needle="not a row of a batch table")


@pytest.mark.parametrize("where", ["output", "lock", "journal"])
@pytest.mark.parametrize("suffix", FORMATS)
def test_links_at_the_output_lock_or_journal_are_refused_and_their_targets_untouched(tmp_path, capsys, suffix,
                                                                                     where):
    if where == "journal" and suffix != ".parquet":
        pytest.skip("only Parquet tables have a journal")
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    name = {"output": f"t{suffix}", "lock": f".t{suffix}.lock", "journal": f".t{suffix}.journal"}[where]
    (tmp_path / name).symlink_to(victim)
    refused(capsys, tmp_path, tmp_path / f"t{suffix}", needle="symbolic link")
    (tmp_path / name).unlink()
    (tmp_path / name).symlink_to(tmp_path / "missing.txt")  # dangling: never created through the link
    refused(capsys, tmp_path, tmp_path / f"t{suffix}", needle="symbolic link")
    assert not (tmp_path / "missing.txt").exists()


@pytest.mark.parametrize("where", ["output", "lock", "journal"])
def test_fifos_at_the_output_lock_or_journal_are_refused_without_hanging(tmp_path, where):
    name = {"output": "t.parquet", "lock": ".t.parquet.lock", "journal": ".t.parquet.journal"}[where]
    os.mkfifo(tmp_path / name)
    status, _, err = run_shapecond("batch", GOOD, "--points", 8, "--out", tmp_path / "t.parquet")
    assert status == 2 and len(err.strip().splitlines()) == 1 and "is a FIFO" in err, err
    assert sorted(os.listdir(tmp_path)) == [name]
    for suffix in (".csv", ".jsonl"):
        os.mkfifo(tmp_path / f"t{suffix}")
        status, _, err = run_shapecond("batch", GOOD, "--points", 8, "--out", tmp_path / f"t{suffix}")
        assert status == 2 and "is a FIFO" in err, err


def test_overwrite_replaces_an_older_versions_table_but_nothing_else(tmp_path, capsys):
    old = tmp_path / "old.csv"
    old.write_text("file,content_hash,params,sigma\n/s/a.off,h,{},0.5\n")
    refused(capsys, tmp_path, old, "--resume", needle="this version's batch table")
    with deadline(60):
        status, _, err = run_cli(capsys, "batch", GOOD, "--points", 8, "--no-cache", "--out", old, "--overwrite")
    assert status == 0, err
    assert [r["file"] for r in read_table(old)] == [GOOD]


def _in_small_file_system(folder: Path, shell: str) -> list[str] | None:
    """``sh -c shell`` with a 64 kB tmpfs mounted at ``folder`` (private mount namespace), or None."""
    unshare = shutil.which("unshare")
    if unshare is None or subprocess.run([unshare, "-Urm", "true"], capture_output=True).returncode != 0:
        return None
    return [unshare, "-Urm", "sh", "-c", f"mount -t tmpfs -o size=64k tmpfs '{folder}' && {shell}"]


@pytest.mark.parametrize("suffix", FORMATS)
def test_a_full_disk_is_one_error_line_and_leaves_whole_rows(tmp_path, suffix):
    """A real full file system: a 64 kB tmpfs filled but for two pages (the lock and a table that
    cannot grow beyond one page); without a mount namespace, a file-size limit (EFBIG) instead."""
    folder = tmp_path / "small"
    folder.mkdir()
    out = folder / f"t{suffix}"
    shapes = [f"demo:blob:subdivisions=1,seed={k}" for k in range(12)]
    batch = [sys.executable, "-m", "shapecond", "batch", *shapes, "--points", "8", "--no-cache", "--out", str(out)]
    cmd = _in_small_file_system(folder, f"dd if=/dev/zero of='{folder}/filler' bs=4096 count=14 2>/dev/null; "
                                + " ".join(f"'{a}'" for a in batch) + f"; s=$?; base64 '{out}' 2>/dev/null; exit $s")
    if cmd is not None:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        reason, data = "No space left on device", base64.b64decode(proc.stdout)
    else:
        def limit():
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

        proc = subprocess.run(batch, capture_output=True, text=True, timeout=120, preexec_fn=limit)
        reason, data = "File too large", out.read_bytes() if out.exists() else b""
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and reason in lines[0] and lines[0].startswith("error: "), \
        proc.stderr
    if suffix != ".parquet":  # whole rows only: the failed write was undone
        assert data.endswith(b"\n") and len(data.splitlines()) >= 2


@pytest.mark.parametrize("suffix", FORMATS)
def test_a_read_only_folder_is_one_error_line(tmp_path, suffix):
    """A read-only file system (a tmpfs mounted ro in a private namespace), or a folder without write
    permission when not root."""
    folder = tmp_path / "ro"
    folder.mkdir()
    batch = [sys.executable, "-m", "shapecond", "batch", GOOD, "--points", "8", "--no-cache",
             "--out", str(folder / f"t{suffix}")]
    cmd = _in_small_file_system(folder, "mount -o remount,ro '" + str(folder) + "' && "
                                + " ".join(f"'{a}'" for a in batch))
    if cmd is None and os.geteuid() == 0:
        pytest.skip("root writes into any folder and no mount namespace is available")
    if cmd is None:
        folder.chmod(0o500)
    try:
        proc = subprocess.run(cmd or batch, capture_output=True, text=True, timeout=60)
    finally:
        folder.chmod(0o700)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: "), proc.stderr
    assert "Read-only file system" in lines[0] or "Permission denied" in lines[0]


@pytest.mark.parametrize("suffix", [".csv", ".jsonl"])
def test_a_refused_batch_leaves_even_its_own_tables_torn_line(tmp_path, capsys, suffix):
    """The torn last line of the batch's own table is cut only by a batch that goes on to write."""
    from shapecond.batch.table import Table

    path = tmp_path / f"t{suffix}"
    with Table(path) as table:
        table.append(table_row(1))
    with open(path, "a") as fh:
        fh.write('"/s/2.off",h2,{' if suffix == ".csv" else '{"file": "/s/2.off", "content_')
    refused(capsys, tmp_path, path, needle="already holds 1 rows")


def test_json_lines_rows_are_recognised_by_their_columns_whatever_their_order(tmp_path):
    """A JSON row is read by name: a table rewritten with sorted keys (jq -S) is still the batch's own."""
    import json

    from shapecond.batch import schema
    from shapecond.batch.table import Table

    path = tmp_path / "t.jsonl"
    row = {k: table_row(1)[k] for k in schema.NAMES}
    path.write_text(json.dumps(row, sort_keys=True).replace("Infinity", '"inf"') + "\n")
    with Table(path, "resume") as table:
        assert [r["file"] for r in table.rows] == ["/s/1.off"]
        table.append(table_row(2))
    assert [r["file"] for r in read_table(path)] == ["/s/1.off", "/s/2.off"]

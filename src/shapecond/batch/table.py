"""Where batch rows go: Parquet, CSV or JSON Lines, appended as shapes complete, one writer at a time.

**Loss-free appends.** CSV and JSON Lines: each row is one line written by a
single ``write`` on a file opened for appending, so a process killed between
two rows (SIGKILL included) leaves only whole rows; a write that fails (full
disk) is undone before the one-line error, and a torn last line left by a
power loss is cut off, with a warning, when the table is opened again.
Parquet cannot be appended to (its footer comes last), so its rows go first
to a journal beside it (``.NAME.journal``, JSON Lines as above) and the
Parquet file is rewritten from all rows, atomically (``output.atomic_open``),
every few seconds and at the end.  The Parquet file is therefore always
complete and readable; rows finished since its last rewrite wait in the
journal, which the next batch on the same output (e.g. ``--resume``) folds in
before doing anything else.

**Only its own table.** A file already at the output is read and recognised
before anything is written to it: a CSV file must have exactly this version's
header, every JSON Lines (or journal) line must be a row with exactly this
version's columns, a Parquet file this version's columns.  Anything else (a
user's notes, another program's CSV) is refused in one line and left as it was:
never truncated, rewritten or appended to.  ``--overwrite`` empties only a
batch table (any version's: its first columns are ``file``, ``content_hash``,
``params``).  The table, its journal and its lock are opened without following
symbolic links and must be regular files (``checks.open_regular``): a link, a
FIFO, a device or a folder at any of these names is refused before it is
opened for writing, so nothing is ever written through a planted link, and a
FIFO cannot block the batch.  A full disk or a read-only folder is one
``OutputError`` line (exit status 2).

**One writer.** The table is locked through ``.NAME.lock`` with ``flock``,
which the kernel releases when the process dies, so a killed batch leaves no
stale lock; a second batch on the same output refuses, naming the holder's
host and pid.  A lock held while the process it names (on this host) is dead
is held by a process that inherited it (a child the kernel did not end): its
file is unlinked, with a warning, and the lock taken afresh, under an ``flock``
of the folder so that two batches cannot both take it over.  The lock file is
only rewritten when it holds nothing but such a line.  (Written here rather than with the ``filelock`` package: its
``flock`` lock leaves the lock file behind and its soft lock goes stale when
the holder is killed.)  On a network file system the lock is only as good as
the server's ``flock`` support.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import re
import socket
import time
import warnings
from pathlib import Path

from ..checks import open_regular
from ..errors import InputError, OutputError
from ..jsonable import jsonable
from ..output import atomic_open
from . import schema

FORMATS = {".parquet": "parquet", ".csv": "csv", ".jsonl": "jsonl", ".ndjson": "jsonl"}
#: The Parquet file is rewritten at most this often (seconds) while rows arrive,
#: and never more often than 5 times the last rewrite took, so that rewriting a
#: large table does not slow the batch.
SNAPSHOT_SECONDS = 2.0
#: What a lock file holds (``OutputLock``); a file at the lock's name holding anything else is refused.
LOCK_LINE = re.compile(r"host .*, pid \d+\n?")
#: How every JSON Lines row of ours starts (``_json_line``: the columns in ``schema.NAMES`` order).
ROW_START = b'{"file": '


def table_format(path) -> str:
    """``parquet``, ``csv`` or ``jsonl`` from the output's extension; InputError otherwise."""
    fmt = FORMATS.get(Path(path).suffix.lower())
    if fmt is None:
        raise InputError(f"{path}: unknown table format; use .parquet, .csv or .jsonl")
    if fmt == "parquet":
        try:
            import pyarrow.parquet  # noqa: F401
        except ImportError:
            raise InputError("writing .parquet needs pyarrow: pip install 'shapecond[parquet]' "
                             "(or write .csv / .jsonl)") from None
    return fmt


def _write_error(path, exc: OSError) -> OutputError:
    return OutputError(f"{path}: cannot write ({exc.strerror or exc.__class__.__name__})")


# --- one writer per output ------------------------------------------------------------

class OutputLock:
    """An exclusive ``flock`` on ``.NAME.lock`` beside the output (see module docstring)."""

    def __init__(self, path: Path):
        self.path = path.with_name(f".{path.name}.lock")
        self.fd = None

    def __enter__(self):
        try:
            import fcntl
        except ImportError:  # no flock on this platform: no protection against a second writer
            return self
        while True:
            fd = open_regular(self.path, os.O_RDWR | os.O_CREAT, follow_links=False, output=True)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                holder = os.read(fd, 200).decode(errors="replace").strip() or "unknown"
                taken_over = _dead_holder(holder) is not None and self._take_over(fd)
                os.close(fd)
                if taken_over:
                    warnings.warn(f"{self.path.name[1:-5]}: took over the lock of a batch that is no longer "
                                  f"running ({holder}); a process it left held the lock")
                    continue
                raise InputError(f"{self.path.name[1:-5]} is being written by another batch ({holder}); "
                                 "wait for it to finish or choose another --out") from None
            if self._names(fd):  # the previous holder may have removed the file between our open and flock
                break
            os.close(fd)
        try:
            self._claim(fd)
        except BaseException:
            os.close(fd)
            raise
        self.fd = fd
        return self

    def _take_over(self, fd) -> bool:
        """Unlink the lock file open as ``fd`` if its name still refers to it (under the folder's flock)."""
        import fcntl

        try:
            folder = os.open(self.path.parent, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except OSError:
            return False
        try:
            fcntl.flock(folder, fcntl.LOCK_EX)
            if not self._names(fd) or os.fstat(fd).st_nlink != 1:
                return False
            self.path.unlink()
            return True
        except OSError:
            return False
        finally:
            os.close(folder)  # releases the folder's flock

    def _names(self, fd) -> bool:
        """Whether the lock's name still refers to the file open as ``fd``."""
        try:
            return os.lstat(self.path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            return False

    def _claim(self, fd) -> None:
        """Write our host and pid into the lock file, if it is one (empty or a previous holder's line)."""
        st = os.fstat(fd)
        old = os.pread(fd, 512, 0).decode(errors="replace")
        if st.st_nlink != 1 or (old and not LOCK_LINE.fullmatch(old)):
            raise OutputError(f"{self.path}: not a lock file of shapecond batch (it holds other data); "
                              "remove it or choose another --out")
        try:
            os.ftruncate(fd, 0)
            os.write(fd, f"host {socket.gethostname()}, pid {os.getpid()}\n".encode())
        except OSError as exc:
            raise _write_error(self.path, exc) from None

    def __exit__(self, *exc):
        if self.fd is not None:
            if self._names(self.fd):
                self.path.unlink(missing_ok=True)
            os.close(self.fd)
            self.fd = None
        return False


def _dead_holder(line: str) -> int | None:
    """The pid named by a lock line of this host whose process has ended; None otherwise."""
    m = re.fullmatch(r"host (.*), pid (\d+)", line.strip())
    if m is None or m.group(1) != socket.gethostname():
        return None
    pid = int(m.group(2))
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return pid
    except (OSError, OverflowError):  # alive but not ours (EPERM), or not a pid at all
        return None
    try:  # a zombie (ended, not yet reaped by its parent) has ended too
        with open(f"/proc/{pid}/stat", "rb") as fh:
            return pid if fh.read().rsplit(b")", 1)[1].split()[0] in (b"Z", b"X") else None
    except (OSError, IndexError):
        return None


# --- append-only line files -------------------------------------------------------------

class _LineFile:
    """A file of whole lines, appended one ``write`` per line; never reached through a link."""

    def __init__(self, path: Path):
        self.path, self.fd, self.created = path, None, False

    def open(self) -> None:
        """Open for reading and appending, creating it if missing (``OutputError`` for a link, FIFO, ...)."""
        exists = os.path.lexists(self.path)
        flags = os.O_RDWR | os.O_APPEND | (0 if exists else os.O_CREAT | os.O_EXCL)
        self.fd = open_regular(self.path, flags, follow_links=False, output=True)
        self.created = not exists

    def read(self) -> tuple[list[str], bytes]:
        """(its complete lines, the torn bytes after the last newline); the file is not changed."""
        chunks, offset = [], 0
        while True:
            chunk = os.pread(self.fd, 1 << 20, offset)
            if not chunk:
                break
            chunks.append(chunk)
            offset += len(chunk)
        data = b"".join(chunks)
        end = data.rfind(b"\n") + 1
        return data[:end].decode("utf-8").splitlines(), data[end:]

    def cut(self, n_bytes: int) -> None:
        """Remove the last ``n_bytes`` (a torn line), once the file is known to be ours."""
        try:
            os.ftruncate(self.fd, os.fstat(self.fd).st_size - n_bytes)
        except OSError as exc:
            raise _write_error(self.path, exc) from None

    def write(self, line: str) -> None:
        """Append one line; a failed write (full disk) is undone, leaving no torn line."""
        data = line.encode("utf-8")
        size = os.fstat(self.fd).st_size
        try:
            while data:
                data = data[os.write(self.fd, data):]
        except OSError as exc:
            with contextlib.suppress(OSError):
                os.ftruncate(self.fd, size)
            raise _write_error(self.path, exc) from None

    def clear(self) -> None:
        try:
            os.ftruncate(self.fd, 0)
        except OSError as exc:
            raise _write_error(self.path, exc) from None

    def close(self, remove=False) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        if remove:
            self.path.unlink(missing_ok=True)


# --- recognising our own table ----------------------------------------------------------

def _columns_problem(names, where, strict: bool, ordered: bool = True) -> str | None:
    """Why columns ``names`` are not those of this version's table (``strict``) or of any
    version's (``--overwrite``); None when they are.  ``ordered``: in this version's order too
    (CSV rows are appended by position; a JSON row is read by name)."""
    same = tuple(names) == schema.NAMES if ordered else sorted(names) == sorted(schema.NAMES)
    if strict and same:
        return None
    if set(schema.KEY) <= set(names):
        if not strict:
            return None
        return f"{where}: its columns are not those of this version's batch table; use another --out or --overwrite"
    return f"{where}: its columns are not those of a batch table (it is not one); choose another --out"


def _csv_rows(lines, tail: bytes, where, strict: bool) -> list[dict]:
    if not lines:
        if tail:
            raise InputError(f"{where}: not a batch table (no complete header line); choose another --out")
        return []
    problem = _columns_problem(next(csv.reader([lines[0]])), where, strict)
    if problem:
        raise InputError(problem)
    return [schema.coerce_row(r) for r in csv.DictReader(lines)] if strict else []


def _json_rows(lines, tail: bytes, where, strict: bool) -> list[dict]:
    rows = []
    for k, line in enumerate(lines, 1):
        try:
            obj = json.loads(line)
        except ValueError:
            obj = None
        if not isinstance(obj, dict):
            raise InputError(f"{where}:{k}: not a row of a batch table (it is not one); choose another --out")
        problem = _columns_problem(list(obj), f"{where}:{k}", strict, ordered=False)
        if problem:
            raise InputError(problem)
        if strict:
            rows.append(schema.coerce_row(obj))
    if tail and not ROW_START.startswith(tail[:len(ROW_START)]):
        raise InputError(f"{where}: its last line is not a row of a batch table (it is not one); "
                         "choose another --out")
    return rows


def _json_line(row: dict) -> str:
    return json.dumps(jsonable({k: row.get(k) for k in schema.NAMES}), allow_nan=False) + "\n"


def _csv_line(values) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(values)
    return buf.getvalue()


def _csv_cell(value):
    if value is None:
        return ""
    if isinstance(value, list):
        return json.dumps([None if v != v else v for v in value])  # NaN -> null
    return value


# --- the table ------------------------------------------------------------------------

class Table:
    """The rows of one output file; ``rows`` holds those already there (for ``--resume``)."""

    def __init__(self, path, mode: str = "new"):
        self.path = Path(path)
        self.format = table_format(self.path)
        if not self.path.parent.is_dir():
            raise InputError(f"{self.path}: the folder {self.path.parent} does not exist")
        self.mode = mode
        self.lock = OutputLock(self.path)
        self.lines = _LineFile(self.path if self.format != "parquet"
                               else self.path.with_name(f".{self.path.name}.journal"))
        self.rows: list[dict] = []
        self._created = False
        self._last_snapshot, self._snapshot_cost, self._dirty = 0.0, 0.0, False

    # opening: check the output, lock, read and recognise what is there, fold a journal in
    def __enter__(self):
        for path in {self.path, self.lines.path}:  # a link, FIFO, device or folder: refused before the lock
            if os.path.lexists(path):
                os.close(open_regular(path, os.O_RDONLY, follow_links=False, output=True))
        self.lock.__enter__()
        try:
            self._open()
        except BaseException:
            try:
                self._discard()
            finally:
                self.lock.__exit__()
            raise
        return self

    def _open(self):
        self._created = not os.path.lexists(self.path)
        self.lines.open()
        existing, tail = self._read()
        if self.mode == "overwrite":
            existing = []
            self.lines.clear()
        elif existing and self.mode == "new":
            raise InputError(f"{self.path} already holds {len(existing)} rows: pass --resume to add to it "
                             "or --overwrite to start again")
        elif tail:  # only now that the file is known to be ours, and will be written to
            self.lines.cut(len(tail))
            warnings.warn(f"{self.lines.path}: cut its incomplete last line ({len(tail)} bytes), left by an "
                          "interrupted batch", stacklevel=4)
        self.rows = existing
        if self.format == "csv" and os.fstat(self.lines.fd).st_size == 0:
            self.lines.write(_csv_line(schema.NAMES))
        if self.format == "parquet":
            self._snapshot()  # the file exists, readable, from the start; a journal is folded in

    def _read(self) -> tuple[list[dict], bytes]:
        """(the rows already there, the torn bytes after the journal's last line), once the output and
        journal are recognised as this batch's table (module docstring); nothing is changed."""
        strict = self.mode != "overwrite"
        try:
            rows = self._read_parquet(strict) if self.format == "parquet" else []
            lines, tail = self.lines.read()
            parse = _csv_rows if self.format == "csv" else _json_rows
            more = parse(lines, tail, self.lines.path, strict)
        except (InputError, OutputError):
            raise
        except Exception as exc:  # noqa: BLE001 - any reader failure means "not our table"
            raise InputError(f"{self.path}: not a readable batch table ({exc.__class__.__name__}); "
                             "choose another --out") from None
        seen = {schema.row_key(r) for r in rows}
        return rows + [r for r in more if schema.row_key(r) not in seen], tail

    def _read_parquet(self, strict: bool) -> list[dict]:
        if self._created:
            return []
        import pyarrow.parquet as pq

        with os.fdopen(open_regular(self.path, os.O_RDONLY, follow_links=False, output=True), "rb") as fh:
            table = pq.read_table(fh)
        problem = _columns_problem(table.column_names, self.path, strict)
        if problem:
            raise InputError(problem)
        return [schema.coerce_row(r) for r in table.to_pylist()] if strict else []

    def _discard(self) -> None:
        """After a failure to open: close, and remove what this run created (no rows yet)."""
        self.lines.close(remove=self.lines.created)
        if self._created and self.format == "parquet" and os.path.lexists(self.path):
            self.path.unlink()

    # writing
    def append(self, row: dict) -> None:
        """Add one row; on disk before this returns (the Parquet file follows within seconds)."""
        if self.format == "csv":
            self.lines.write(_csv_line([_csv_cell(row.get(k)) for k in schema.NAMES]))
        else:
            self.lines.write(_json_line(row))
        self.rows.append(row)
        if self.format == "parquet":
            self._dirty = True
            wait = max(SNAPSHOT_SECONDS, 5 * self._snapshot_cost)
            if time.monotonic() - self._last_snapshot >= wait:
                self._snapshot()

    def _snapshot(self) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        t0 = time.monotonic()
        table = pa.Table.from_pylist([{k: r.get(k) for k in schema.NAMES} for r in self.rows],
                                     schema=schema.arrow_schema())
        with atomic_open(self.path, "wb") as fh:
            pq.write_table(table, fh)
        if self.lines.fd is not None:
            self.lines.clear()
        self._last_snapshot = time.monotonic()
        self._snapshot_cost = self._last_snapshot - t0
        self._dirty = False

    def __exit__(self, exc_type, *exc):
        try:
            if exc_type is not None and self._created and not self.rows:  # failed before any row: no file
                self._discard()
            elif self.format == "parquet" and self.lines.fd is not None:
                if self._dirty:
                    self._snapshot()  # if this fails, the journal stays for the next run
                self.lines.close(remove=True)
        finally:
            self.lines.close()
            self.lock.__exit__()
        return False

"""Where batch rows go: Parquet, CSV or JSON Lines, appended as shapes complete, one writer at a time.

**Loss-free appends.** CSV and JSON Lines: each row is one line written by a
single ``write`` on a file opened for appending, so a process killed between
two rows (SIGKILL included) leaves only whole rows; a torn last line (power
loss, full disk) is cut off when the table is opened again.  Parquet cannot be
appended to (its footer comes last), so its rows go first to a journal beside
it (``.NAME.journal``, JSON Lines as above) and the Parquet file is rewritten
from all rows, atomically (temporary file, then rename), every few seconds and
at the end.  The Parquet file is therefore always complete and readable; rows
finished since its last rewrite wait in the journal, which the next batch on
the same output (e.g. ``--resume``) folds in before doing anything else.

**One writer.** The table is locked through ``.NAME.lock`` with ``flock``,
which the kernel releases when the process dies, so a killed batch leaves no
stale lock; a second batch on the same output refuses, naming the holder's
host and pid.  (Written here rather than with the ``filelock`` package: its
``flock`` lock leaves the lock file behind and its soft lock goes stale when
the holder is killed.)  On a network file system the lock is only as good as
the server's ``flock`` support.
"""

from __future__ import annotations

import csv
import io
import json
import os
import socket
import time
from pathlib import Path

from ..errors import InputError
from . import schema

FORMATS = {".parquet": "parquet", ".csv": "csv", ".jsonl": "jsonl", ".ndjson": "jsonl"}
#: The Parquet file is rewritten at most this often (seconds) while rows arrive,
#: and never more often than 5 times the last rewrite took, so that rewriting a
#: large table does not slow the batch.
SNAPSHOT_SECONDS = 2.0


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
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                holder = os.read(fd, 200).decode(errors="replace").strip() or "unknown"
                os.close(fd)
                raise InputError(f"{self.path.name[1:-5]} is being written by another batch ({holder}); "
                                 "wait for it to finish or choose another --out") from None
            try:  # the previous holder may have removed the file between our open and flock
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.write(fd, f"host {socket.gethostname()}, pid {os.getpid()}\n".encode())
        self.fd = fd
        return self

    def __exit__(self, *exc):
        if self.fd is not None:
            self.path.unlink(missing_ok=True)
            os.close(self.fd)
            self.fd = None
        return False


# --- append-only line files -------------------------------------------------------------

class _LineFile:
    """A file of whole lines, appended one ``write`` per line."""

    def __init__(self, path: Path):
        self.path, self.fd = path, None

    def read(self) -> list[str]:
        """Its lines; a torn last line (no newline) is cut off the file first."""
        if not self.path.exists():
            return []
        data = self.path.read_bytes()
        if data and not data.endswith(b"\n"):
            data = data[: data.rfind(b"\n") + 1]
            os.truncate(self.path, len(data))
        return data.decode("utf-8").splitlines()

    def open(self):
        self.fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def write(self, line: str) -> None:
        data = line.encode("utf-8")
        while data:
            data = data[os.write(self.fd, data):]

    def clear(self) -> None:
        os.ftruncate(self.fd, 0)

    def close(self, remove=False) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        if remove:
            self.path.unlink(missing_ok=True)


def _json_line(row: dict) -> str:
    from ..jsonable import jsonable

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

    # opening: lock, read what is there, fold a journal in
    def __enter__(self):
        self.lock.__enter__()
        try:
            self._open()
        except BaseException:
            self.lock.__exit__()
            raise
        return self

    def _open(self):
        if self.mode == "overwrite":
            self.path.unlink(missing_ok=True)
            self.lines.path.unlink(missing_ok=True)
        self._created = not self.path.exists()
        existing = self._read()
        if existing and self.mode == "new":
            raise InputError(f"{self.path} already holds {len(existing)} rows: pass --resume to add to it "
                             "or --overwrite to start again")
        self.rows = existing
        self.lines.open()
        if self.format == "csv" and os.fstat(self.lines.fd).st_size == 0:
            self.lines.write(_csv_line(schema.NAMES))
        if self.format == "parquet":
            self._snapshot()  # the file exists, readable, from the start; a journal is folded in

    def _read(self) -> list[dict]:
        try:
            if self.format == "jsonl":
                return [schema.coerce_row(json.loads(line)) for line in self.lines.read() if line.strip()]
            if self.format == "csv":
                lines = self.lines.read()
                if not lines:
                    return []
                reader = csv.DictReader(lines)
                if tuple(reader.fieldnames or ()) != schema.NAMES:
                    raise InputError(f"{self.path}: its columns are not those of this version's batch table; "
                                     "use another --out or --overwrite")
                return [schema.coerce_row(r) for r in reader]
            rows = []
            if self.path.exists():
                import pyarrow.parquet as pq

                table = pq.read_table(self.path)
                if tuple(table.column_names) != schema.NAMES:
                    raise InputError(f"{self.path}: its columns are not those of this version's batch table; "
                                     "use another --out or --overwrite")
                rows = [schema.coerce_row(r) for r in table.to_pylist()]
            seen = {schema.row_key(r) for r in rows}
            journal = [schema.coerce_row(json.loads(line)) for line in self.lines.read() if line.strip()]
            return rows + [r for r in journal if schema.row_key(r) not in seen]
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001 - any reader failure means "not our table"
            raise InputError(f"{self.path}: not a readable batch table ({exc.__class__.__name__}); "
                             "use another --out or --overwrite") from None

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

        from ..output import atomic_open

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
                self.lines.close(remove=True)
                self.path.unlink(missing_ok=True)
            elif self.format == "parquet" and self.lines.fd is not None:
                if self._dirty:
                    self._snapshot()
                self.lines.close(remove=True)
            else:
                self.lines.close()
        finally:
            self.lock.__exit__()
        return False

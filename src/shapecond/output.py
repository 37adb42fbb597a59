"""The one way shapecond writes a file: atomically, without following links, cleaned up on failure.

Every output (``-o``, ``--png``, ``--ply``, ``--witness-png``, the evaluation's
report, results and plots, the demo's pictures) and every cache entry is written
by :func:`atomic_open`:

* a **regular file** (or a path that does not exist yet) is written to an
  unnamed temporary file in the target's folder (Linux ``O_TMPFILE``), which is
  given a random name and renamed onto the target only once complete.  A process
  killed while writing leaves no file behind and the previous output intact.
  Where ``O_TMPFILE`` is not supported the temporary file is created under a
  random name with ``O_CREAT | O_EXCL | O_NOFOLLOW``, as ``tempfile.mkstemp``
  does (but with the umask's permissions rather than 0600), and removed on any
  failure.  A symbolic link planted at a temporary name is never followed: the
  name is skipped.  A symbolic link *at the target* is replaced by the new file;
  the file it pointed to is not touched;
* a process killed after its temporary file got a name (SIGKILL between link and
  rename, or anywhere with the named fallback) leaves a complete hidden
  ``.NAME.<hex>.tmp`` behind, which the next write of the same target removes.
  A writer holds an ``flock`` on its temporary file until the rename, so a
  temporary file that can be locked has no live writer; links, FIFOs and other
  files that are not regular at such names are left alone.  (With the named
  fallback a concurrent writer's file is exposed for the instant between its
  creation and its lock: the rename of that writer then fails in one line.)
* a **stream** (a FIFO, a character device such as ``/dev/null``, or a symbolic
  link to one, e.g. ``/dev/stdout``) is written in one go once the content is
  complete; it is never replaced by a regular file.  A FIFO nobody reads
  (within ``FIFO_WAIT`` seconds) is refused in one line instead of blocking;
* a failure (a full disk, no permission, a folder in the way) raises one
  :class:`~shapecond.errors.OutputError` naming the file.

A **set of files** that only make sense together (the evaluation's results,
report and plots) is written by :func:`staged_outputs`: into a hidden staging
folder beside them, then moved into place together, so that a killed run leaves
the previous set (not a mix of two runs).

Standard output carries results only: :func:`stdout_fd_diverted` points file
descriptor 1 elsewhere for a block, so that what a compiled library prints on
its own stdout (HiGHS prints a banner when an instance is created, before any
option can be set) cannot end up in front of the JSON of ``--json``.

Before any work, :func:`check_distinct` refuses an output that is one of the
command's inputs or another of its outputs (the same file by device and inode,
through links; a path that does not exist yet by its resolved location).
Streams (``/dev/null``, ``/dev/stdout``, a FIFO) are never replaced, so they
may take several outputs.

Examples
--------
>>> import tempfile, pathlib
>>> from shapecond.output import atomic_open
>>> path = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
>>> with atomic_open(path, "w") as fh:
...     _ = fh.write("done\\n")
>>> path.read_text()
'done\\n'
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import io
import os
import re
import secrets
import stat
import sys
from pathlib import Path

from .errors import InputError, OutputError

_FLAGS = os.O_WRONLY | getattr(os, "O_CLOEXEC", 0)
#: Write through an unnamed file (Linux O_TMPFILE) when the system has it.
USE_TMPFILE = hasattr(os, "O_TMPFILE")


def _temp_name(folder: Path, name: str) -> Path:
    """A fresh random name beside the target (tests replace this to plant links)."""
    return folder / f".{name}.{secrets.token_hex(8)}.tmp"


#: The end of a temporary name after ``.NAME.`` (``_temp_name``).
_TEMP_TAIL = re.compile(r"[0-9a-f]{16}\.tmp")


def _hold(fd: int) -> None:
    """Lock a temporary file for as long as its writer lives (module docstring)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - no flock: stale temporary files are not collected
        return
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)


def _remove_stale_temps(folder: Path, name: str) -> None:
    """Remove the temporary files of ``folder/name`` left by killed writers (module docstring)."""
    try:
        import fcntl

        from .checks import open_regular

        prefix = f".{name}."
        stale = [e.name for e in os.scandir(folder)
                 if e.name.startswith(prefix) and _TEMP_TAIL.fullmatch(e.name[len(prefix):])]
    except (ImportError, OSError):
        return
    for tmp in stale:
        try:
            fd = open_regular(folder / tmp, follow_links=False)
        except InputError:  # gone, a link, a FIFO...: not ours to remove
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # fails while its writer is alive
            if os.lstat(folder / tmp).st_ino == os.fstat(fd).st_ino:
                os.unlink(folder / tmp)
        except OSError:
            pass
        finally:
            os.close(fd)


def _reason(exc: OSError) -> str:
    return exc.strerror or exc.__class__.__name__


def _stream_kind(path: Path) -> str | None:
    """"stream" for a FIFO/device (or a link to one), "folder", or None (file or missing)."""
    try:
        st = os.stat(path)  # follows links: /dev/stdout -> the pipe or terminal
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({_reason(exc)})") from None
    if stat.S_ISDIR(st.st_mode):
        return "folder"
    if stat.S_ISFIFO(st.st_mode) or stat.S_ISCHR(st.st_mode) or stat.S_ISSOCK(st.st_mode):
        return "stream"
    return None


def _open_temp(folder: Path, name: str):
    """(fd, temporary path or None): an unnamed file in ``folder`` if the system allows it."""
    if USE_TMPFILE:
        try:
            fd = os.open(folder, os.O_TMPFILE | _FLAGS, 0o666)
        except OSError as exc:
            if exc.errno not in (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL, errno.ENOENT):
                raise
        else:
            _hold(fd)
            return fd, None
    for _ in range(100):
        tmp = _temp_name(folder, name)
        try:
            fd = os.open(tmp, _FLAGS | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o666)
        except FileExistsError:
            continue
        _hold(fd)
        return fd, tmp
    raise OSError(errno.EEXIST, "no free temporary name")


def _publish(fd: int, tmp: Path | None, path: Path) -> None:
    """Give the complete file its final name (link the unnamed file first)."""
    if tmp is None:
        folder = os.open(path.parent, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        try:
            for _ in range(100):
                candidate = _temp_name(path.parent, path.name)
                try:  # linkat(AT_SYMLINK_FOLLOW) names the unnamed file; it never follows a link at candidate
                    os.link(f"/proc/self/fd/{fd}", candidate.name, src_dir_fd=folder, dst_dir_fd=folder,
                            follow_symlinks=True)
                except FileExistsError:
                    continue
                tmp = candidate
                break
            else:
                raise OSError(errno.EEXIST, "no free temporary name")
        finally:
            os.close(folder)
    try:
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


#: Seconds to wait for a reader to open a FIFO before refusing to write to it.
FIFO_WAIT = 3.0


def _write_stream(path: Path, data: bytes) -> None:
    import time

    deadline = time.monotonic() + FIFO_WAIT
    while True:
        try:
            fd = os.open(path, _FLAGS | os.O_NONBLOCK)  # never blocks: ENXIO while no process reads a FIFO
            break
        except OSError as exc:
            if exc.errno == errno.ENXIO and time.monotonic() < deadline:
                time.sleep(0.05)
                continue
            if exc.errno == errno.ENXIO:
                raise OutputError(f"{path}: a FIFO that no process is reading; start the reader first") from None
            raise OutputError(f"{path}: cannot write ({_reason(exc)})") from None
    try:
        os.set_blocking(fd, True)
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({_reason(exc)})") from None
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_open(path, mode: str = "wb", make_parents: bool = True):
    """Open ``path`` for writing, atomically (see the module docstring).

    Parameters
    ----------
    path : str or path-like
    mode : ``"wb"`` (binary file object) or ``"w"`` (UTF-8 text).
    make_parents : create missing parent folders.

    Yields
    ------
    A file object; the target appears (complete) only when the block ends
    without an exception.
    """
    if mode not in ("wb", "w"):
        raise ValueError("mode must be 'wb' or 'w'")
    if not isinstance(path, (str, os.PathLike)) or not isinstance(os.fspath(path), str) or not os.fspath(path):
        raise InputError(f"an output must be a file name (str or path), got {path!r:.40}")
    path = Path(os.fspath(path))
    kind = _stream_kind(path)
    if kind == "folder":
        raise OutputError(f"{path}: is a folder, not a file")
    if kind == "stream":
        buffer = io.BytesIO()
        handle = buffer if mode == "wb" else io.TextIOWrapper(buffer, encoding="utf-8", newline="")
        yield handle
        handle.flush()
        _write_stream(path, buffer.getvalue())
        return
    folder = path.parent
    try:
        if make_parents:
            folder.mkdir(parents=True, exist_ok=True)
        elif not folder.is_dir():
            raise OutputError(f"{path}: the folder {folder} does not exist")
        _remove_stale_temps(folder, path.name)
        fd, tmp = _open_temp(folder, path.name)
    except OutputError:
        raise
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({_reason(exc)})") from None
    fh = os.fdopen(fd, "wb", closefd=False)
    handle = fh if mode == "wb" else io.TextIOWrapper(fh, encoding="utf-8", newline="")
    try:
        try:
            yield handle
            handle.flush()
            fh.flush()
            _publish(fd, tmp, path)
        except OutputError:
            raise
        except OSError as exc:
            raise OutputError(f"{path}: cannot write ({_reason(exc)})") from None
    except BaseException:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        raise
    finally:
        with contextlib.suppress(OSError, ValueError):
            handle.close()
        with contextlib.suppress(OSError):
            os.close(fd)


#: A staging folder's name (``staged_outputs``).
_STAGE = re.compile(r"\.staged-[0-9a-f]{16}")


def _remove_stale_stages(folder: Path) -> None:
    """Remove the staging folders in ``folder`` left by killed writers: those whose ``flock`` can be taken."""
    try:
        import fcntl
        import shutil

        stale = [e.name for e in os.scandir(folder) if _STAGE.fullmatch(e.name)]
    except (ImportError, OSError):
        return
    for name in stale:
        try:
            fd = os.open(folder / name, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | getattr(os, "O_NOFOLLOW", 0))
        except OSError:  # gone, a link, not a folder: not ours to remove
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # fails while its writer is alive
            shutil.rmtree(folder / name)  # never follows a link
        except OSError:
            pass
        finally:
            os.close(fd)


def _new_stage(folder: Path) -> tuple[Path, int]:
    """(a fresh staging folder in ``folder``, a descriptor holding its ``flock``)."""
    for _ in range(100):
        stage = folder / f".staged-{secrets.token_hex(8)}"
        try:
            os.mkdir(stage)
        except FileExistsError:
            continue
        fd = os.open(stage, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | getattr(os, "O_NOFOLLOW", 0))
        _hold(fd)
        return stage, fd
    raise OSError(errno.EEXIST, "no free staging name")


def _publish_stage(stage: Path, folder: Path) -> None:
    """Move the files of ``stage`` into ``folder`` in the order they were written (a stream target gets
    the bytes instead, as with ``atomic_open``); every target checked first."""
    files = sorted((e.stat(follow_symlinks=False).st_mtime_ns, e.name) for e in os.scandir(stage) if e.is_file())
    for _, name in files:
        if _stream_kind(folder / name) == "folder":
            raise OutputError(f"{folder / name}: is a folder, not a file")
    for _, name in files:
        target = folder / name
        try:
            if _stream_kind(target) == "stream":
                _write_stream(target, (stage / name).read_bytes())
            else:
                os.replace(stage / name, target)
        except OSError as exc:
            raise OutputError(f"{target}: cannot write ({_reason(exc)})") from None


@contextlib.contextmanager
def staged_outputs(folder, make_parents: bool = True, publish_on_error: bool = False):
    """A set of files for ``folder``, written to a hidden staging folder in it and moved into place together.

    The block writes its files (with :func:`atomic_open`, :func:`write_text`...) into the yielded
    staging folder ``folder/.staged-<hex>``; when it ends without an exception they are moved into
    ``folder`` in the order they were written, each by one rename, and the staging folder is removed.
    A process killed while the block runs therefore leaves every file of the previous set as it was,
    none of the new set beside them (a set of files is whole only together: a report and the results
    it describes); only a kill within the renames, microseconds, can leave both.  A staging folder
    left by a killed writer is removed by the next writer in the same folder (a live writer holds an
    ``flock`` on its own).  On an exception nothing is moved (unless ``publish_on_error``) and the
    staging folder is removed.

    Parameters
    ----------
    folder : str or path-like, the folder the files are for.
    make_parents : create ``folder`` and its missing parents.
    publish_on_error : on an exception (not an interrupt) in the block, still move the files written
        so far into place before it propagates (results that must outlive a failing figure).

    Yields
    ------
    Path of the staging folder.
    """
    import shutil

    folder = Path(os.fspath(folder))
    if _stream_kind(folder) not in ("folder", None):
        raise OutputError(f"{folder}: not a folder")
    try:
        if make_parents:
            folder.mkdir(parents=True, exist_ok=True)
        elif not folder.is_dir():
            raise OutputError(f"{folder}: the folder does not exist")
        _remove_stale_stages(folder)
        stage, fd = _new_stage(folder)
    except OutputError:
        raise
    except OSError as exc:
        raise OutputError(f"{folder}: cannot write ({_reason(exc)})") from None
    try:
        try:
            yield stage
        except Exception:
            if publish_on_error:
                with contextlib.suppress(OutputError):
                    _publish_stage(stage, folder)
            raise
        _publish_stage(stage, folder)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        os.close(fd)


def _identity(path):
    """What ``path`` is as a file: ("file", device, inode) through links, ("new", resolved path) when it does
    not exist, None for a stream or folder (never replaced by a write)."""
    try:
        st = os.stat(path)
    except OSError:
        return ("new", os.path.realpath(os.path.abspath(path)))
    return ("file", st.st_dev, st.st_ino) if stat.S_ISREG(st.st_mode) else None


def check_distinct(outputs, inputs=()) -> None:
    """Refuse, in one line, an output that is an input or another output (module docstring).

    Parameters
    ----------
    outputs : (label, path) pairs, e.g. ``("--html", "page.html")``.
    inputs : (label, path) pairs of the files read; names that are not files are ignored.

    Raises
    ------
    InputError
        naming the output and the input or output it is.
    """
    seen = {}
    for label, path in inputs:
        ident = _identity(path)
        if ident is not None and ident[0] == "file":
            seen.setdefault(ident, f"the input {label} ({path})")
    for label, path in outputs:
        ident = _identity(path)
        if ident is None:
            continue
        if ident in seen:
            what = seen[ident]
            hint = "an output may not overwrite an input" if what.startswith("the input") else \
                "give each output its own file"
            raise InputError(f"{label} {path}: it is {what}; {hint}")
        seen[ident] = f"the output {label} ({path})"


def write_bytes(path, data: bytes, make_parents: bool = True) -> Path:
    """Write ``data`` to ``path`` with :func:`atomic_open`; return the path."""
    with atomic_open(path, "wb", make_parents) as fh:
        fh.write(data)
    return Path(path)


def write_text(path, text: str, make_parents: bool = True) -> Path:
    """Write ``text`` (UTF-8) to ``path`` with :func:`atomic_open`; return the path."""
    with atomic_open(path, "w", make_parents) as fh:
        fh.write(text)
    return Path(path)


def _flush_c_stdio() -> None:
    """Flush the C library's ``stdout`` buffer (text a compiled library printed but not written yet)."""
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None).fflush(None)


def _python_stdout_fd():
    """File descriptor under ``sys.stdout`` (None when it has none, e.g. under pytest's ``capsys``)."""
    try:
        sys.stdout.flush()
        return sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return None


@contextlib.contextmanager
def stdout_fd_diverted(to=None, keep_python_stdout: bool = False):
    """Point file descriptor 1 at stderr (``to=None``) or at the file ``to`` (e.g. ``os.devnull``) for the block.

    What a compiled library writes to its C ``stdout`` in the block goes there instead of standard
    output.  With ``keep_python_stdout``, and when ``sys.stdout`` writes to descriptor 1, Python's
    ``sys.stdout`` is given a copy of the original descriptor for the block: ``print`` and
    ``click.echo`` still reach standard output, only writes below Python are diverted.  Nothing is
    diverted when descriptor 1 cannot be duplicated (closed).
    """
    python_fd = _python_stdout_fd()
    _flush_c_stdio()
    try:
        saved = os.dup(1)
    except OSError:
        yield
        return
    target = os.open(to, os.O_WRONLY | getattr(os, "O_CLOEXEC", 0)) if to is not None else 2
    previous = sys.stdout
    try:
        os.dup2(target, 1)
        if keep_python_stdout and python_fd == 1:
            sys.stdout = io.TextIOWrapper(io.FileIO(saved, "w", closefd=False), encoding=previous.encoding,
                                          errors=previous.errors, line_buffering=previous.line_buffering)
        yield
    finally:
        if sys.stdout is not previous:
            with contextlib.suppress(OSError, ValueError):
                sys.stdout.flush()
            sys.stdout = previous
        _flush_c_stdio()
        os.dup2(saved, 1)
        os.close(saved)
        if to is not None:
            os.close(target)

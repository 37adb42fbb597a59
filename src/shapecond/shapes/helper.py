"""A second process that computes half of every block of geodesic rows, so that both cores work.

The sparse Cholesky solves hold Python's GIL (cholespy), so threads cannot
share them; a process can.  The helper is *forked* from the process that built
the solver, so it inherits the factorisations and the compiled kernels instead
of rebuilding them (a second or more), and it hands its rows back through an
anonymous shared-memory buffer.  It is started on the first request of at least
two rows and stops with the solver (or with the main process).

The helper dies with its parent, even when the parent is killed (SIGKILL
included): it closes every descriptor it inherited but its own end of the pipe
and the standard streams (the parent's end of the pipe, so that a dead parent is
an end of file; an output's lock, so that no lock outlives its writer), asks
the kernel for SIGKILL when its parent ends (Linux ``PR_SET_PDEATHSIG``,
``die_with_parent``) and elsewhere polls ``os.getppid()`` twice a
second.

Only the main process of a program forks a helper (a joblib or multiprocessing
worker, e.g. the evaluation's ``--jobs``, already has its core), only where
``fork`` exists (Linux, macOS) and only when at least two CPUs are available to
the process; otherwise, and whenever the helper fails, every row is computed in
the calling process.  ``SHAPECOND_WORKERS=1`` turns it off.
"""

from __future__ import annotations

import mmap
import multiprocessing as mp
import os
import weakref

import numpy as np


def helper_allowed() -> bool:
    """Whether this process may fork a helper (module docstring)."""
    if os.environ.get("SHAPECOND_WORKERS", "").strip() == "1":
        return False
    if "fork" not in mp.get_all_start_methods() or mp.parent_process() is not None:
        return False
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS
        cpus = os.cpu_count() or 1
    return cpus >= 2 and not mp.current_process().daemon


#: Seconds between two looks at the parent where the kernel cannot signal its death.
PARENT_POLL = 0.5


def _close_inherited(keep: int) -> None:
    """Close every descriptor of this process above 2 except ``keep`` (module docstring)."""
    top = os.sysconf("SC_OPEN_MAX") if hasattr(os, "sysconf") else 1 << 16
    os.closerange(3, keep)
    os.closerange(max(3, keep + 1), max(top, 3))


def die_with_parent(parent_pid: int) -> bool:
    """Make this worker process end when its parent does (Linux ``PR_SET_PDEATHSIG``).

    Called at the start of every task run by a pool of worker processes
    (``parallel``), and by the forked geodesic helper, so that killing the command
    (even with SIGKILL) does not leave its workers running.  Returns whether the
    kernel will send the signal (False where ``prctl`` is not available: the
    caller may watch ``os.getppid()`` itself).
    """
    import ctypes
    import signal

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        armed = libc.prctl(1, int(signal.SIGKILL), 0, 0, 0) == 0  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        return False
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)
    return armed


def _watch_parent(parent_pid: int) -> None:
    """End this process when its parent is gone: the kernel's signal, or a thread that polls."""
    import threading
    import time

    if die_with_parent(parent_pid):
        return

    def poll():  # pragma: no cover - not Linux
        while os.getppid() == parent_pid:
            time.sleep(PARENT_POLL)
        os._exit(1)

    threading.Thread(target=poll, daemon=True).start()


def _serve(compute, conn, buffer, parent_end, parent_pid) -> None:  # pragma: no cover - the forked process
    parent_end.close()
    _close_inherited(conn.fileno())
    _watch_parent(parent_pid)
    while True:
        try:
            sources = conn.recv()
        except (EOFError, OSError):  # the parent closed its end or died
            return
        if sources is None:
            return
        try:
            rows = compute(sources)
            buffer[: len(sources)] = rows
            reply = len(sources)
        except Exception as exc:  # noqa: BLE001 - reported to the parent, which computes the rows itself
            reply = f"{type(exc).__name__}: {exc}"
        try:
            conn.send(reply)
        except OSError:  # the parent is gone
            return


def _stop(conn, proc) -> None:
    try:
        conn.send(None)
        proc.join(timeout=2)
    except (OSError, ValueError):
        pass
    if proc.is_alive():
        proc.kill()


class SplitRows:
    """``compute(sources) -> (k, n)`` rows, with the first half of each request done by a forked helper.

    Parameters
    ----------
    compute : function of an int array of sources returning (len, n) float64 rows.
    n : row length.
    capacity : most rows the helper computes per request (its buffer size).
    """

    def __init__(self, compute, n: int, capacity: int):
        self.compute, self.n, self.capacity = compute, int(n), int(capacity)
        self._conn = self._proc = self._buffer = None
        self._failed = False

    def _start(self) -> bool:
        if self._proc is not None:
            return True
        if self._failed:
            return False
        try:
            ctx = mp.get_context("fork")
            memory = mmap.mmap(-1, self.capacity * self.n * 8)  # anonymous and shared with the fork
            self._buffer = np.frombuffer(memory, dtype=np.float64).reshape(self.capacity, self.n)
            self._conn, child = ctx.Pipe()
            self._proc = ctx.Process(target=_serve, args=(self.compute, child, self._buffer, self._conn, os.getpid()),
                                     daemon=True)
            self._proc.start()
            child.close()
        except (OSError, ValueError, AssertionError):
            self._failed = True
            self._proc = None
            return False
        weakref.finalize(self, _stop, self._conn, self._proc)
        return True

    def __call__(self, sources) -> np.ndarray:
        sources = np.asarray(sources, dtype=np.int64)
        step = 2 * self.capacity
        parts = [self._pair(sources[i:i + step]) for i in range(0, sources.size, step)]
        return np.concatenate(parts) if parts else self.compute(sources)

    def _pair(self, sources: np.ndarray) -> np.ndarray:
        half = sources.size // 2
        if half == 0 or not self._start():
            return self.compute(sources)
        try:
            self._conn.send(sources[:half])
        except OSError:
            self._failed, self._proc = True, None
            return self.compute(sources)
        mine = self.compute(sources[half:])
        try:
            reply = self._conn.recv()
        except (EOFError, OSError):
            reply = "the helper process stopped"
        if isinstance(reply, str):
            self._failed, self._proc = True, None
            theirs = self.compute(sources[:half])
        else:
            theirs = self._buffer[:half].copy()
        return np.concatenate([theirs, mine])

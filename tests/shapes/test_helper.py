"""The forked helper that computes half of every block of rows (shapes.helper)."""

import fcntl
import multiprocessing as mp
import os
import signal
import time

import numpy as np
import pytest

from shapecond.shapes import helper, synthetic
from shapecond.shapes.geodesics import DistanceSolver

pytestmark = pytest.mark.skipif("fork" not in mp.get_all_start_methods(), reason="needs fork")


def _rows(sources):
    sources = np.asarray(sources)
    return np.sin(sources[:, None] * 0.1 + np.arange(50)[None, :]) + sources[:, None]


def test_split_rows_equal_local_rows_in_order():
    split = helper.SplitRows(_rows, 50, capacity=4)
    for k in (0, 1, 2, 7, 8, 19):
        src = np.arange(100, 100 + k)
        assert np.array_equal(split(src), _rows(src))
    assert split._proc is not None and split._proc.is_alive()  # the helper did the first halves
    proc = split._proc
    del split
    proc.join(timeout=5)
    assert not proc.is_alive()  # stopped with its owner


def test_a_dead_helper_falls_back_to_local_rows():
    split = helper.SplitRows(_rows, 50, capacity=4)
    split(np.arange(6))
    split._proc.kill()
    split._proc.join()
    src = np.arange(30, 38)
    assert np.array_equal(split(src), _rows(src))
    assert split._failed and np.array_equal(split(src), _rows(src))


def test_heat_solver_rows_with_and_without_helper(monkeypatch):
    g = synthetic.bumpy_blob(subdivisions=3)
    sources = np.arange(0, g.n_vertices, 41)
    monkeypatch.setattr(helper, "helper_allowed", lambda: True)
    both = DistanceSolver(g, "heat")
    monkeypatch.setattr(helper, "helper_allowed", lambda: False)
    one = DistanceSolver(g, "heat")
    assert isinstance(both._rows, helper.SplitRows) and not isinstance(one._rows, helper.SplitRows)
    assert both.block == 2 * one.block
    assert np.allclose(both.distances(sources), one.distances(sources), rtol=0, atol=1e-9)


def test_environment_turns_the_helper_off(monkeypatch):
    monkeypatch.setenv("SHAPECOND_WORKERS", "1")
    assert not helper.helper_allowed()


def _in_child(queue):
    queue.put(helper.helper_allowed())


def test_no_helper_inside_a_worker_process():
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_in_child, args=(queue,))
    proc.start()
    proc.join()
    assert queue.get(timeout=5) is False


# --- the helper dies with its parent ----------------------------------------------------------

def _gone(pid: int) -> bool:
    """Whether ``pid`` has ended (a zombie waiting for a parent that does not reap counts as ended)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except FileNotFoundError:
        return True


def _slow_in_helper(parent):
    def compute(sources):
        if os.getpid() != parent:  # the helper's half never finishes
            time.sleep(60)
        return _rows(sources)
    return compute


def _parent(queue, lock_path, busy):
    fd = os.open(lock_path, os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # like a batch's output lock
    split = helper.SplitRows(_slow_in_helper(os.getpid()) if busy else _rows, 50, capacity=4)
    split._start()
    queue.put(split._proc.pid)
    if busy:
        split(np.arange(8))  # blocks: the helper sleeps on its half
    time.sleep(60)


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="reads /proc")
@pytest.mark.parametrize("busy", [False, True], ids=["idle", "busy"])
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_the_helper_dies_with_its_killed_parent_and_frees_its_locks(tmp_path, busy, sig):
    """The helper kept both ends of its pipe (no end of file) and the parent's descriptors: a killed batch
    left it running for good, holding the output's lock."""
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    lock = tmp_path / ".t.csv.lock"
    parent = ctx.Process(target=_parent, args=(queue, lock, busy))
    parent.start()
    pid = queue.get(timeout=20)
    time.sleep(0.3)  # the helper is serving (busy: computing)
    os.kill(parent.pid, sig)
    parent.join(timeout=5)
    deadline = time.monotonic() + 5
    while not _gone(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    alive = not _gone(pid)
    if alive:
        os.kill(pid, signal.SIGKILL)
    assert not alive, "the helper outlived its parent"
    fd = os.open(lock, os.O_RDWR)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # nobody holds the dead parent's lock
    finally:
        os.close(fd)


def test_the_helper_keeps_only_its_end_of_the_pipe(tmp_path):
    fd = os.open(tmp_path / "held", os.O_RDWR | os.O_CREAT)
    split = helper.SplitRows(_rows, 50, capacity=4)
    try:
        split(np.arange(8))
        held = {os.readlink(f"/proc/{split._proc.pid}/fd/{n}") for n in os.listdir(f"/proc/{split._proc.pid}/fd")
                if int(n) > 2}
    finally:
        os.close(fd)
    assert len(held) == 1 and next(iter(held)).startswith("socket:"), held

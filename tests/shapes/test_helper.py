"""The forked helper that computes half of every block of rows (shapes.helper)."""

import multiprocessing as mp

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

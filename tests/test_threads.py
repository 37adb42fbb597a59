"""shapecond.threads: results in input order, errors raised, nested maps serial."""

import threading

import numba
import pytest

from shapecond.threads import n_threads, thread_map


def test_results_in_input_order_and_errors_raised():
    assert thread_map(lambda x: x * x, range(20)) == [x * x for x in range(20)]
    assert thread_map(lambda x: x, []) == []

    def boom(x):
        if x == 3:
            raise ValueError("three")
        return x

    with pytest.raises(ValueError, match="three"):
        thread_map(boom, range(6))


def test_nested_maps_run_serially_in_their_task_thread():
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba has one thread on this machine")

    def inner(_):
        return n_threads(), threading.current_thread().name

    def outer(_):
        here = threading.current_thread().name
        got = thread_map(inner, range(4))
        return all(k == 1 and name == here for k, name in got)

    assert n_threads() >= 2
    assert all(thread_map(outer, range(4)))


def test_one_numba_thread_means_no_pool():
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        assert n_threads() == 1
        main = threading.current_thread().name
        assert thread_map(lambda _: threading.current_thread().name, range(3)) == [main] * 3
    finally:
        numba.set_num_threads(before)

"""The same landmarks in separate processes, whatever the BLAS thread count."""

import json
import os
import subprocess
import sys

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from shapecond.selection.cnbs import CNBSOptions, cnbs_landmarks

from tests.helpers import mirror_pairs_instance

SCRIPT = """
import json, sys
sys.path.insert(0, {root!r})
from tests.helpers import mirror_pairs_instance
from shapecond.selection.cnbs import CNBSOptions, cnbs_landmarks
from shapecond.symmetry.scale import budget_of, default_epsilon
D = mirror_pairs_instance(120, 7, noise=0.05)
out = {{}}
for name, budget in (("sigma", None), ("scale", budget_of(default_epsilon(D), 120, D))):
    r = cnbs_landmarks(D, 120, 3, budget=budget, options=CNBSOptions(seed=0, effort="quick"))
    out[name] = [r["landmarks"], [float(v).hex() for v in r["scores"]]]
print(json.dumps(out))
"""


def _run(threads: str) -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS=threads, OMP_NUM_THREADS=threads, MKL_NUM_THREADS=threads,
               NUMBA_NUM_THREADS=threads)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    res = subprocess.run([sys.executable, "-c", SCRIPT.format(root=root)], env=env, capture_output=True,
                         text=True, timeout=600, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_cnbs_selections_are_identical_across_processes_and_thread_counts():
    """Two processes, one BLAS and numba thread and two (the heat map's candidates then run in two
    threads): the same landmarks and the same scores to the bit (the evaluation selects landmarks in
    pool workers limited to one thread per core, a user's command line in a process with every core)."""
    assert _run("1") == _run("2")


def test_cnbs_runs_with_one_blas_thread_whatever_the_caller_allows():
    """The mechanism: a threaded product sums in another order and CNBS follows near-ties of such
    sums (TOSCA wolf0 at N = 400: a different second landmark with two BLAS threads)."""
    seen = []

    def progress(step, done, total):
        seen.extend(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")

    with threadpool_limits(limits=2, user_api="blas"):
        cnbs_landmarks(mirror_pairs_instance(30, 1), 30, 1, progress=progress, options=CNBSOptions(effort="quick"))
    assert seen and set(seen) == {1}

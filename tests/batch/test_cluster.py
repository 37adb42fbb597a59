"""Where batches run: local processes, a real 2-worker Dask cluster on loopback, and a kill -9 mid-run."""

import json
import math
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from shapecond import parallel
from shapecond.batch import schema
from shapecond.batch.run import BatchRun, run_batch
from shapecond.errors import InputError
from shapecond.shapes.io import write_mesh
from tests.helpers import VOLATILE, descendants, read_table, run_cli, stable, write_strip_class


def same_rows(a, b):
    """Rows equal up to the worker that computed them (its name appears in some errors)."""
    a, b = stable(a), stable(b)
    assert len(a) == len(b)
    for x, y in zip(a, b):
        for k in schema.NAMES:
            if k in VOLATILE:
                continue
            u, v = x[k], y[k]
            if k == "error" and u is not None:
                u, v = re.sub(r"worker \S+", "worker W", u), re.sub(r"worker \S+", "worker W", v)
            if isinstance(u, float) and not math.isinf(u):
                assert v == pytest.approx(u, rel=1e-9, abs=1e-12), (x["file"], k)
            else:
                assert u == v, (x["file"], k)


# --- the runners on their own -----------------------------------------------------------------

TASKS = [(math.sqrt, (4.0,), {}), (os._exit, (1,), {}), (math.sqrt, (-1.0,), {}), (time.sleep, (0.05,), {}),
         (math.sqrt, (9.0,), {})]


def _check_outcomes(outcomes, died):
    got = {i: (r, e) for i, r, e in outcomes}
    assert sorted(got) == list(range(len(TASKS)))
    assert got[0] == (2.0, None) and got[4] == (3.0, None) and got[3] == (None, None)
    assert isinstance(got[2][1], ValueError)
    assert got[1][0] is None and died(got[1][1])


def test_a_crashing_task_fails_alone_on_local_processes():
    with parallel.runner(2) as run:
        _check_outcomes(list(run.iter_tasks(TASKS)), lambda e: isinstance(e, parallel.WorkerDied))


def test_a_crashing_task_fails_alone_on_a_dask_cluster(dask_client):
    with parallel.runner(1, dask_client) as run:
        assert run.workers == 2
        _check_outcomes(list(run.iter_tasks(TASKS)), lambda e: type(e).__name__ == "KilledWorker")
    dask_client.wait_for_workers(2, timeout=30)  # the nanny restarts the killed workers


def test_a_cluster_without_workers_ends_the_run_instead_of_hanging(monkeypatch):
    from dask.distributed import Client, LocalCluster

    monkeypatch.setattr(parallel, "NO_WORKER_TIMEOUT", 0.5)
    monkeypatch.setattr(parallel, "POLL_SECONDS", 0.2)
    with LocalCluster(n_workers=0, host="127.0.0.1", dashboard_address=":0") as cluster, Client(cluster) as client:
        with pytest.raises(InputError, match="no worker for"):
            parallel.run_tasks([(math.sqrt, (4.0,), {})], scheduler=client)


def test_an_unreachable_scheduler_is_one_error_line(shape_dir, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1.0)
    status, _, err = run_cli(capsys, "batch", shape_dir / "blob0.off", "--out", tmp_path / "t.csv",
                             "--scheduler", "tcp://127.0.0.1:9")
    assert status == 2 and "cannot reach the Dask scheduler" in err and err.count("\n") == 1
    assert not (tmp_path / "t.csv").exists()


# --- batch and evaluate give the same results everywhere ------------------------------------

def test_batch_on_a_cluster_gives_the_rows_of_a_local_run(shape_dir, broken_dir, tmp_path, dask_client, capsys):
    inputs = [shape_dir, broken_dir / "garbage.off", broken_dir / "dangling.off"]
    opts = ["--points", "20", "--what", "score,landmarks:2:fps"]
    status, _, err = run_cli(capsys, "batch", *inputs, *opts, "--out", tmp_path / "local.parquet")
    assert status == 3, err
    status, out, err = run_cli(capsys, "batch", *inputs, *opts, "--out", tmp_path / "dask.parquet",
                               "--scheduler", dask_client.scheduler.address, "--json")
    assert status == 3, err
    summary = json.loads(out)
    assert summary["where"].startswith("the Dask cluster") and (summary["scored"], summary["failed"]) == (6, 2)
    rows = read_table(tmp_path / "dask.parquet")
    # both workers took part (the row of the dangling link is made by this process, which cannot read it)
    assert len({r["worker"] for r in rows} - {parallel.worker_name()}) == 2
    same_rows(read_table(tmp_path / "local.parquet"), rows)


@pytest.mark.slow
def test_batch_starts_and_stops_its_own_local_cluster(shape_dir, tmp_path, capsys):
    status, out, err = run_cli(capsys, "batch", shape_dir / "blob0.off", shape_dir / "blob1.off",
                               "--points", "16", "--out", tmp_path / "t.jsonl", "--scheduler", "local:2", "--json")
    assert status == 0, err
    assert json.loads(out)["where"] == "a LocalCluster of 2 workers"
    local = run_batch([shape_dir / "blob0.off", shape_dir / "blob1.off"], tmp_path / "u.jsonl", {"points": 16})
    assert local.failed == 0
    same_rows(read_table(tmp_path / "u.jsonl"), read_table(tmp_path / "t.jsonl"))


def _worker_environment():
    return {k: os.environ.get(k) for k in ("MALLOC_TRIM_THRESHOLD_", *parallel._THREAD_VARIABLES)}


@pytest.mark.slow
def test_a_local_cluster_gives_its_workers_the_thread_share_and_no_malloc_trim(monkeypatch):
    monkeypatch.setattr(parallel.os, "cpu_count", lambda: 4)
    # a Dask nanny writes its workers' variables into this process's environment, where the next
    # cluster's nanny reads them first: start from an environment no earlier cluster of the session set
    for name in ("MALLOC_TRIM_THRESHOLD_", *parallel._THREAD_VARIABLES):
        monkeypatch.delenv(name, raising=False)
    before = _worker_environment()
    with parallel.runner(1, "local:2") as run:
        seen = list(run.client.run(_worker_environment).values())
        during = _worker_environment()
    # this process keeps its own: the nanny's thread limits would reach its numba (which refuses a
    # changed NUMBA_NUM_THREADS once its threads run) and the next cluster
    assert during == before and _worker_environment() == before
    assert len(seen) == 2
    for env in seen:
        assert env["MALLOC_TRIM_THRESHOLD_"] is None  # Dask's default (65536) costs system time
        assert {env[k] for k in parallel._THREAD_VARIABLES} == {"2"}  # 4 cores, 2 workers


def test_evaluate_quick_on_a_cluster_matches_the_local_run(tmp_path, dask_client, capsys):
    dataset = write_strip_class(tmp_path / "data")
    common = ["evaluate", dataset, "--quick", "--points", "30", "--methods", "fps", "--matchers", "faq", "--json"]
    status, _, err = run_cli(capsys, *common, "--out", tmp_path / "local")
    assert status == 0, err
    status, _, err = run_cli(capsys, *common, "--out", tmp_path / "dask", "--scheduler",
                             dask_client.scheduler.address)
    assert status == 0, err
    local, remote = (json.loads((tmp_path / d / "results.json").read_text()) for d in ("local", "dask"))

    def records(data):
        return sorted((r["target"], r["n_landmarks"], r["error"], r["sample_error"]) for r in data["records"])

    a, b = records(local), records(remote)
    assert len(a) == 4 and [r[:2] for r in a] == [r[:2] for r in b]
    assert [x for r in b for x in r[2:]] == pytest.approx([x for r in a for x in r[2:]], rel=1e-9, abs=1e-12)
    (la,), (lb,) = local["landmarks"], remote["landmarks"]
    assert la["ids"] == lb["ids"] and la["scores"] == pytest.approx(lb["scores"], rel=1e-9)


# --- killed and resumed --------------------------------------------------------------------

@pytest.mark.slow
def test_a_batch_killed_mid_run_resumes_to_the_same_table(tmp_path):
    from shapecond.shapes.synthetic import bumpy_blob

    folder = tmp_path / "in"
    folder.mkdir()
    for k in range(6):  # ~0.4 s each from an empty cache
        g = bumpy_blob(subdivisions=4, seed=20 + k)
        write_mesh(folder / f"b{k}.off", g.vertices, g.faces)
    out, journal = tmp_path / "t.parquet", tmp_path / ".t.parquet.journal"
    env = dict(os.environ, SHAPECOND_CACHE=str(tmp_path / "cache"))
    proc = subprocess.Popen([sys.executable, "-m", "shapecond", "batch", str(folder), "--points", "60",
                             "--out", str(out)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while proc.poll() is None and time.monotonic() < deadline:
        done = (len(read_table(out)) if out.exists() else 0) + \
            (journal.read_text().count("\n") if journal.exists() else 0)
        if done >= 2:
            break
        time.sleep(0.02)
    assert proc.poll() is None, "the batch ended before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    before = read_table(out)  # readable after SIGKILL, though it may lag the journal
    assert len(before) < 6 and (tmp_path / ".t.parquet.lock").exists()
    os.environ["SHAPECOND_CACHE"], saved = str(tmp_path / "cache"), os.environ["SHAPECOND_CACHE"]
    try:
        resumed = run_batch([folder], out, {"points": 60}, how=BatchRun(resume=True))  # the killed batch's lock is gone
        fresh = run_batch([folder], tmp_path / "fresh.parquet", {"points": 60})
    finally:
        os.environ["SHAPECOND_CACHE"] = saved
    assert resumed.resumed >= 2 and resumed.scored == 6 - resumed.resumed and resumed.failed == 0
    same_rows(read_table(tmp_path / "fresh.parquet"), read_table(out))
    assert not journal.exists()


def _running(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            return fh.read().rsplit(b")", 1)[1].split()[0] not in (b"Z", b"X")  # a zombie has ended
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc/self") or len(os.sched_getaffinity(0)) < 2,
                    reason="reads /proc; the geodesic helper needs two CPUs")
def test_a_batch_killed_while_its_helper_works_leaves_no_process_and_resumes(tmp_path):
    """A kill -9 left the forked geodesic helper running for good, holding the output's lock: --resume
    answered "being written by another batch" (the dead one) for ever."""
    from shapecond.shapes.synthetic import bumpy_blob

    folder = tmp_path / "in"
    folder.mkdir()
    for k in range(4):
        g = bumpy_blob(subdivisions=3, seed=30 + k)
        write_mesh(folder / f"b{k}.off", g.vertices, g.faces)
    out = tmp_path / "t.csv"
    env = {k: v for k, v in os.environ.items() if k != "SHAPECOND_WORKERS"}
    cmd = [sys.executable, "-m", "shapecond", "batch", str(folder), "--points", "60", "--no-cache", "--out", str(out)]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline, kids = time.monotonic() + 60, set()
    while proc.poll() is None and not kids and time.monotonic() < deadline:
        kids = descendants(proc.pid)
        time.sleep(0.01)
    assert kids, "the batch ended (or did not fork its helper) before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    deadline = time.monotonic() + 5
    while any(map(_running, kids)) and time.monotonic() < deadline:
        time.sleep(0.05)
    left = [p for p in kids if _running(p)]
    for p in left:
        os.kill(p, signal.SIGKILL)
    assert not left, "processes of the killed batch are still running"
    resumed = subprocess.run(cmd + ["--resume"], env=env, capture_output=True, text=True, timeout=120)
    assert resumed.returncode == 0, resumed.stderr
    assert len(read_table(out)) == 4


def test_jobs_and_scheduler_parse():
    assert parallel.parse_scheduler("local:3") == ("local", 3)
    assert parallel.parse_scheduler("tcp://10.0.0.1:8786") == ("address", "tcp://10.0.0.1:8786")
    for bad in ("local:", "local:x", "nonsense"):
        with pytest.raises(InputError):
            parallel.parse_scheduler(bad)

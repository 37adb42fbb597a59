"""Running independent tasks in parallel: local processes (joblib) or a Dask cluster.

A task is ``(function, args, kwargs)``.  Where tasks run is what the command
line's ``--jobs`` and ``--scheduler`` say:

* ``n_jobs = 1`` and no scheduler: one after the other in this process;
* ``n_jobs = J``: J local worker processes from joblib's process pool (loky),
  each limited to its share of the cores for BLAS, OpenMP and numba threads;
* ``scheduler = "tcp://HOST:PORT"`` (any address ``dask.distributed`` accepts):
  the workers of an existing cluster;
* ``scheduler = "local:W"``: a ``LocalCluster`` of W single-threaded worker
  processes on the loopback interface, started and stopped here, without a
  dashboard.  Its workers get the loky workers' share of the cores for BLAS,
  OpenMP and numba threads, and not Dask's default ``MALLOC_TRIM_THRESHOLD_``
  of 64 KiB: with it every large numpy array freed goes back to the kernel and
  the next one faults its pages in again, 1.1–1.5 s of system time in a 5k-vertex
  ``match`` of about 5 s (0.1 s without), and numba's parallel kernels could take
  both cores in each of the two workers.  A variable already set in this
  process's environment wins (Dask's rule).  A cluster of the user's own
  (``tcp://``) keeps its configuration.

``iter_tasks`` yields ``(index, result, error)`` in completion order: a task
that raises, or whose worker process dies, gives its error and the others go
on.  A dying loky worker breaks the whole pool; since at most J tasks are in
flight, those are the suspects, and each is retried alone in a fresh pool, so
that only the task that kills its worker on its own is reported as failed.
On Dask the scheduler reschedules a task whose worker died up to
``distributed.scheduler.allowed-failures`` times (3 by default) and then fails
it with ``KilledWorker``.  ``run_tasks`` is the all-or-nothing form: the
first error is raised.

Every worker must see the input paths under the same names and should share
the cache folder ``$SHAPECOND_CACHE``: a worker with its own cache recomputes
the distance matrices (same results, more time); a worker that cannot see a
file fails that task with a one-line error naming its host.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import socket
import sys
import time
import uuid
from collections import deque
from concurrent.futures import FIRST_COMPLETED, wait

from shapecond._version import __version__
from shapecond.errors import InputError

#: Seconds to wait for a Dask scheduler to answer before giving up.
CONNECT_TIMEOUT = 10.0
#: Seconds a Dask cluster may have no worker at all before the run is abandoned.
NO_WORKER_TIMEOUT = 60.0
#: Seconds between two looks at a Dask cluster's workers while no task completes.
POLL_SECONDS = 5.0
_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS",
                     "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS", "NUMBA_NUM_THREADS")
#: What a Dask nanny writes into this process's environment (``_restore_environment``).
_NANNY_VARIABLES = ("MALLOC_TRIM_THRESHOLD_", *_THREAD_VARIABLES)


class WorkerDied(RuntimeError):
    """The process running a task ended (crash, out-of-memory kill) before the task did."""


def parse_scheduler(text):
    """``None``, ``("local", W)`` for ``local:W``, or ``("address", text)`` for a scheduler address.

    A ``dask.distributed.Client`` passes through as ``("client", client)``.
    """
    if text is None:
        return None
    if not isinstance(text, str):
        return ("client", text)
    text = text.strip()
    if text.startswith("local:") or text == "local":
        w = text.partition(":")[2]
        if not w.isdigit() or int(w) < 1:
            raise InputError(f"--scheduler {text!r}: expected local:W with W >= 1 workers, e.g. local:2")
        return ("local", int(w))
    if "://" not in text and ":" not in text:
        raise InputError(f"--scheduler {text!r}: expected tcp://HOST:PORT or local:W")
    return ("address", text)


def _client(kind, value):
    """A ``(client, cluster)`` pair for a parsed scheduler; the caller closes what it opened."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise InputError("--scheduler needs dask: pip install 'shapecond[dask]'") from None
    if kind == "client":
        return value, None
    if kind == "local":
        import dask

        # the workers' environment replaces Dask's default one (module docstring)
        with dask.config.set({"distributed.nanny.pre-spawn-environ": _thread_env(value)}):
            cluster = LocalCluster(n_workers=value, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=None, silence_logs=logging.ERROR)
        return Client(cluster), cluster
    try:
        return Client(value, timeout=CONNECT_TIMEOUT), None
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at {value} within {CONNECT_TIMEOUT:.0f} s "
                         f"({exc.__class__.__name__})") from None


def _worker_version():
    from shapecond._version import __version__ as on_worker  # imported on the worker: its own install

    return on_worker


def check_workers(client) -> int:
    """Number of workers; InputError if one cannot import shapecond or runs another version."""
    try:
        versions = client.run(_worker_version)
    except ImportError:
        raise InputError("shapecond is not installed on every Dask worker") from None
    bad = {w: v for w, v in versions.items() if v != __version__}
    if bad:
        w, v = next(iter(bad.items()))
        raise InputError(f"Dask worker {w} runs shapecond {v}, this client {__version__}: "
                         "install the same version everywhere")
    return len(versions)


class Runner:
    """Where tasks run; made by ``runner`` (a context manager), used through ``iter_tasks``."""

    def __init__(self, n_jobs=1, client=None, label=""):
        self.n_jobs, self.client, self.label = n_jobs, client, label

    @property
    def workers(self) -> int:
        if self.client is None:
            return self.n_jobs
        return len(self.client.scheduler_info().get("workers", {}))

    def iter_tasks(self, tasks):
        """Yield ``(index, result, error)`` for ``tasks`` in completion order (see module docstring)."""
        tasks = list(tasks)
        if self.client is not None:
            yield from _iter_dask(self.client, tasks)
        elif self.n_jobs == 1:
            for i, (f, a, k) in enumerate(tasks):
                yield (i, *_outcome(f, *a, **k))
        else:
            yield from _iter_loky(tasks, self.n_jobs)


def check_where(n_jobs=1, scheduler=None):
    """The parsed scheduler (``parse_scheduler``) after checking ``n_jobs`` against it; InputError if wrong."""
    if n_jobs < 1:
        raise InputError("--jobs must be at least 1")
    parsed = parse_scheduler(scheduler)
    if parsed is not None and n_jobs != 1:
        raise InputError("--jobs and --scheduler exclude each other (the cluster's workers do the work)")
    return parsed


@contextlib.contextmanager
def runner(n_jobs=1, scheduler=None):
    """A ``Runner`` for ``n_jobs`` local processes or a Dask scheduler (closed on exit)."""
    parsed = check_where(n_jobs, scheduler)
    if parsed is None:
        yield Runner(n_jobs, None, "this process" if n_jobs == 1 else f"{n_jobs} local processes")
        return
    saved = {name: os.environ.get(name) for name in _NANNY_VARIABLES}
    try:
        client, cluster = _client(*parsed)
    finally:
        _restore_environment(saved)
    try:
        n = check_workers(client)
        label = (f"a LocalCluster of {n} workers" if parsed[0] == "local"
                 else f"the Dask cluster at {client.scheduler.address} ({n} workers)")
        yield Runner(1, client, label)
    finally:
        if parsed[0] != "client":
            client.close()
        if cluster is not None:
            cluster.close()
        _restore_environment(saved)  # a worker restarted during the run wrote them again


def run_tasks(tasks, n_jobs=1, scheduler=None, progress=False, desc="tasks"):
    """Run ``(function, args, kwargs)`` tasks; results in completion order; the first error is raised.

    ``scheduler``: a Dask scheduler address (``tcp://host:8786``), ``local:W``,
    or a ``dask.distributed.Client``.
    """
    from tqdm import tqdm

    tasks = list(tasks)
    results = []
    with runner(n_jobs, scheduler) as run, \
            tqdm(total=len(tasks), desc=desc, unit="task", disable=not progress) as bar:
        for _, result, error in run.iter_tasks(tasks):
            if error is not None:
                raise error
            results.append(result)
            bar.update(1)
    return results


def _outcome(f, *args, **kwargs):
    """``(result, None)`` or ``(None, exception)`` of one call."""
    try:
        return f(*args, **kwargs), None
    except Exception as exc:  # noqa: BLE001 - reported per task
        return None, exc


def _restore_environment(saved: dict) -> None:
    """Put back the variables of ``_NANNY_VARIABLES`` as they were (``saved``, None: unset).  A Dask
    nanny writes its workers' environment into this process's (``os.environ.update``) before it spawns
    each worker; left there, the thread limits reach this process's own numba, which refuses a
    ``NUMBA_NUM_THREADS`` changed after its threads started (an API user's next call would fail), and
    the next cluster's nanny reads them first."""
    for name, value in saved.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


def _thread_env(n_jobs: int) -> dict:
    share = str(max(1, (os.cpu_count() or 1) // n_jobs))
    return {name: share for name in _THREAD_VARIABLES}


def _in_worker(parent_pid, f, args, kwargs):
    """Run one task in a pool worker that ends with the command, even on SIGKILL."""
    from .shapes.helper import die_with_parent

    die_with_parent(parent_pid)
    return f(*args, **kwargs)


def _iter_loky(tasks, n_jobs):
    """Tasks on joblib's loky pool, at most ``n_jobs`` in flight (no more workers than tasks
    and cores: ``cap_jobs``); suspects of a crash retried alone."""
    from joblib.externals.loky import get_reusable_executor
    from joblib.externals.loky.process_executor import BrokenProcessPool


    n_jobs = cap_jobs(n_jobs, len(tasks))
    queue, suspects, running = deque(range(len(tasks))), deque(), {}
    parent = os.getpid()

    def submit(i, alone):
        f, a, k = tasks[i]
        ex = get_reusable_executor(max_workers=n_jobs, env=_thread_env(n_jobs))
        running[ex.submit(_in_worker, parent, f, a, k)] = (i, alone)

    while queue or suspects or running:
        if suspects and not running:
            submit(suspects.popleft(), True)
        while not suspects and queue and len(running) < n_jobs:
            submit(queue.popleft(), False)
        done, _ = wait(list(running), return_when=FIRST_COMPLETED)
        if any(isinstance(f.exception(), BrokenProcessPool) for f in done):
            # the pool is broken: every task in flight fails with it; those are the suspects
            done = list(running)
        for fut in done:
            i, alone = running.pop(fut)
            result, error = _outcome(fut.result)
            if isinstance(error, BrokenProcessPool):
                if not alone:
                    suspects.append(i)
                    continue
                error = WorkerDied("the worker process died while running this task "
                                   f"({str(error).splitlines()[0][:120]})")
            yield i, result, error


def _iter_dask(client, tasks):
    """Tasks as Dask futures; an unavailable cluster ends the run with an InputError, not a hang."""
    from dask.distributed import wait as dask_wait

    # one key prefix for every task of the run: Dask then sees one large task group
    # ("root-ish") and queues it on the scheduler, handing a worker only what it can run
    # now, so a task that kills its worker takes no innocent task queued behind it along
    futures = {}
    for i, (f, a, k) in enumerate(tasks):
        futures[client.submit(f, *a, key=f"shapecond-task-{uuid.uuid4().hex}", **k)] = i
    remaining, idle_since = set(futures), None
    try:
        while remaining:
            try:
                done, remaining = dask_wait(list(remaining), timeout=POLL_SECONDS, return_when="FIRST_COMPLETED")
            except TimeoutError:
                if client.scheduler_info().get("workers"):
                    idle_since = None
                elif idle_since is None:
                    idle_since = time.monotonic()
                elif time.monotonic() - idle_since > NO_WORKER_TIMEOUT:
                    raise InputError(f"the Dask cluster has had no worker for {NO_WORKER_TIMEOUT:.0f} s; "
                                     f"{len(remaining)} tasks were not run") from None
                continue
            remaining = set(remaining)
            for fut in done:
                i = futures[fut]
                if fut.status == "finished":
                    yield i, fut.result(), None
                elif fut.status == "cancelled":
                    yield i, None, WorkerDied("the Dask scheduler cancelled this task")
                elif fut.status == "error":
                    yield i, None, fut.exception()
                else:  # finished, then its result was lost with a dying worker: Dask computes it again
                    remaining.add(fut)
                    continue
                fut.release()
    finally:
        for fut in remaining:
            fut.cancel()


# --- per-task accounting -----------------------------------------------------------

def worker_name() -> str:
    """``host:pid`` of this process (rows say where they were computed)."""
    return f"{socket.gethostname()}:{os.getpid()}"


class PeakMemory:
    """Peak resident memory (MiB) of this process while the ``with`` block ran.

    On Linux the kernel's high-water mark (``VmHWM``) is reset on entry by
    writing 5 to ``/proc/self/clear_refs``, so the figure is this block's own
    peak, interpreter and libraries included.  Elsewhere (or if the reset is
    refused) it is the process's lifetime peak (``ru_maxrss``), an upper bound;
    ``exact`` says which.
    """

    def __enter__(self):
        try:
            with open("/proc/self/clear_refs", "w") as fh:
                fh.write("5")
            self.exact = True
        except OSError:
            self.exact = False
        self.mib = math.nan
        return self

    def __exit__(self, *exc):
        self.mib = _vm_hwm_mib() if self.exact else math.nan
        if math.isnan(self.mib):  # no /proc: the lifetime peak (kB on Linux, bytes on macOS)
            import resource

            rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            self.mib = rss / (2 ** 20 if sys.platform == "darwin" else 2 ** 10)
            self.exact = False
        return False


def _vm_hwm_mib() -> float:
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return math.nan


def cap_jobs(n_jobs: int, n_tasks: int) -> int:
    """At most one worker per task and per core (``os.cpu_count``), at least one."""
    import os

    return max(1, min(int(n_jobs), int(n_tasks), os.cpu_count() or 1))

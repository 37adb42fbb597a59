"""Running independent tasks in parallel: local processes (joblib) or a Dask cluster.

A task is ``(function, args, kwargs)``; ``run_tasks`` runs a list of them with
joblib, either in ``n_jobs`` local processes or, given a Dask scheduler address,
through joblib's ``"dask"`` backend on that cluster (needs ``dask[distributed]``;
every worker must see the input paths and should share the cache folder
``$SHAPECOND_CACHE``).
"""

from __future__ import annotations

from shapecond.errors import InputError


def run_tasks(tasks, n_jobs=1, scheduler=None, progress=False):
    """Run ``(function, args, kwargs)`` tasks with joblib; results in completion order.

    ``scheduler``: a Dask scheduler address (``tcp://host:8786``) or a
    ``dask.distributed.Client``; joblib's ``"dask"`` backend then ships the tasks.
    """
    import joblib
    from tqdm import tqdm

    tasks = list(tasks)
    bar = tqdm(total=len(tasks), desc="matching", unit="shape", disable=not progress)
    if scheduler is not None:
        try:
            from dask.distributed import Client
        except ImportError:
            raise InputError("--scheduler needs dask: pip install 'shapecond[dask]'") from None
        client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
        ctx = joblib.parallel_config(backend="dask")
    else:
        client, ctx = None, joblib.parallel_config(backend="loky" if n_jobs != 1 else "sequential")
    results = []
    try:
        with ctx:
            par = joblib.Parallel(n_jobs=-1 if scheduler is not None else n_jobs,
                                  return_as="generator_unordered")
            for res in par(joblib.delayed(f)(*a, **k) for f, a, k in tasks):
                results.append(res)
                bar.update(1)
    finally:
        bar.close()
        if client is not None and client is not scheduler:
            client.close()
    return results

"""Batch scoring throughput: 1 and 2 local processes and a 2-worker LocalCluster on the same TOSCA meshes.

Usage: python benchmarks/bench_batch.py TOSCA_DIR [--points 200] [--count 20] [--no-write]

TOSCA_DIR is ``shared/data/tosca_hires``.  ``--count`` meshes are taken evenly
spread over the sorted list of meshes that can be scored as they are (gorilla,
with 38 components, is left out).  Each configuration runs ``shapecond batch`` in
a fresh process with an empty cache folder (so each computes its geodesics),
then the single-process run is repeated on its warm cache to split the time
between geodesics and the search.  Also measured in this process: the cost per
task of each runner (a task that returns a row-sized dict), hashing the inputs,
and appending 10,000 rows to a Parquet table.  Writes the ``batch`` section of
benchmarks/RESULTS.md.
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _results import command_line, machine, write_section  # noqa: E402

CONFIGS = [("1 process", ["--jobs", "1"], 1), ("2 processes (joblib)", ["--jobs", "2"], 2),
           ("LocalCluster, 2 workers", ["--scheduler", "local:2"], 2)]


def pick(root: Path, count: int) -> list[Path]:
    files = sorted(p for p in root.rglob("*.off") if p.parent.name != "gorilla")
    if count >= len(files):
        return files
    return [files[round(i * (len(files) - 1) / (count - 1))] for i in range(count)]


def load_rows(path: Path) -> list[dict]:
    import pyarrow.parquet as pq

    return pq.read_table(path).to_pylist()


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run_batch_process(files, points, extra, cache, out) -> dict:
    env = dict(os.environ, SHAPECOND_CACHE=str(cache))
    cmd = [sys.executable, "-m", "shapecond", "batch", *map(str, files), "--points", str(points),
           "--out", str(out), "--overwrite", "--json", *extra]
    t0, c0 = time.perf_counter(), _children_cpu()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, _children_cpu() - c0
    if proc.returncode not in (0, 3):
        raise RuntimeError(proc.stderr.strip().splitlines()[-1])
    summary = json.loads(proc.stdout)
    rows = load_rows(out)
    by_worker = {}
    for r in rows:
        by_worker.setdefault(r["worker"], []).append(r)
    return dict(wall=wall, cpu=cpu, load=os.getloadavg()[0], summary=summary, rows=rows,
                busy=sum(r["seconds"] for r in rows), busy_cpu=sum(r["cpu_seconds"] for r in rows),
                median=statistics.median(r["seconds"] for r in rows),
                median_cpu=statistics.median(r["cpu_seconds"] for r in rows),
                peak={w: max(r["peak_memory_mib"] for r in rs) for w, rs in by_worker.items()},
                per_worker={w: len(rs) for w, rs in by_worker.items()},
                failed=sum(r["error"] is not None for r in rows))


def _row_task(i):
    from shapecond.batch import schema

    row = schema.empty_row()
    row.update(file=f"/data/shape{i}.off", content_hash="0" * 64, params="x" * 180, sigma_lower=1.0)
    return row


def task_overhead(n_tasks=400) -> dict:
    """Seconds per task of each runner for a task that only returns a row."""
    from shapecond.parallel import runner

    out = {}
    for label, jobs, sched in (("this process", 1, None), ("2 processes (joblib)", 2, None),
                               ("LocalCluster, 2 workers", 1, "local:2")):
        with runner(jobs, sched) as run:
            list(run.iter_tasks([(_row_task, (i,), {}) for i in range(20)]))  # warm up the workers
            t0 = time.perf_counter()
            results = list(run.iter_tasks([(_row_task, (i,), {}) for i in range(n_tasks)]))
            out[label] = (time.perf_counter() - t0) / n_tasks
        assert all(e is None for _, _, e in results)
    return out


def client_costs(files, n_rows=10_000) -> dict:
    from shapecond.batch.inputs import content_hashes
    from shapecond.batch.table import Table

    size = sum(p.stat().st_size for p in files) / 2 ** 20
    t0 = time.perf_counter()
    content_hashes([str(p) for p in files])
    hash_s = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "t.parquet"
        t0 = time.perf_counter()
        with Table(path) as table:
            for i in range(n_rows):
                row = _row_task(i)
                row.update(landmarks=[1, 2, 3], landmark_scores=[0.5, 0.4, 0.3], seconds=1.0)
                table.append(row)
            t1 = time.perf_counter()
            table._snapshot()  # what every rewrite costs once the table is this large
            snapshot = time.perf_counter() - t1
        append_s = time.perf_counter() - t0
        mib = path.stat().st_size / 2 ** 20
    return dict(hash_mib=size, hash_s=hash_s, append_s=append_s, n_rows=n_rows, snapshot_s=snapshot,
                parquet_mib=mib)


#: The collection and cluster of the projection paragraph.
PROJECT_SHAPES, PROJECT_NODES, WORKERS_PER_NODE = 10_000, 100, 2
MEASURES = Path(__file__).with_name("out") / "bench_batch.json"


def main(argv):
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tosca_dir", type=Path)
    parser.add_argument("--points", type=int, default=200)
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--no-write", action="store_true")
    parser.add_argument("--from-json", action="store_true",
                        help=f"rebuild the section from the measurements saved in {MEASURES.name}")
    args = parser.parse_args(argv)
    if args.from_json:
        m = json.loads(MEASURES.read_text())
    else:
        m = measure(pick(args.tosca_dir, args.count), args.points)
        MEASURES.parent.mkdir(exist_ok=True)
        MEASURES.write_text(json.dumps(m))
    body = report(m)
    print(body)
    if not args.no_write:
        write_section("batch", body)


def measure(files, points) -> dict:
    load = os.getloadavg()
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for label, extra, workers in CONFIGS:
            cache = tmp / f"cache-{len(results)}"
            r = run_batch_process(files, points, extra, cache, tmp / f"{len(results)}.parquet")
            r["workers"] = workers
            results[label] = r
            print(f"{label}: {r['wall']:.1f} s, {60 * len(files) / r['wall']:.2f} shapes/min, "
                  f"peak {max(r['peak'].values()):.0f} MiB", flush=True)
        warm = run_batch_process(files, points, ["--jobs", "1"], tmp / "cache-0", tmp / "warm.parquet")
        warm["workers"] = 1
        cache_mib = sum(p.stat().st_size for p in (tmp / "cache-0").iterdir()) / 2 ** 20
    agrees = agree(results)
    return dict(files=[p.stem for p in files], file_mib=[p.stat().st_size / 2 ** 20 for p in files], points=points,
                command=command_line(), machine=machine(), load=load, load_after=os.getloadavg(),
                results=results, warm=warm, agree=agrees, overhead=task_overhead(), client=client_costs(files),
                cache_mib=cache_mib)


def report(m) -> str:
    n, results, warm, client = len(m["files"]), m["results"], m["warm"], m["client"]
    base = results["1 process"]
    load, load_after = m["load"], m["load_after"]
    lines = ["## Batch scoring: throughput on one machine and a LocalCluster (bench_batch.py)", "",
             f"Machine: {m['machine']}. Command: `{m['command']}`. Load average before "
             f"{load[0]:.2f} / {load[1]:.2f}, after {load_after[0]:.2f} / {load_after[1]:.2f} (1 / 5 min).",
             "",
             f"{n} TOSCA meshes ({', '.join(m['files'])}; {sum(m['file_mib']):.0f} MiB of OFF), N = {m['points']}, "
             f"dense targets M = {8 * m['points']}, default effort; each configuration is a fresh `shapecond batch` "
             "process with an empty cache folder, so it computes every geodesic matrix. CPU = user + system time "
             "of the batch process and all its workers; rows = sums of the rows' `seconds` (wall) and "
             "`cpu_seconds`; rows' wall / rows' CPU above 1 means the workers waited for a core (the 2 cores are "
             "shared with other jobs, see the load); peak = the largest `peak_memory_mib` of any row of that "
             "worker process.", "",
             "| configuration | wall (s) | shapes/min | speed-up | CPU (s) | rows' wall (s) | rows' CPU (s) | "
             "rows' wall / CPU | median CPU s/shape | peak MiB per worker | shapes per worker | load at end |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for label, r in [*results.items(), ("1 process, warm cache", warm)]:
        lines.append(f"| {label} | {r['wall']:.1f} | {60 * n / r['wall']:.2f} | {base['wall'] / r['wall']:.2f} | "
                     f"{r['cpu']:.0f} | {r['busy']:.0f} | {r['busy_cpu']:.0f} | {r['busy'] / r['busy_cpu']:.2f} | "
                     f"{r['median_cpu']:.1f} | {', '.join(f'{v:.0f}' for v in sorted(r['peak'].values()))} | "
                     f"{', '.join(str(v) for v in sorted(r['per_worker'].values()))} | {r['load']:.2f} |")
    failed = {label: r["failed"] for label, r in results.items() if r["failed"]}
    overhead = m["overhead"]
    lines += ["", f"Failed rows: {failed or 'none'}. Rows of the three configurations agree: {m['agree']}.", "",
              "Per-task cost of each runner (a task that returns a row-sized dict; 400 tasks after 20 warm-up "
              "tasks): " + ", ".join(f"{k} {1e3 * v:.2f} ms" for k, v in overhead.items()) + ".", "",
              f"Client side: hashing the {n} inputs ({client['hash_mib']:.0f} MiB) took {client['hash_s']:.2f} s "
              f"({client['hash_mib'] / client['hash_s']:.0f} MiB/s, warm page cache); appending "
              f"{client['n_rows']:,} rows to a Parquet table took {client['append_s']:.1f} s "
              f"({1e3 * client['append_s'] / client['n_rows']:.2f} ms per row, journal line plus the periodic "
              f"atomic rewrite); one rewrite of all {client['n_rows']:,} rows takes {client['snapshot_s']:.2f} s "
              f"(file {client['parquet_mib']:.1f} MiB). Cache written by the single-process run: "
              f"{m['cache_mib']:.0f} MiB ({m['cache_mib'] / n:.1f} MiB per shape).", "", projection(m)]
    return "\n".join(lines)


def projection(m) -> str:
    """The paragraph on a 100-node cluster scoring 10,000 meshes, every figure from ``m``."""
    n, base, warm, client = len(m["files"]), m["results"]["1 process"], m["warm"], m["client"]
    rows = base["rows"]
    cold = base["busy_cpu"] / n                 # CPU seconds per shape, geodesics included
    hot = warm["busy_cpu"] / n                  # the same shapes with their distance matrices cached
    longest = max(r["cpu_seconds"] for r in rows)
    workers = PROJECT_NODES * WORKERS_PER_NODE
    total_h = PROJECT_SHAPES * cold / 3600
    ideal = PROJECT_SHAPES * cold / workers
    per_task = m["overhead"]["LocalCluster, 2 workers"]
    rate = workers / cold                        # tasks per second the scheduler must hand out
    mib_shape = sum(m["file_mib"]) / n
    read_gib = PROJECT_SHAPES * mib_shape / 1024
    cache_shape = m["cache_mib"] / n
    lc = m["results"]["LocalCluster, 2 workers"]
    top = max((r for res in m["results"].values() for r in res["rows"]), key=lambda r: r["peak_memory_mib"])
    peak = top["peak_memory_mib"]
    why = (", so the shortfall is the shared cores, not the runner." if lc["busy_cpu"] < 1.15 * base["busy_cpu"]
           else ": two busy processes on this virtual machine's two cores, which other jobs share too, each "
                "get less done per CPU second than one alone, and each fresh worker pays its imports on its "
                "first shape; separate cluster nodes do not share cores that way.")
    rewrite = client["snapshot_s"]
    return (
        f"**A {PROJECT_NODES}-node cluster and {PROJECT_SHAPES:,} meshes** (projected from the figures above, "
        f"for meshes like these {n}: {mib_shape:.1f} MiB of OFF and {cold:.1f} CPU s per shape on average "
        f"at N = {m['points']}, the longest {longest:.0f} s). "
        f"*Where the time goes*: {PROJECT_SHAPES:,} x {cold:.1f} s = {total_h:.0f} CPU hours, of which "
        f"{1 - hot / cold:.0%} is building the distance matrices (farthest-point sampling of M = {8 * m['points']} "
        f"targets by heat geodesics; the warm-cache run needs {hot:.1f} s per shape) and the rest the witness "
        f"search and the resolution report. With {WORKERS_PER_NODE} single-threaded workers per node "
        f"({workers} workers, one per core as here) that is {ideal / 60:.0f} minutes if every core is busy, "
        f"plus at most one longest shape ({longest:.0f} s) of tail. On this machine the 2-worker LocalCluster "
        f"reached {base['wall'] / lc['wall']:.2f}x one worker: its rows took {lc['busy'] / lc['busy_cpu']:.2f}x "
        f"their CPU time in wall time (waiting for cores shared with other jobs; one worker alone: "
        f"{base['busy'] / base['busy_cpu']:.2f}x) while their CPU time per shape was "
        f"{lc['busy_cpu'] / base['busy_cpu']:.2f}x the single worker's{why} "
        f"*The scheduler*: {1e3 * per_task:.1f} ms per task here, all included (submission, one row back) "
        f"and with the scheduler sharing the two cores with its workers, "
        f"i.e. about {1 / per_task:.0f} tasks per second, while {workers} workers finishing a shape every "
        f"{cold:.0f} s need {rate:.0f} per second ({rate * per_task:.0%} of that); the {PROJECT_SHAPES:,} "
        f"tasks cost the scheduler {PROJECT_SHAPES * per_task:.0f} s in all. The client hashes every input "
        f"before the first task ({read_gib:.0f} GiB at {client['hash_mib'] / client['hash_s']:.0f} MiB/s from "
        f"a warm page cache is {read_gib * 1024 / (client['hash_mib'] / client['hash_s']):.0f} s; from a "
        f"network file system at 100 MiB/s it would be {read_gib * 1024 / 100 / 60:.0f} minutes, the one "
        f"serial step worth overlapping with the work if collections grow further), and appends "
        f"{rate:.0f} rows per second at {1e3 * client['append_s'] / client['n_rows']:.2f} ms each; rewriting "
        f"the {PROJECT_SHAPES:,}-row Parquet file takes {rewrite:.2f} s and happens at most every "
        f"{max(2.0, 5 * rewrite):.0f} s. *What must be shared*: the {read_gib:.0f} GiB of meshes, under the "
        f"same paths on every node; the same shapecond version; and, for re-runs, the cache: "
        f"{cache_shape:.0f} MiB per shape is {PROJECT_SHAPES * cache_shape / 1024:.0f} GiB, written at "
        f"{workers * cache_shape / cold:.0f} MiB/s in aggregate while the batch runs. A single screening pass "
        f"computes each shape once whether or not the cache is shared (`--no-cache` spares the file system "
        f"that write); a second pass with other options is then {cold / hot:.1f}x cheaper with the cache than "
        f"without. *Memory*: {peak:.0f} MiB peak per worker process here ({Path(top['file']).stem}), so "
        f"{WORKERS_PER_NODE * peak / 1024:.1f} GiB per node for the workers, plus Dask's nanny processes.")


def agree(results) -> str:
    keys = ("sigma_lower", "sigma_hat", "resolution", "witness_moved", "error")
    tables = [{r["file"]: tuple(r[k] for k in keys) for r in res["rows"]} for res in results.values()]
    return "yes" if all(t == tables[0] for t in tables[1:]) else "NO (see the parquet files)"


if __name__ == "__main__":
    main(sys.argv[1:])

"""A collection matched on 1 and 2 Dask workers (issue 34): throughput, memory per worker, the same maps.

Usage:
    python benchmarks/bench_collection_workers.py RELEASE [--shapes 12] [--matcher faq] [--no-write]

RELEASE is a remeshed release (``SMAL_r``); its null shape is the template and the first ``--shapes``
other shapes the collection, each with 6 named landmarks carried through the ground truth, as
``bench_collection.py`` builds it.  The one command a user runs,
``shapecond batch COLLECTION --what match:TEMPLATE``, runs once per configuration in a fresh process
with an empty cache (every run computes its geodesics and bases): a LocalCluster of 1 worker limited
to one thread, of 1 worker with the threads of both cores (the product's share for one worker), of 2
workers, and 2 joblib processes.  Reported: wall time, the process tree's CPU time, maps per minute
and the ratio to 1 worker, the largest ``peak_memory_mib`` of a row (each row's worker's peak), and
whether every run wrote the same maps.  Writes the section ``collection-workers`` of
benchmarks/RESULTS.md.  Wall-time ratios need a machine with 2 idle cores: the load average before
and after each run is printed beside it.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402
from bench_collection import _children_cpu, _classes, build_collection  # noqa: E402

#: One thread for BLAS, OpenMP and numba (a variable set in the command's environment wins over the cluster's).
ONE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}
#: (name, options, environment) of each run; the first is the baseline of the ratios.
CONFIGS = [("LocalCluster, 1 worker, one thread", ["--scheduler", "local:1"], ONE_THREAD),
           ("LocalCluster, 1 worker (both cores' threads)", ["--scheduler", "local:1"], {}),
           ("LocalCluster, 2 workers", ["--scheduler", "local:2"], {}),
           ("joblib, 2 processes", ["--jobs", "2"], {})]


def _run(folder: Path, template: Path, out: Path, extra: list, env: dict, a) -> dict:
    cmd = [sys.executable, "-m", "shapecond", "batch", str(folder), "--out", str(out / "table.jsonl"), "--json",
           "--what", f"match:{folder / template.name}", "--matcher", a.matcher, *extra]
    env = dict(os.environ, SHAPECOND_CACHE=str(out / "cache"), **env)
    load0, t0, c0 = os.getloadavg()[0], time.perf_counter(), _children_cpu()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=folder, env=env)
    wall, cpu = time.perf_counter() - t0, _children_cpu() - c0
    if proc.returncode != 0:
        raise SystemExit(f"the command failed ({proc.returncode}): {proc.stderr.strip()[-2000:]}")
    rows = [json.loads(x) for x in (out / "table.jsonl").read_text().splitlines() if x.strip()]
    maps = hashlib.sha256(b"".join((out / "maps" / p).read_bytes() for p in sorted(os.listdir(out / "maps"))))
    return dict(wall=wall, cpu=cpu, load=(load0, os.getloadavg()[0]), rows=len(rows),
                failed=sum(r.get("error") is not None for r in rows),
                peak=max(r.get("peak_memory_mib") or 0 for r in rows), maps=maps.hexdigest()[:12])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("release", type=Path)
    p.add_argument("--shapes", type=int, default=12)
    p.add_argument("--matcher", default="faq")
    p.add_argument("--no-write", action="store_true")
    a = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_workers_") as tmp:
        os.environ["SHAPECOND_CACHE"] = str(Path(tmp) / "build-cache")
        classes = _classes(a.release, a.shapes)
        if len(classes) != 1:
            raise SystemExit("one class (a release such as SMAL_r) is needed: one template")
        folder = Path(tmp) / "collection"
        folder.mkdir()
        build_collection(classes, folder)
        results = {}
        for k, (name, extra, env) in enumerate(CONFIGS):
            out = Path(tmp) / f"run{k}"
            out.mkdir()
            results[name] = _run(folder, classes[0].null, out, extra, env, a)
            print(name, results[name], flush=True)
    base = results[CONFIGS[0][0]]
    lines = ["## A collection on 1 and 2 Dask workers (bench_collection_workers.py)", "", f"Machine: {machine()}", "",
             f"Command: `{command_line()}`", "",
             f"{classes[0].null.stem} matched to {len(classes[0].shapes)} shapes (itself included) of "
             f"{a.release.name}, matcher {a.matcher}, 6 landmarks per shape; each run a fresh process with an empty "
             "cache.", "",
             "| run | wall s | CPU s | maps / min | vs the first | largest peak per worker (MiB) | rows (failed) | "
             "maps (hash) | load before / after |", "|---|---|---|---|---|---|---|---|---|"]
    for name, r in results.items():
        rate = 60 * r["rows"] / r["wall"]
        lines.append(f"| {name} | {r['wall']:.0f} | {r['cpu']:.0f} | {rate:.1f} | {base['wall'] / r['wall']:.2f}x | "
                     f"{r['peak']:.0f} | {r['rows']} ({r['failed']}) | {r['maps']} | "
                     f"{r['load'][0]:.1f} / {r['load'][1]:.1f} |")
    text = "\n".join(lines)
    print(text)
    if not a.no_write:
        write_section("collection-workers", text)


if __name__ == "__main__":
    main()

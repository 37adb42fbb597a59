"""Limits honoured: time of each guard, measured on the command line (issue "every limit honoured").

Usage::

    python benchmarks/bench_limits.py DATASET_DIR [--write]

Runs each command in a fresh process and reports its exit status, wall and CPU
time: the long requests must be refused (exit 2, one line with the estimate) in
about a second, and ``score --exact --time-limit 10`` at N = 400 must return
within 30 s.  The baseline is the same ``score`` without ``--exact``, measured in
the same run.  ``--write`` replaces the "limits" section of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RESULTS = Path(__file__).with_name("RESULTS.md")
SECTION = "## Limits honoured (bench_limits.py)"


def run(argv):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "shapecond", *argv], capture_output=True, text=True,
                       stdin=subprocess.DEVNULL, timeout=3600)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    last = (p.stderr.strip().splitlines() or [""])[-1]
    return p.returncode, wall, cpu, last


def main(argv) -> int:
    data = Path(argv[1])
    write = "--write" in argv
    wolf = str(data / "wolf" / "wolf0.off")
    cat = str(data / "cat" / "cat0.off")
    cases = [
        ("score N=400 (baseline, cache warmed)", ["score", wolf]),
        ("score N=400 --exact --time-limit 10", ["score", wolf, "--exact", "--time-limit", "10"]),
        ("score N=400 --target samples --exact --time-limit 10",
         ["score", wolf, "--target", "samples", "--exact", "--time-limit", "10"]),
        ("cat0: score -n 4000 (refused)", ["score", cat, "-n", "4000"]),
        ("cat0: heatmap -n 2000 (refused)", ["heatmap", cat, "-n", "2000", "--png", "/dev/null"]),
        ("kappa N=8 --trials 1e9 (refused)", ["kappa", "demo:animal", "--trials", "1000000000"]),
        ("kappa N=8 --trials 1e9 --time-limit 5", ["kappa", "demo:animal", "--trials", "1000000000",
                                                   "--time-limit", "5"]),
        ("demo:sphere:subdivisions=14 (refused)", ["info", "demo:sphere:subdivisions=14"]),
        ("cat0: score --geodesic-backend exact (refused)", ["score", cat, "--geodesic-backend", "exact", "--no-cache"]),
    ]
    os.environ.setdefault("SHAPECOND_CACHE", tempfile.mkdtemp())
    run(["score", wolf])  # warm the distance cache: every row below times the guard, not geodesics
    rows = []
    for name, args in cases:
        code, wall, cpu, last = run(args)
        rows.append((name, code, wall, cpu, last))
        print(f"{name:55s} exit {code}  wall {wall:6.1f} s  CPU {cpu:6.1f} s  {last[:110]}")
    load = os.getloadavg()
    lines = [SECTION, "",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, load average {load[0]:.2f} {load[1]:.2f} "
             f"{load[2]:.2f} at the end; command: `python benchmarks/bench_limits.py {argv[1]} --write`; "
             "each command in a fresh process, the distance cache warmed first.", "",
             "| request | exit | wall s | CPU s | last stderr line |", "|---|---|---|---|---|"]
    for name, code, wall, cpu, last in rows:
        lines.append(f"| {name} | {code} | {wall:.1f} | {cpu:.1f} | {last[:140].replace('|', '/')} |")
    lines.append("")
    if write:
        text = RESULTS.read_text()
        if SECTION in text:
            start = text.index(SECTION)
            nxt = text.find("\n## ", start + len(SECTION))
            text = text[:start] + "\n".join(lines) + ("\n" + text[nxt + 1:] if nxt >= 0 else "")
        else:
            text = text.rstrip() + "\n\n" + "\n".join(lines)
        RESULTS.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

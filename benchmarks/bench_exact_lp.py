"""Exact σ and the LP upper bound: time versus N, tightness, and the done-when checks.

Writes the ``exact_lp`` section of benchmarks/RESULTS.md.  Four tables:

1. LP time and exact time versus N (6 ... 16) with upper/exact, on random and
   near-symmetric point sets (2D/3D), no landmarks;
2. 200 instances at N = 8 (random and near-symmetric, 2D and 3D, noise 0.01,
   0.05, 0.2): exact <= upper (1e-9 slack) and upper/exact <= 1.01, with and
   without the triangle cuts;
3. branch and bound at N = 16 (target: every instance within 10 s) and N = 20;
4. injective maps (N <= 6 samples into M <= 10 targets): the LP brackets exact.

Usage: python benchmarks/bench_exact_lp.py [--sizes 6,8,10,12,14,16] [--per-size 3]
       [--n8 200] [--bnb16 20] [--bnb20 8] [--lp-time-limit 900]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _results import command_line, machine, peak_rss_mb, write_section  # noqa: E402

from shapecond.symmetry.exact import exact_sigma  # noqa: E402
from shapecond.symmetry.relax import lp_upper_bound  # noqa: E402
from tests.helpers import dense_instance, mixed_instances, near_symmetric_instance, random_instance  # noqa: E402


def fmt(v, d=3):
    if v is None:
        return "-"
    if isinstance(v, float) and math.isinf(v):
        return "inf"
    return f"{v:.{d}f}" if isinstance(v, float) else str(v)


def table_sizes(sizes, per_size, lp_limit, rng):
    rows = ["| N | instance | exact σ | method | exact s | LP upper | upper/exact | LP s | LP variables | cuts |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    kinds = [("random 2D", lambda n: random_instance(rng, n, 2)),
             ("near-sym 3D, noise 0.05", lambda n: near_symmetric_instance(rng, n, 3, 0.05)),
             ("random 3D", lambda n: random_instance(rng, n, 3))]
    for n in sizes:
        for name, make in kinds[:per_size]:
            D = make(n)
            e = exact_sigma(D, time_limit=120)
            lp = lp_upper_bound(D, force=True, time_limit=lp_limit)
            ratio = lp.upper / e.sigma if e.sigma else None
            rows.append(f"| {n} | {name} | {fmt(e.sigma, 4)} | {e.method} | {e.seconds:.2f} | {fmt(lp.upper, 4)} | "
                        f"{fmt(ratio, 6)} | {lp.seconds:.2f} | {lp.n_variables} | {lp.n_cuts} |")
            print(rows[-1], flush=True)
    return "\n".join(rows)


def table_n8(count):
    worst, worst_plain, viol, loose, loose_plain, t_lp, t_ex = 1.0, 1.0, 0, 0, 0, 0.0, 0.0
    for D in mixed_instances(2024, count, 8):
        e = exact_sigma(D)
        lp = lp_upper_bound(D)
        plain = lp_upper_bound(D, cuts=False)
        t_lp += lp.seconds
        t_ex += e.seconds
        viol += int(not e.sigma <= lp.upper * (1 + 1e-9)) + int(not e.sigma <= plain.upper * (1 + 1e-9))
        worst, worst_plain = max(worst, lp.upper / e.sigma), max(worst_plain, plain.upper / e.sigma)
        loose += int(lp.upper / e.sigma > 1.01)
        loose_plain += int(plain.upper / e.sigma > 1.01)
    rows = ["| instances | exact > upper | LP with cuts: worst upper/exact | > 1.01 | "
            "paper's LP (no cuts): worst | > 1.01 | mean LP s | mean exact s |",
            "|---|---|---|---|---|---|---|---|",
            f"| {count} | {viol} | {worst:.7f} | {loose} | {worst_plain:.4f} | {loose_plain} | "
            f"{t_lp / count:.3f} | {t_ex / count:.3f} |"]
    print("\n".join(rows), flush=True)
    return "\n".join(rows)


def table_bnb(count, rng, n=16):
    times, rows = [], ["| instance | σ | finished | nodes | seconds |", "|---|---|---|---|---|"]
    for k in range(count):
        dim = 2 + (k // 2) % 2
        if k % 2 == 0:
            name, D = f"random {dim}D", random_instance(rng, n, dim)
        else:
            noise = (0.02, 0.1, 0.3)[(k // 2) % 3]
            name, D = f"near-sym {dim}D, noise {noise}", near_symmetric_instance(rng, n, dim, noise)
        e = exact_sigma(D, time_limit=60)
        times.append(e.seconds if e.finished else math.inf)
        rows.append(f"| {name} | {fmt(e.sigma, 4)} | {e.finished} | {e.nodes} | {e.seconds:.2f} |")
        print(rows[-1], flush=True)
    rows.append(f"| **all {count}** | | {sum(math.isfinite(t) for t in times)}/{count} | | "
                f"max {max(times):.2f}, median {float(np.median(times)):.2f} |")
    return "\n".join(rows)


def table_injective(count, rng):
    viol, worst = 0, 1.0
    for k in range(count):
        n = int(rng.integers(3, 7))
        m = int(rng.integers(n + 1, 11))
        D = dense_instance(rng, n, m, 2 + k % 2, None if k % 2 else 0.05)
        e = exact_sigma(D, n_samples=n)
        lp = lp_upper_bound(D, n_samples=n)
        viol += int(not e.sigma <= lp.upper * (1 + 1e-9))
        worst = max(worst, lp.upper / e.sigma)
    return ("| instances (N <= 6, N < M <= 10) | exact > upper | worst upper/exact |\n|---|---|---|\n"
            f"| {count} | {viol} | {worst:.4f} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="6,8,10,12,14,16")
    ap.add_argument("--per-size", type=int, default=2)
    ap.add_argument("--n8", type=int, default=200)
    ap.add_argument("--bnb16", type=int, default=20)
    ap.add_argument("--bnb20", type=int, default=8)
    ap.add_argument("--injective", type=int, default=40)
    ap.add_argument("--lp-time-limit", type=float, default=900)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    load = os.getloadavg()[0]
    parts = [f"Machine: {machine()}; load average at start {load:.1f} (the machine is shared, so times are "
             "pessimistic).", f"Command: `{command_line()}`", ""]
    parts += ["**Done-when: 200 instances at N = 8.**", "", table_n8(args.n8), ""]
    parts += ["**Injective maps (dense targets).**", "", table_injective(args.injective, rng), ""]
    parts += ["**Branch and bound at N = 16** (target: each within 10 s; half random, the hard case).", "",
              table_bnb(args.bnb16, rng, 16), ""]
    parts += ["**Branch and bound at N = 20** (time limit 60 s).", "", table_bnb(args.bnb20, rng, 20), ""]
    sizes = [int(s) for s in args.sizes.split(",")]
    parts += ["**LP time and exact time versus N** (LP with triangle cuts; exact by enumeration up to 9! "
              "maps, else branch and bound).", "", table_sizes(sizes, args.per_size, args.lp_time_limit, rng), ""]
    parts.append(f"Total {time.perf_counter() - t0:.0f} s, peak memory {peak_rss_mb():.0f} MB.")
    body = "## Exact σ and LP upper bound (bench_exact_lp.py)\n\n" + "\n".join(parts)
    print(body)
    write_section("exact_lp", body)


if __name__ == "__main__":
    main()

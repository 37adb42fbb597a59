"""The loop a user runs (issue 32): from 3 landmarks, add one at a time — the suggested point or the method's own.

Usage:
    python benchmarks/bench_suggest.py DATASET [--pairs FILE | --max-targets T] [--method fps] [--matcher faq]
           [--steps 3] [--points 400]

For every pair (a release's pairs list, or each class's null shape to its first
targets; ``shapecond.evaluation.datasets``), landmarks of ``--method`` on the
source (``sc.landmarks``), their images through the ground truth
(``evaluation.protocols.landmark_images``), and ``sc.match`` with the first 3.
Then ``--steps`` times: (a) the first suggestion of the current match
(``MatchResult.suggest``) with its *true* image from the ground truth (a user
who clicks the right point), and (b) the method's own next landmark.  Errors at
the reference points in units of sqrt(area) (``evaluation.protocols.reference_errors``),
the bar after each step, and whether it holds the error.  Written to
``benchmarks/RESULTS.md``, section ``suggest-loop``, with the CPU time of the
suggestions beside that of the matchings.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402
from _releases import groups  # noqa: E402


def _pairs(a):
    return [(g, t) for g in groups(a.dataset, a.pairs).values() for t in g.targets[:a.max_targets]]


def _error(g, ref_t, vmap_internal, ref_s):
    from shapecond.evaluation.protocols import reference_errors
    from shapecond.matching.sampled import surface_unit

    raw, diameter, _ = reference_errors(g, ref_t, {"m": vmap_internal[ref_s]}, "heat")
    return float(raw["m"].mean() / surface_unit(g, diameter))


def run_pair(group, target, a) -> dict:
    import shapecond as sc
    from shapecond.evaluation.protocols import _reference_ids, landmark_images
    from shapecond.matching.sampled import CachedSolver

    src, tgt = sc.load(group.null), sc.load(target)
    ref_s, ref_t = _reference_ids(group, group.null, src), _reference_ids(group, target, tgt)
    solver = CachedSolver(src, "heat")
    ids = [int(v) for v in sc.landmarks(group.null, 3 + a.steps, a.method, force=True).landmarks][:3 + a.steps]

    def image(ids_s):
        return [int(tgt.ids[v]) for v in landmark_images(src.to_internal(ids_s), ref_s, ref_t, solver)]

    def step(ids_s):
        t0 = time.process_time()
        r = sc.match(group.null, target, ids_s, image(ids_s), matcher=a.matcher, n_points=a.points, force=True)
        t1 = time.process_time()
        sug = r.suggest(1)
        t2 = time.process_time()
        vmap = tgt.to_internal(r.map[src.ids])
        return dict(error=_error(tgt, ref_t, vmap, ref_s), bar=r.summary["error_bar"]["bar"],
                    next=sug[0]["source_id"] if sug else None, match_cpu=t1 - t0, suggest_cpu=t2 - t1)

    out = {"pair": f"{group.null.stem}->{target.stem}", "suggested": [], "method": []}
    cur = ids[:3]
    first = step(cur)
    out["suggested"].append(first)
    out["method"].append(first)
    s = first
    for _ in range(a.steps):
        if s["next"] is None:
            break
        cur = cur + [s["next"]]
        s = step(cur)
        out["suggested"].append(s)
    for k in range(1, a.steps + 1):
        out["method"].append(step(ids[:3 + k]))
    return out


def summarise(rows, a) -> str:
    steps = a.steps
    lines = [f"Machine: {machine()}; load {os.getloadavg()[0]:.1f}.", "", f"Command: `{command_line()}`", "",
             f"{len(rows)} pairs, method {a.method}, matcher {a.matcher}, N = {a.points}; errors and bars in 10⁻³ "
             "sqrt(area), means over the pairs; held: share of maps whose bar is at least the error.", "",
             "| landmarks | suggested: error | bar | held | method's next: error | bar | held |", "|---|---|---|---|---|---|---|"]
    for k in range(steps + 1):
        cells = []
        for key in ("suggested", "method"):
            vals = [r[key][k] for r in rows if len(r[key]) > k]
            e = np.array([v["error"] for v in vals]) * 1e3
            b = np.array([v["bar"] for v in vals]) * 1e3
            cells += [f"{e.mean():.1f}", f"{b.mean():.1f}", f"{np.mean(b >= e):.2f}"]
        lines.append(f"| 3 + {k} | " + " | ".join(cells) + " |")
    failed = [r for r in rows if r["suggested"][0]["error"] > 0.05]
    repaired = [r for r in failed if any(s["error"] < 0.03 for s in r["suggested"][1:3])]
    cpu_m = np.mean([s["match_cpu"] for r in rows for s in r["suggested"]])
    cpu_s = np.mean([s["suggest_cpu"] for r in rows for s in r["suggested"]])
    lines += ["", f"Maps that failed with 3 (error > 0.05): {len(failed)}; repaired below 0.03 within 2 suggestions: "
              f"{len(repaired)}.  CPU per match (bar included) {cpu_m:.2f} s, per suggestion {cpu_s:.2f} s "
              f"({100 * cpu_s / cpu_m:.0f} %).", "", "Per pair (errors, 10⁻³ sqrt(area), 3 → 3 + steps):", ""]
    for r in rows:
        lines.append(f"- {r['pair']}: suggested " + " → ".join(f"{s['error'] * 1e3:.0f}" for s in r["suggested"])
                     + "; method " + " → ".join(f"{s['error'] * 1e3:.0f}" for s in r["method"]))
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("dataset", type=Path)
    p.add_argument("--pairs", type=Path, default=None)
    p.add_argument("--max-targets", type=int, default=4)
    p.add_argument("--method", default="fps")
    p.add_argument("--matcher", default="faq")
    p.add_argument("--steps", type=int, default=3)
    p.add_argument("--points", type=int, default=400)
    a = p.parse_args()
    rows = []
    for group, target in _pairs(a):
        rows.append(run_pair(group, target, a))
        print(rows[-1]["pair"], [round(s["error"] * 1e3) for s in rows[-1]["suggested"]],
              [round(s["error"] * 1e3) for s in rows[-1]["method"]], flush=True)
    text = summarise(rows, a)
    print(text)
    write_section(f"suggest-loop-{a.dataset.name}-{a.method}-{a.matcher}", text)


if __name__ == "__main__":
    main()

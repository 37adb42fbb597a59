"""What `match --suggest K` costs beside the match (issue 32): the δ searches continued, against fresh ones.

Usage:
    python benchmarks/bench_suggest_cost.py DATASET LANDMARKS.json [--pairs FILE | --max-targets T]
           [--method fps] [--k 3] [--section NAME]

For every pair (a release's pairs list, or each class's null shape to its first targets), the first
3 landmarks of ``--method`` from an ``evaluate`` run's ``results.json`` (``LANDMARKS.json``) with their
images through the ground truth, one ``sc.match`` (FAQ, error bar on, caches warm), then
``MatchResult.suggest(k)`` twice in the same process: with the δ search after each suggested point
run fresh at effort ``quick`` (the former search, the baseline) and continued from the previous
search's maps (``warm``, what ships: ``matching.suggest.SEARCH``).  Reported: CPU of the match and of
each ``suggest(k)`` (one BLAS and numba thread), whether the two give the same points in order, and
the ratio of their ``bar_after``.  ``benchmarks/RESULTS.md`` section ``suggest-cost-DATASET``.
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
from _releases import groups, landmark_sets  # noqa: E402

SEARCHES = ("quick", "warm")


def run_pair(group, target, ids, k) -> dict:
    import shapecond as sc
    import shapecond.matching.suggest as suggest
    from shapecond.evaluation.protocols import _reference_ids, landmark_images
    from shapecond.matching.sampled import CachedSolver

    src, tgt = sc.load(group.null), sc.load(target)
    ref_s, ref_t = _reference_ids(group, group.null, src), _reference_ids(group, target, tgt)
    images = landmark_images(src.to_internal(ids), ref_s, ref_t, CachedSolver(src, "heat"))
    lt = [int(tgt.ids[v]) for v in images]
    sc.match(group.null, target, ids, lt, matcher="faq")  # the caches warm: the match's CPU, not the geodesics'
    t0 = time.process_time()
    m = sc.match(group.null, target, ids, lt, matcher="faq")
    row = {"pair": f"{group.null.stem}->{target.stem}", "match": time.process_time() - t0}
    for search in SEARCHES:
        suggest.SEARCH = search
        t0 = time.process_time()
        row[search] = m.suggest(k)
        row[search + " cpu"] = time.process_time() - t0
    suggest.SEARCH = "warm"
    return row


def summarise(rows, a) -> str:
    match = np.array([r["match"] for r in rows])
    cpu = {s: np.array([r[s + " cpu"] for r in rows]) for s in SEARCHES}
    same = sum(int([d["source_id"] for d in r["quick"]] == [d["source_id"] for d in r["warm"]]) for r in rows)
    first = sum(int(r["quick"][0]["source_id"] == r["warm"][0]["source_id"]) for r in rows)
    ratio = np.array([w["bar_after"] / q["bar_after"] for r in rows for q, w in zip(r["quick"], r["warm"])])
    lines = [f"Machine: {machine()}; load {os.getloadavg()[0]:.1f}.", "", f"Command: `{command_line()}`", "",
             f"{len(rows)} pairs, the first 3 landmarks of {a.method} and their true images, FAQ, "
             f"`suggest({a.k})`; CPU s (one thread), sums over the pairs.", "",
             "| | match (bar included) | suggest, fresh δ searches (quick) | suggest, continued (warm, shipped) |",
             "|---|---|---|---|",
             f"| CPU s | {match.sum():.1f} | {cpu['quick'].sum():.1f} ({100 * cpu['quick'].sum() / match.sum():.0f} % "
             f"of the match) | {cpu['warm'].sum():.1f} ({100 * cpu['warm'].sum() / match.sum():.0f} %) |", "",
             f"Same {a.k} points in order: {same} of {len(rows)} pairs (the first point: {first} of {len(rows)}). "
             f"bar_after continued / fresh: median {np.median(ratio):.3f}, range {ratio.min():.3f}–{ratio.max():.3f} "
             f"over {ratio.size} suggestions (δ is a lower bound: higher is the better search).", "", "Per pair:", ""]
    for r in rows:
        lines.append(f"- {r['pair']}: match {r['match']:.2f} s; quick {r['quick cpu']:.2f} s "
                     f"{[d['source_id'] for d in r['quick']]}; warm {r['warm cpu']:.2f} s "
                     f"{[d['source_id'] for d in r['warm']]}")
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("dataset", type=Path)
    p.add_argument("landmarks", type=Path)
    p.add_argument("--pairs", default=None)
    p.add_argument("--max-targets", type=int, default=8)
    p.add_argument("--method", default="fps")
    p.add_argument("--k", type=int, default=3)
    p.add_argument("--section", default=None, help="default: suggest-cost-DATASET")
    a = p.parse_args()
    lms = landmark_sets(a.landmarks)
    rows = []
    for name, g in groups(a.dataset, a.pairs).items():
        if (name, a.method) not in lms:
            continue
        for t in g.targets[:a.max_targets]:
            rows.append(run_pair(g, t, [int(v) for v in lms[(name, a.method)][:3]], a.k))
            print(rows[-1]["pair"], round(rows[-1]["quick cpu"], 2), round(rows[-1]["warm cpu"], 2), flush=True)
    text = summarise(rows, a)
    print(text)
    title = "## What `--suggest K` costs: δ searches continued, not fresh (bench_suggest_cost.py)"
    write_section(a.section or f"suggest-cost-{a.dataset.name}", title + "\n\n" + text)


if __name__ == "__main__":
    main()

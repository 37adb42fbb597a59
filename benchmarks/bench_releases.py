"""Matching off isometry on the releases as they ship (issue 31): two `shapecond evaluate` runs side by side.

Usage:
    shapecond evaluate RELEASE [--pairs FILE] --methods fps --counts 3,6 --landmark-count 6 --out DIR_A   # code A
    shapecond evaluate RELEASE [--pairs FILE] --methods fps --counts 3,6 --landmark-count 6 --out DIR_B   # code B
    python benchmarks/bench_releases.py --name NAME --run "label A=DIR_A" --run "label B=DIR_B" [--note TEXT]

Reads each run's ``results.json`` (``shapecond.evaluation.report``) and writes
``benchmarks/RESULTS.md``, section ``releases-NAME``: per landmark method, count
and matcher, the mean, median and worst error over the matchings (10⁻³
sqrt(area)), the failed ones (> 0.05), the flips (where the release gives
mirror images) and the share held by the error bar, one column group per run;
then the issue's checks: no pair above 0.05 with 6 landmarks, 6 landmarks at
most 1.05× 3 on every pair, the bar holding ≥ 90 % and every failed map.
Each run's settings (dataset, pairs, N, seed) are printed from its file, so
the rows compare the same matchings.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections import defaultdict
from types import SimpleNamespace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402


def _records(path: Path) -> tuple[dict, list]:
    d = json.loads((path / "results.json").read_text())
    return d["settings"], [r for r in d["records"] if r["protocol"] in ("remeshed", "corresponding")]


def _number(v) -> float:
    return math.inf if v == "inf" else math.nan if v is None else float(v)


def _err(r) -> float:
    return _number(r["error_area"])


def pooled(records) -> dict:
    """``evaluation.report.pooled`` of a results.json's records, errors in 10⁻³ sqrt(area)."""
    from shapecond.evaluation.report import pooled as report_pooled

    rows = [SimpleNamespace(**{k: _number(r[k]) if k in ("error_area", "bar", "flipped") else r[k] for k in
                               ("method", "n_landmarks", "matcher", "error_area", "bar", "flipped")})
            for r in records]
    return {k: dict(d, mean=1e3 * d["mean"], median=1e3 * d["median"], worst=1e3 * d["worst"])
            for k, d in sorted(report_pooled(rows).items())}


def checks(records) -> list[str]:
    by_pair = defaultdict(dict)
    for r in records:
        by_pair[(r["cls"], r["target"], r["method"], r["matcher"])][r["n_landmarks"]] = _err(r)
    worse = [(k, v) for k, v in by_pair.items() if len(v) >= 2 and v[max(v)] > 1.05 * v[min(v)]]
    top = max((r["n_landmarks"] for r in records), default=0)
    above = [r for r in records if r["n_landmarks"] == top and _err(r) > 0.05]
    out = [f"pairs above 0.05 with {top} landmarks: {len(above)} of "
           f"{sum(1 for r in records if r['n_landmarks'] == top)}",
           f"(pair, method, matcher) where {top} landmarks err more than 1.05x {min((r['n_landmarks'] for r in records), default=0)}: "
           f"{len(worse)} of {len(by_pair)}"]
    out += [f"  {k[0]}->{k[1]} {k[2]} {k[3]}: " + ", ".join(f"{c}: {1e3 * e:.0f}" for c, e in sorted(v.items()))
            for k, v in worse[:12]]
    return out


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--name", required=True)
    p.add_argument("--run", action="append", required=True, help="LABEL=DIR of an evaluate run")
    p.add_argument("--note", default="")
    a = p.parse_args()
    runs = [(s.split("=", 1)[0], Path(s.split("=", 1)[1])) for s in a.run]
    data = [(label, *_records(d)) for label, d in runs]
    lines = [f"Machine: {machine()}.", "", f"Command: `{command_line()}`", ""]
    if a.note:
        lines += [a.note, ""]
    for label, st, recs in data:
        lines.append(f"- {label}: `{st['dataset']}`, {len(recs)} matchings, N = {st['n_points']}, seed {st['seed']}, "
                     f"methods {st['methods']}, matchers {st['matchers']}, "
                     f"{len(st['pairs']) if st.get('pairs') else 'null shape to each target'} pairs, "
                     f"error bars {'on' if st.get('error_bars') else 'off'}")
    tables = [pooled(recs) for _, _, recs in data]
    keys = sorted(set().union(*tables))
    lines += ["", "Errors in 10⁻³ sqrt(area) over every matching: mean / median / worst, failed (> 50), flipped, "
              "held by the bar (and failed maps held).", "",
              "| method | L | matcher | " + " | ".join(label for label, *_ in data) + " |",
              "|---|---|---|" + "---|" * len(data)]
    for k in keys:
        cells = []
        for t in tables:
            d = t.get(k)
            cells.append("-" if d is None else
                         f"{d['mean']:.1f} / {d['median']:.1f} / {d['worst']:.0f}, failed {d['failed']}/{d['n']}"
                         + ("" if d["flipped"] is None else f", flipped {d['flipped']}")
                         + ("" if not np.isfinite(d["held"]) else
                            f", held {d['held']:.2f} ({d['failed_held'][0]}/{d['failed_held'][1]})"))
        lines.append(f"| {k[0]} | {k[1]} | {k[2]} | " + " | ".join(cells) + " |")
    for label, _, recs in data:
        lines += ["", f"Checks, {label}:", ""] + [f"- {c}" if not c.startswith("  ") else f"  - {c.strip()}"
                                                   for c in checks(recs)]
    text = "\n".join(lines)
    print(text)
    write_section(f"releases-{a.name}", f"## Off isometry and the releases as they ship: {a.name} (bench_releases.py)\n\n"
                  + text)


if __name__ == "__main__":
    main()

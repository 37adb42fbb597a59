"""Where the dense stage loses a good start (issue 31): ZoomOut's coarse-to-fine schedule against fewer levels.

Usage:
    python benchmarks/bench_zoomout_schedule.py run DATASET LANDMARKS.json --out RUN.jsonl [--methods pls,fps]
           [--pairs PAIRS.txt] [--max-targets T]
    python benchmarks/bench_zoomout_schedule.py report --run "LABEL=RUN.jsonl" ... [--note TEXT]

``run``: for each (pair, landmark method), the landmarks of ``LANDMARKS.json`` (the
``landmarks`` list an ``evaluate`` run writes: class, method, vertex ids on the null
shape) with their images through the ground truth, the dense stage
(``matching.pipeline.dense_stage``, the shipped anchors and options) from two
starts — FAQ's sample map extended to every vertex (what ``match`` refines) and
the *true* map (every source vertex sent where the ground truth sends its nearest
reference point) — with four schedules: the shipped one (``k`` from 20 to the
whole basis by 10), from 60, one level at the whole basis, and that level three
times.  Errors at the reference points in 10⁻³ sqrt(area).

``report``: mean errors per schedule and start, and how often a schedule beats the
shipped one, in ``benchmarks/RESULTS.md`` section ``zoomout-schedule``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402
from _releases import groups, landmark_sets, run_or_report, truth_start  # noqa: E402

#: name -> the k_start of each dense stage run in turn.
SCHEDULES = {"shipped": [20], "from 60": [60], "whole basis once": [None], "whole basis 3x": [None] * 3}


def _refine(null, g, start, anchors, schedule):
    from shapecond.matching.pipeline import MatchOptions, dense_stage
    from shapecond.matching.zoomout import ZoomOutOptions

    T = start
    for k0 in schedule:
        T = dense_stage(null, g, T, anchors, MatchOptions(zoomout=ZoomOutOptions(k_start=k0 or 10 ** 6)))
    return T


def _pair(null, g, ref_s, ref_t, src, ids, truth):
    from shapecond.evaluation import protocols as P
    from shapecond.matching.pipeline import MatchOptions, anchors_of
    from shapecond.matching.problem import match_surfaces
    from shapecond.matching.sampled import CachedSolver, sample_surface, surface_unit

    tgt = sample_surface(g, 400, "heat", 0, cache=True)
    solvers = (CachedSolver(null, "heat", src), CachedSolver(g, "heat", tgt))
    ls = null.to_internal(ids)
    lt = P.landmark_images(ls, ref_s, ref_t, solvers[0])
    m = match_surfaces(src, tgt, ls, lt, MatchOptions(matcher="faq", dense="distances"), solvers)
    anchors = anchors_of(m.source, m.target, ls.size)
    maps = {f"{start}: {name}": _refine(null, g, T0, anchors, ks)[ref_s]
            for start, T0 in (("faq", m.vertex_map), ("truth", truth)) for name, ks in SCHEDULES.items()}
    raw, diameter, _ = P.reference_errors(g, ref_t, maps, "heat")
    unit = surface_unit(g, diameter)
    return {k: round(1e3 * float(e.mean()) / unit, 2) for k, e in raw.items()}


def run(a) -> None:
    from shapecond.api import load
    from shapecond.evaluation import protocols as P
    from shapecond.matching.sampled import sample_surface

    lms = landmark_sets(a.landmarks)
    with open(a.out, "w") as out:
        for name, cls in groups(a.dataset, a.pairs).items():
            null = load(cls.null)
            ref_s = P._reference_ids(cls, cls.null, null)
            src = sample_surface(null, 400, "heat", 0, cache=True)
            for t in cls.targets[:a.max_targets]:
                g = load(t)
                ref_t = P._reference_ids(cls, t, g)
                truth = truth_start(null, ref_s, ref_t)
                for method in a.methods.split(","):
                    if (name, method) in lms:
                        errors = _pair(null, g, ref_s, ref_t, src, lms[(name, method)], truth)
                        out.write(json.dumps({"pair": f"{cls.null.stem}/{t.stem}", "method": method, **errors}) + "\n")
                        out.flush()


def report(a) -> None:
    lines = ["## Where the dense stage loses a good start: ZoomOut's schedule (bench_zoomout_schedule.py)", "",
             f"Machine: {machine()}", "", f"Command: `{command_line()}`", "", a.note or "", "",
             "Errors in 10⁻³ sqrt(area), mean over the (pair, landmark method) rows; in brackets, the rows where "
             "the schedule is more than 5 % better / worse than the shipped one from the same start.", "",
             "| run | n | start | " + " | ".join(SCHEDULES) + " |", "|---|---|---|" + "---|" * len(SCHEDULES)]
    for r in a.run:
        label, path = r.split("=", 1)
        rows = [json.loads(x) for x in Path(path).read_text().splitlines() if x.strip()]
        for start in ("faq", "truth"):
            base = np.array([d[f"{start}: shipped"] for d in rows])
            cells = []
            for name in SCHEDULES:
                e = np.array([d[f"{start}: {name}"] for d in rows])
                cells.append(f"{e.mean():.1f}" + ("" if name == "shipped" else
                                                  f" ({int((e < base / 1.05).sum())} / {int((e > 1.05 * base).sum())})"))
            lines.append(f"| {label} | {len(rows)} | {start} | " + " | ".join(cells) + " |")
    write_section("zoomout-schedule", "\n".join(lines))


def main() -> None:
    def arguments(r):
        r.add_argument("landmarks", type=Path)
        r.add_argument("--methods", default="pls,fps")
        r.add_argument("--pairs", default=None)
        r.add_argument("--max-targets", type=int, default=4)
    run_or_report(__doc__, run, report, arguments)


if __name__ == "__main__":
    main()

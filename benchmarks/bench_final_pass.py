"""The dense stage's final pass searched near the subsample's map against every target vertex (issue 35).

Usage:
    python benchmarks/bench_final_pass.py DATASET [DATASET ...] [--pairs FILE] [--max-targets 8]
           [--landmarks 6] [--note TEXT]

For every pair (a release's ``--pairs`` list, else the null shape of each class to its
first targets) FAQ matches the samples with ``--landmarks`` farthest-point landmarks of
the null shape and their images through the ground truth, and the dense stage refines the
extended map twice from that one start: with the final pass searched in each cell's region
(``matching.zoomout``, what ships) and among every target vertex (the former search).
Reported per dataset: vertices whose image differs, the mean error of both at the reference
points (10⁻³ sqrt(area)) and the worst change, and the CPU seconds of the two final passes.
Written to section ``final-pass`` of ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402
from _releases import groups  # noqa: E402


def _timed_nearest(full: bool, seconds: list):
    """The final pass's search (restricted, or every target vertex when ``full``), timed."""
    from shapecond.matching import zoomout as Z

    restricted = Z._nearest_in_regions

    def search(X, Y, cell, regions):
        t = time.process_time()
        out = Z.nearest_rows(X, Y) if full else restricted(X, Y, cell, regions)
        seconds.append(time.process_time() - t)
        return out
    return search


def _pair(g, src, ref_s, target_path, n_landmarks: int) -> dict:
    from shapecond.api import load
    from shapecond.evaluation import protocols as P
    from shapecond.matching import zoomout as Z
    from shapecond.matching.pipeline import MatchOptions, anchors_of, dense_stage
    from shapecond.matching.problem import match_shapes
    from shapecond.matching.sampled import CachedSolver, sample_surface, surface_unit

    tgt = load(target_path)
    ref_t = P._reference_ids(g, target_path, tgt)
    ls = sample_surface(src, 400, "heat", 0, cache=True).samples[:n_landmarks]
    lt = P.landmark_images(ls, ref_s, ref_t, CachedSolver(src, "heat"))
    m = match_shapes(src, tgt, ls, lt, MatchOptions(matcher="faq", dense="distances"))
    maps, cpu = {}, {}
    shipped = Z._nearest_in_regions
    for label, full in (("regions", False), ("every vertex", True)):
        seconds: list = []
        Z._nearest_in_regions = _timed_nearest(full, seconds)
        try:
            maps[label] = dense_stage(src, tgt, m.vertex_map, anchors_of(m.source, m.target, n_landmarks),
                                      MatchOptions(matcher="faq"))
        finally:
            Z._nearest_in_regions = shipped
        cpu[label] = sum(seconds)
    raw, diameter, _ = P.reference_errors(tgt, ref_t, {k: v[ref_s] for k, v in maps.items()}, "heat")
    unit = surface_unit(tgt, diameter)
    return {"differ": float(np.mean(maps["regions"] != maps["every vertex"])),
            "error": {k: 1e3 * float(e.mean()) / unit for k, e in raw.items()}, "cpu": cpu,
            "vertices": int(src.n_vertices)}


def main() -> None:
    from shapecond.api import load
    from shapecond.evaluation import protocols as P

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("datasets", nargs="+", type=Path)
    p.add_argument("--pairs")
    p.add_argument("--max-targets", type=int, default=8)
    p.add_argument("--landmarks", type=int, default=6)
    p.add_argument("--note", default="")
    a = p.parse_args()
    lines = ["## The final pass of the dense stage: cell regions against every target vertex (bench_final_pass.py)",
             "", f"Machine: {machine()}", "", f"Command: `{command_line()}`", "", a.note, "",
             "| dataset | pairs | vertices | images that differ | error, regions | error, every vertex | "
             "worst change | final pass CPU s, regions / every vertex |", "|---|" + "---|" * 7]
    for root in a.datasets:
        classes = groups(root, a.pairs if root == a.datasets[0] else None)
        rows = []
        for g in classes.values():
            src = load(g.null)
            ref_s = P._reference_ids(g, g.null, src)
            for t in g.targets[:a.max_targets]:
                rows.append(_pair(g, src, ref_s, t, a.landmarks))
                print(t.stem, rows[-1], file=sys.stderr, flush=True)
        er = np.array([[r["error"]["regions"], r["error"]["every vertex"]] for r in rows])
        cpu = np.array([[r["cpu"]["regions"], r["cpu"]["every vertex"]] for r in rows])
        lines.append(f"| {root.name} | {len(rows)} | {int(np.mean([r['vertices'] for r in rows]))} | "
                     f"{100 * np.mean([r['differ'] for r in rows]):.2f} % | {er[:, 0].mean():.2f} | {er[:, 1].mean():.2f} | "
                     f"{np.abs(er[:, 0] - er[:, 1]).max():.2f} | {cpu[:, 0].sum():.1f} / {cpu[:, 1].sum():.1f} |")
    write_section("final-pass", "\n".join(lines))


if __name__ == "__main__":
    main()

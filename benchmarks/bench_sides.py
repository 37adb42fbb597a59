"""Which sides the dense stage reads (issue 31): the distances' (shipped) against the harmonic coordinates'.

Usage:
    python benchmarks/bench_sides.py run DATASET LANDMARKS.json --out RUN.jsonl [--pairs FILE]
           [--methods fps,pls,hks,cnbs,cnbs-scale] [--max-targets 8]
    python benchmarks/bench_sides.py report --run "LABEL=RUN.jsonl" ... [--note TEXT]

``run``: for every (pair, landmark method) the null shape of the class is matched to
the target by FAQ with the first 3 and then the first 6 landmarks of the method
(``LANDMARKS.json``: an ``evaluate`` results file, whose ``landmarks`` it reads) and
their images through the ground truth, the sample map extended to the vertices; the
dense stage (``matching.pipeline.dense_stage``) then refines that one start twice: with
the sides of the landmark pairs read off the geodesic distances (``orientation``, what
ships) and with the sides read off the harmonic coordinates' gradients, an experiment
(the angle between two harmonic functions' gradients is a conformal invariant and has no
cut locus).  One JSON line per (pair, method): errors at the reference points in
10⁻³ sqrt(area) for L = 3 and 6, each variant.

``report``: section ``sides-NAME`` of ``benchmarks/RESULTS.md``: means, the
(pair, method) where 6 landmarks err more than 1.05× 3 (issue 31's "a correct landmark
never costs accuracy"), where the variant is 5 % worse or better than what ships.
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402
from _releases import groups, landmark_sets, run_or_report  # noqa: E402

VARIANTS = ("distances", "harmonic")


def _harmonic_sides(anchors, source_geometry, target_geometry, radius):
    """The experiment: the anchors' harmonic coordinates, and the sides read off them."""
    from shapecond.matching.harmonic import harmonic_coordinates
    from shapecond.matching.orientation import orientation_features

    hs = harmonic_coordinates(source_geometry, anchors.source_rows, radius)
    ht = harmonic_coordinates(target_geometry, anchors.target_rows, radius)
    if hs is None or ht is None:
        return anchors
    return replace(anchors, source_sides=orientation_features(source_geometry, hs.T),
                   target_sides=orientation_features(target_geometry, ht.T),
                   source_harmonic=hs.astype(np.float32), target_harmonic=ht.astype(np.float32))


def _refine(src, tgt, start, anchors, variant):
    from shapecond.matching import zoomout as Z
    from shapecond.matching.pipeline import MatchOptions, dense_stage

    shipped = Z.Anchors.oriented, Z.Anchors.harmonic
    if variant == "harmonic":
        Z.Anchors.oriented, Z.Anchors.harmonic = (lambda self, a, b: self), _harmonic_sides
    try:
        return dense_stage(src, tgt, start, anchors, MatchOptions(matcher="faq"))
    finally:
        Z.Anchors.oriented, Z.Anchors.harmonic = shipped


def run(a) -> None:
    from shapecond.api import load
    from shapecond.evaluation.protocols import _reference_ids, landmark_images, reference_errors
    from shapecond.matching.pipeline import MatchOptions, anchors_of
    from shapecond.matching.problem import match_shapes
    from shapecond.matching.sampled import CachedSolver, surface_unit

    lms = landmark_sets(a.landmarks)
    with open(a.out, "w") as out:
        for name, g in groups(a.dataset, a.pairs).items():
            src = load(g.null)
            ref_s = _reference_ids(g, g.null, src)
            for tp in g.targets[:a.max_targets]:
                tgt = load(tp)
                ref_t = _reference_ids(g, tp, tgt)
                for method in a.methods.split(","):
                    row = {"pair": f"{g.null.stem}->{tp.stem}", "method": method}
                    for L in (3, 6):
                        ls = np.asarray(lms[(name, method)][:L])
                        lt = landmark_images(ls, ref_s, ref_t, CachedSolver(src, "heat"))
                        m = match_shapes(src, tgt, ls, lt, MatchOptions(matcher="faq", dense="distances"))
                        for v in VARIANTS:
                            vm = _refine(src, tgt, m.vertex_map, anchors_of(m.source, m.target, L), v)
                            vm[ls] = lt
                            raw, diam, _ = reference_errors(tgt, ref_t, {"m": vm[ref_s]}, "heat")
                            row[f"{v} {L}"] = 1e3 * float(raw["m"].mean()) / surface_unit(tgt, diam)
                    print(json.dumps(row), file=out, flush=True)
                    print(row, file=sys.stderr, flush=True)


def report(a) -> None:
    lines = ["## The sides the dense stage reads: the distances' against the harmonic coordinates' (bench_sides.py)",
             "", f"Machine: {machine()}", "", f"Command: `{command_line()}`", "", a.note or "", "",
             "FAQ start, the dense stage refined twice from it; errors in 10⁻³ sqrt(area), mean over the (pair, method).",
             "", "| run | n | distances L=3 | distances L=6 | harmonic L=3 | harmonic L=6 | 6 > 1.05× 3 (distances / harmonic) "
             "| harmonic at 6 worse / better by 5 % | above 50 at 6 (distances / harmonic) |", "|---|" + "---|" * 8]
    for spec in a.run:
        label, path = spec.split("=", 1)
        rows = [json.loads(x) for x in Path(path).read_text().splitlines() if x.strip()]
        c = {k: np.array([r[k] for r in rows]) for k in ("distances 3", "distances 6", "harmonic 3", "harmonic 6")}
        lines.append(
            f"| {label} | {len(rows)} | {c['distances 3'].mean():.1f} | {c['distances 6'].mean():.1f} | "
            f"{c['harmonic 3'].mean():.1f} | {c['harmonic 6'].mean():.1f} | "
            f"{int((c['distances 6'] > 1.05 * c['distances 3']).sum())} / {int((c['harmonic 6'] > 1.05 * c['harmonic 3']).sum())} | "
            f"{int((c['harmonic 6'] > 1.05 * c['distances 6']).sum())} / {int((c['harmonic 6'] < c['distances 6'] / 1.05).sum())} | "
            f"{int((c['distances 6'] > 50).sum())} / {int((c['harmonic 6'] > 50).sum())} |")
    write_section("sides", "\n".join(lines))


def main() -> None:
    def arguments(r):
        r.add_argument("landmarks", type=Path)
        r.add_argument("--pairs")
        r.add_argument("--methods", default="fps,pls,hks,cnbs,cnbs-scale")
        r.add_argument("--max-targets", type=int, default=8)
    run_or_report(__doc__, run, report, arguments)


if __name__ == "__main__":
    main()

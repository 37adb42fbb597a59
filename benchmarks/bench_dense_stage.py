"""Off isometry, where the dense stage ends (issue 31): every matcher, and the dense stage started from the truth.

Usage:
    python benchmarks/bench_dense_stage.py run DATASET --out A.json [--class NAME] [--max-targets T]
           [--landmarks 6] [--matchers faq,lh05,zoomout]
    python benchmarks/bench_dense_stage.py report --run "label A=A.json" --run "label B=B.json" [--note TEXT]

``run``: the class's null shape (``evaluation.datasets``; a release in any of its
layouts) matched to each of its first targets with ``--landmarks`` farthest-point
samples of the null shape as landmarks and their images through the ground truth
(``evaluation.protocols.landmark_images``), every matcher
(``matching.problem.match_surfaces`` / ``pipeline.match_landmarks_only``, as ``evaluate``
calls them), and the dense stage alone started from the *true* map (every source
vertex sent where the ground truth sends its nearest reference point): what the
refinement keeps of a perfect start is the floor every matcher meets.  Errors at
the reference points in 10⁻³ sqrt(area) (``evaluation.protocols.reference_errors``),
one JSON per code version (run it from two checkouts: ``PYTHONPATH=OTHER/src``).

``report``: the runs side by side in ``benchmarks/RESULTS.md``, section
``dense-stage-NAME`` (NAME from the first run's dataset): mean / worst / pairs above
50 per matcher, and the pairs where a run is more than 5 % worse than the first.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402
from _releases import run_or_report, truth_start  # noqa: E402


def _pair(cls, null, src, ref_s, target_path, a) -> dict:
    from shapecond.api import load
    from shapecond.evaluation import protocols as P
    from shapecond.matching.pipeline import MatchOptions, anchors_of, dense_stage, match_landmarks_only
    from shapecond.matching.problem import match_surfaces
    from shapecond.matching.sampled import CachedSolver, insert_landmarks, sample_surface, surface_unit

    g = load(target_path)
    ref_t = P._reference_ids(cls, target_path, g)
    tgt = sample_surface(g, 400, "heat", 0, cache=True)
    solvers = (CachedSolver(null, "heat", src), CachedSolver(g, "heat", tgt))
    ls = src.samples[:a.landmarks]
    lt = P.landmark_images(ls, ref_s, ref_t, solvers[0])
    maps = {}
    for m in a.matchers.split(","):
        o = MatchOptions(matcher=m)
        found = (match_landmarks_only(null, g, ls, lt, o, solvers) if m == "zoomout"
                 else match_surfaces(src, tgt, ls, lt, o, solvers))
        maps[m] = found.vertex_map[ref_s]
    s2, _ = insert_landmarks(src, ls, solvers[0])
    t2, _ = insert_landmarks(tgt, lt, solvers[1])
    truth = dense_stage(null, g, truth_start(null, ref_s, ref_t), anchors_of(s2, t2, a.landmarks), MatchOptions())
    maps["from the truth"] = truth[ref_s]
    raw, diameter, _ = P.reference_errors(g, ref_t, maps, "heat")
    unit = surface_unit(g, diameter)
    return {k: 1e3 * float(e.mean()) / unit for k, e in raw.items()}


def run(a) -> None:
    from shapecond.api import load
    from shapecond.evaluation import protocols as P
    from shapecond.evaluation.datasets import find_classes
    from shapecond.matching.sampled import sample_surface

    classes = find_classes(a.dataset)
    cls = classes[a.cls] if a.cls else next(iter(classes.values()))
    null = load(cls.null)
    ref_s = P._reference_ids(cls, cls.null, null)
    src = sample_surface(null, 400, "heat", 0, cache=True)
    out = {"dataset": str(a.dataset), "class": cls.name, "null": cls.null.stem, "landmarks": a.landmarks,
           "pairs": {}}
    for t in cls.targets[:a.max_targets]:
        out["pairs"][t.stem] = _pair(cls, null, src, ref_s, t, a)
        print(t.stem, {k: round(v, 1) for k, v in out["pairs"][t.stem].items()}, file=sys.stderr, flush=True)
    Path(a.out).write_text(json.dumps(out, indent=1))


def report(a) -> None:
    runs = [(r.split("=", 1)[0], json.loads(Path(r.split("=", 1)[1]).read_text())) for r in a.run]
    first = runs[0][1]
    pairs = [p for p in first["pairs"] if all(p in d["pairs"] for _, d in runs)]
    keys = list(dict.fromkeys(k for _, d in runs for k in d["pairs"][pairs[0]]))
    lines = ["## Off isometry, where the dense stage ends (bench_dense_stage.py)", "", f"Machine: {machine()}", "", f"Command: `{command_line()}`", "", a.note or "", "",
             f"{first['class']}: {first['null']} matched to {len(pairs)} targets, {first['landmarks']} farthest-point "
             "landmarks with their true images; errors in 10⁻³ sqrt(area): mean / worst, matchings above 50.", "",
             "| matcher | " + " | ".join(label for label, _ in runs) + " |", "|---|" + "---|" * len(runs)]
    for k in keys:
        cells = []
        for _, d in runs:
            if k not in d["pairs"][pairs[0]]:
                cells.append("—")
                continue
            e = np.array([d["pairs"][p][k] for p in pairs])
            cells.append(f"{e.mean():.1f} / {e.max():.0f}, above 50: {int((e > 50).sum())}")
        lines.append(f"| {k} | " + " | ".join(cells) + " |")
    base_label, base = runs[0]
    for label, d in runs[1:]:
        common = [k for k in keys if k in base["pairs"][pairs[0]] and k in d["pairs"][pairs[0]]]
        worse = [f"{p} {k}: {base['pairs'][p][k]:.1f} → {d['pairs'][p][k]:.1f}" for p in pairs for k in common
                 if d["pairs"][p][k] > 1.05 * base["pairs"][p][k]]
        lines += ["", f"{label}: {len(worse)} of {len(pairs) * len(common)} (pair, matcher) more than 5 % worse than "
                  f"{base_label}" + (": " + "; ".join(worse) if worse else "")]
    write_section(f"dense-stage-{Path(first['dataset']).name}", "\n".join(lines))


def main() -> None:
    def arguments(r):
        r.add_argument("--class", dest="cls")
        r.add_argument("--max-targets", type=int, default=8)
        r.add_argument("--landmarks", type=int, default=6)
        r.add_argument("--matchers", default="faq,lh05,zoomout")
    run_or_report(__doc__, run, report, arguments)


if __name__ == "__main__":
    main()

"""Time of CNBS on σ and on δ(ε) on one TOSCA shape, in one run: a full heat map and K landmarks.

Usage: ``python benchmarks/bench_cnbs_time.py DATA_DIR [--shape cat0] [-k 15]``

The setting of the paper's Figure 7: N = 400 samples, bijections, symmetry-consistent
sampling from the class's ``.sym`` map when there is one (as in bench_landmarks.py).
Each figure is the wall time and the CPU time of this process (``time.process_time``),
with the 1-minute load average before it: the machine is shared.  The heat maps are
unpruned (what ``shapecond heatmap`` draws); the landmarks use the pruned heat maps of
``cnbs_landmarks``; the scores are those ``shapecond landmarks`` reports (for δ, the heat
values of the chosen candidates made non-increasing).  Writes the section ``cnbs-time`` of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, peak_rss_mb, write_section  # noqa: E402

from shapecond.landmarks import monotone  # noqa: E402
from shapecond.landmarks.cnbs import cnbs_landmarks, heat_map  # noqa: E402
from shapecond.shapes.io import load_geometry, read_symmetry_map  # noqa: E402
from shapecond.shapes.metric import metric_shape  # noqa: E402
from shapecond.symmetry.scale import budget_of, default_epsilon  # noqa: E402
from shapecond.symmetry.search import witness_search  # noqa: E402


def timed(f):
    load = os.getloadavg()[0]
    w, c = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - w, time.process_time() - c, load


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data")
    ap.add_argument("--shape", default="cat0")
    ap.add_argument("-k", type=int, default=15)
    a = ap.parse_args()
    cls = a.shape.rstrip("0123456789")
    root = Path(a.data)
    root = root / "tosca_hires" if (root / "tosca_hires").is_dir() else root
    g = load_geometry(root / cls / f"{a.shape}.off")
    sym = root / "symmetries" / f"{cls}.sym"
    if sym.exists():
        g = g.with_symmetry(read_symmetry_map(sym))
    shape, w, c, load = timed(lambda: metric_shape(g, n_points=400, target="samples"))
    D, n = shape.D, shape.n_samples
    rows = [("geodesics and sampling", "-", w, c, load, "")]
    eps = default_epsilon(D, n)
    targets = {"sigma": ("10 s", "30 s"), "scale": ("30 s", "60 s")}
    for score, budget in (("sigma", None), ("scale", budget_of(eps, n, D))):
        base, w, c, load = timed(lambda: witness_search(D, n, budget=budget))
        rows.append((f"witness search, no landmarks ({score})", "-", w, c, load, ""))
        _, w, c, load = timed(lambda: heat_map(D, n, base=base, budget=budget))
        rows.append((f"full heat map ({score})", targets[score][0], w, c, load, ""))
        out, w, c, load = timed(lambda: cnbs_landmarks(D, n, a.k, base=base, budget=budget))
        # as `shapecond landmarks` reports them: δ made non-increasing (``landmarks.monotone``)
        sc = out["scores"] if budget is None else monotone([v / math.sqrt(n) for v in out["scores"]])
        rows.append((f"{a.k} landmarks ({'cnbs' if budget is None else 'cnbs-scale'})", targets[score][1], w, c,
                     load, ", ".join(f"{v:.3g}" for v in sc)))
    lines = ["## CNBS time: σ and δ(ε) on one shape (bench_cnbs_time.py)", "",
             f"Machine: {machine()}. Command: `{command_line()}`. {a.shape}: {len(g.vertices)} vertices, N = {n} "
             f"samples (symmetry-consistent), bijections; δ at the default ε = {eps:.4f} (the median sample "
             f"spacing). Peak memory {peak_rss_mb():.0f} MB. Targets: issue 16 for σ (heat map ≤ 10 s, 15 "
             "landmarks ≤ 30 s), issue 12 for δ (≤ 30 s, ≤ 60 s), wall time on 2 cores.", "",
             "| step | target | wall s | CPU s | load before | scores after each landmark |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {r[0]} | {r[1]} | {r[2]:.1f} | {r[3]:.1f} | {r[4]:.2f} | {r[5]} |" for r in rows]
    text = "\n".join(lines)
    print(text)
    write_section("cnbs-time", text)


if __name__ == "__main__":
    main()

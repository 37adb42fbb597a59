"""Time and peak memory to build the 400-sample geodesic matrix, per backend (issue 2).

Usage: python benchmarks/bench_geodesics.py DATASET_DIR [--points 400]

DATASET_DIR is a TOSCA folder such as ../shared/data/tosca_hires.  Each case runs
in a fresh interpreter (peak RSS is the whole process) with the cache disabled.
The exact backend (MMP, tvb-gdist) is timed on 20 sources and extrapolated to N.
Target: 400 samples of a 50k-vertex mesh in under 15 s with the heat backend.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, run_isolated, write_section  # noqa: E402

CASES = [("wolf", "wolf/wolf0.off"), ("cat", "cat/cat0.off"), ("david", "david/david0.off")]

CODE = """
import time
from shapecond.shapes.io import load_geometry
from shapecond.shapes.metric import metric_shape
from shapecond.shapes.geodesics import DistanceSolver
g = load_geometry({path!r})
t = time.perf_counter()
if {backend!r} == "exact":
    DistanceSolver(g, "exact").distances(range(20))
    seconds = (time.perf_counter() - t) * {points} / 20
else:
    metric_shape(g, n_points={points}, backend={backend!r}, cache=False)
    seconds = time.perf_counter() - t
print(g.n_vertices, seconds)
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--points", type=int, default=400)
    ap.add_argument("--backends", default="heat,fmm,exact")
    args = ap.parse_args()
    rows = ["| mesh | vertices | backend | seconds | peak memory (MB) |", "|---|---|---|---|---|"]
    for name, rel in CASES:
        for backend in args.backends.split(","):
            out, rss = run_isolated(CODE.format(path=str(args.dataset / rel), backend=backend, points=args.points))
            n, seconds = out.split()
            note = " (extrapolated from 20 sources)" if backend == "exact" else ""
            rows.append(f"| {name}0 | {n} | {backend} | {float(seconds):.1f}{note} | {rss:.0f} |")
            print(rows[-1], flush=True)
    body = "\n".join([f"## Geodesic matrix of {args.points} FPS samples (issue 2)", "",
                      f"Machine: {machine()}. Command: `{command_line()}`.", "",
                      "Time includes FPS (one solve per sample) and the solver set-up; cache disabled.", ""] + rows)
    write_section("geodesics", body)


if __name__ == "__main__":
    main()

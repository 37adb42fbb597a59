"""Witness search (lower bound of σ, DESIGN.md 3) on real TOSCA shapes.

Usage: python benchmarks/bench_search.py DATASET_DIR [--shapes cat0,dog0,horse0] [--sizes 100,200,400]
       [--dense cat0] [--resolution cat0,cat3,...] [--resolution-points 100]

Tables written to benchmarks/RESULTS.md (section bench_search):
1. bijections of N FPS samples (heat geodesics): wall and CPU time of ``witness_search`` (default
   effort) against one ``scipy.optimize.quadratic_assignment(D, D, method="faq", maximize=True)``
   self-match of the same matrix, their ratio, σ, the best single swap, peak traced memory;
2. dense targets N = 400, M = 3200: time, σ, best single swap, agreement of the witness with the
   ground-truth .sym map (target within 2 covering radii of the mirror image's nearest target);
3. resolution report (dense, M = 8N against 16N): flag, σ at both, RMS distortion / covering radius.
Distance matrices are built by ``metric_shape`` (cached on disk; build time not counted).
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
from scipy.optimize import quadratic_assignment

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, peak_rss_mb, write_section  # noqa: E402

from shapecond.shapes.io import load_geometry, read_symmetry_map  # noqa: E402
from shapecond.api import metric_shape  # noqa: E402
from shapecond.symmetry.resolution import resolution_for_shape  # noqa: E402
from shapecond.symmetry.search import best_single_swap, witness_search  # noqa: E402


def geometry(root: Path, name: str):
    cls = name.rstrip("0123456789")
    return load_geometry(root / "tosca_hires" / cls / f"{name}.off")


def timed(f):
    w, c = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - w, time.process_time() - c


def table_bijections(root, shapes, sizes):
    rows = ["| shape | N | search s (CPU) | FAQ s (CPU) | ratio (CPU) | σ lower | best swap | peak traced MB |",
            "|---|---|---|---|---|---|---|---|"]
    for name in shapes:
        g = geometry(root, name)
        for n in sizes:
            D = metric_shape(g, n_points=n, target="samples").D
            tracemalloc.start()
            res, w, c = timed(lambda: witness_search(D))
            peak = tracemalloc.get_traced_memory()[1] / 2**20
            tracemalloc.stop()
            _, fw, fc = timed(lambda: quadratic_assignment(D, D, method="faq",
                                                           options={"maximize": True, "rng": np.random.default_rng(0)}))
            swap = best_single_swap(D)[0]
            rows.append(f"| {name} | {n} | {w:.2f} ({c:.2f}) | {fw:.2f} ({fc:.2f}) | {w / fw:.1f} ({c / fc:.1f}) | "
                        f"{res.sigma:.4g} | {swap:.4g} | {peak:.0f} |")
            print(rows[-1], flush=True)
    return rows


def table_dense(root, shapes, n=400, factor=8):
    rows = ["| shape | N | M | search s (CPU) | σ lower | best swap | σ / swap | agree with .sym | peak traced MB |",
            "|---|---|---|---|---|---|---|---|---|"]
    for name in shapes:
        g = geometry(root, name)
        sh = metric_shape(g, n_points=n, target="dense", target_factor=factor)
        tracemalloc.start()
        res, w, c = timed(lambda: witness_search(sh.D, n_samples=n))
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        swap = best_single_swap(sh.D, n)[0]
        cls = name.rstrip("0123456789")
        agree = "-"
        sym_path = root / "tosca_hires" / "symmetries" / f"{cls}.sym"
        if sym_path.exists():
            sym = read_symmetry_map(sym_path)  # 0-based file ids
            internal = {int(v): i for i, v in enumerate(g.ids)}
            mir = np.array([internal[int(sym[g.ids[v]])] for v in sh.samples[:n]])
            gt = sh.nearest[mir]
            agree = f"{np.mean(sh.D[res.witness, gt] <= 2 * sh.covering_radius):.1%}"
        rows.append(f"| {name} | {n} | {sh.n_targets} | {w:.2f} ({c:.2f}) | {res.sigma:.4g} | {swap:.4g} | "
                    f"{res.sigma / swap:.2f} | {agree} | {peak:.0f} |")
        print(rows[-1], flush=True)
    return rows


def table_resolution(root, shapes, n=100):
    rows = ["| shape | N | σ at M=8N | σ at M=16N | change | RMS distortion / covering radius | flag |",
            "|---|---|---|---|---|---|---|"]
    for name in shapes:
        sh = metric_shape(geometry(root, name), n_points=n, target="dense", target_factor=16)
        r = resolution_for_shape(sh)
        rows.append(f"| {name} | {n} | {r.sigma_lo:.4g} | {r.sigma_hi:.4g} | {r.relative_change:+.1%} | "
                    f"{r.distortion_rms / r.covering_radius:.2f} | {r.flag} |")
        print(rows[-1], flush=True)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--shapes", default="cat0,dog0,horse0")
    ap.add_argument("--sizes", default="100,200,400")
    ap.add_argument("--dense", default="cat0")
    ap.add_argument("--resolution", default="cat0,cat3,dog0,dog5,horse0,horse5")
    ap.add_argument("--resolution-points", type=int, default=100)
    a = ap.parse_args()
    witness_search(np.abs(np.subtract.outer(np.arange(9.0), np.arange(9.0))))  # compile / load numba cache
    parts = [f"Machine: {machine()}. Command: `{command_line()}`. Wall time on a shared machine (other jobs "
             "running); CPU time of this process in parentheses. Geodesic build time (cached) not counted.", "",
             "Bijections of N FPS samples (paper's score); FAQ = one scipy `quadratic_assignment` self-match:", ""]
    parts += table_bijections(a.dataset, [s for s in a.shapes.split(",") if s], [int(v) for v in a.sizes.split(",")])
    if a.dense:
        parts += ["", "Dense targets (issue 4), N = 400, M = 8N; agreement = witness target within 2 covering "
                  "radii of the nearest target of the ground-truth mirror image:", ""]
        parts += table_dense(a.dataset, [s for s in a.dense.split(",") if s])
    if a.resolution:
        parts += ["", "Resolution report (dense, same samples, M = 8N against M = 16N, prefix of one FPS order):", ""]
        parts += table_resolution(a.dataset, [s for s in a.resolution.split(",") if s], a.resolution_points)
    parts += ["", f"Peak RSS of the benchmark process: {peak_rss_mb():.0f} MB."]
    body = "\n".join(["## Witness search (bench_search.py)", ""] + parts)
    print(body)
    write_section("bench_search", body)


if __name__ == "__main__":
    main()

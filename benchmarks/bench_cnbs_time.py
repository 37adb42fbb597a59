"""Time of CNBS on σ and on δ(ε) on one TOSCA shape, against an earlier commit in the same run.

Usage: ``python benchmarks/bench_cnbs_time.py DATA_DIR [--shape cat0] [-k 15] [--baseline REV]``

The setting of the paper's Figure 7: N = 400 samples, bijections, symmetry-consistent
sampling from the class's ``.sym`` map when there is one (as in bench_landmarks.py).
Each step runs for the *baseline* (the package at git revision ``--baseline``, default
the merge base of HEAD and ``main``, extracted under benchmarks/out/) and for *ours* (the
working tree), each in a fresh process with the same interpreter and dependencies; each
figure is the wall time and the CPU time of that process (``time.process_time``, all
threads), with the 1-minute load average before it: the machine is shared.  The heat maps
are unpruned (what ``shapecond heatmap`` draws); the landmarks use the pruned heat maps of
``cnbs_landmarks``; the scores are those ``shapecond landmarks`` reports (for δ, the heat
values of the chosen candidates made non-increasing).  Writes the section ``cnbs-time``
of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import baseline_src, command_line, git, machine, run_variant, write_section  # noqa: E402

#: One variant's measurements, printed as JSON by a fresh interpreter.
WORKER = r"""
import json, math, os, resource, time
from pathlib import Path
import importlib, importlib.util
_SEL = "shapecond.selection" if importlib.util.find_spec("shapecond.selection") else "shapecond.landmarks"  # renamed
monotone = importlib.import_module(_SEL).monotone
cnbs_landmarks, heat_map = (getattr(importlib.import_module(_SEL + ".cnbs"), f) for f in ("cnbs_landmarks", "heat_map"))
from shapecond.shapes.io import load_geometry, read_symmetry_map
from shapecond.api import metric_shape
from shapecond.symmetry.scale import budget_of, default_epsilon
from shapecond.symmetry.search import witness_search

def timed(f):
    load = os.getloadavg()[0]
    w, c = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - w, time.process_time() - c, load

root, name, k = Path({root!r}), {shape!r}, {k}
cls = name.rstrip("0123456789")
g = load_geometry(root / cls / f"{{name}}.off")
sym = root / "symmetries" / f"{{cls}}.sym"
if sym.exists():
    g = g.with_symmetry(read_symmetry_map(sym))
shape = metric_shape(g, n_points=400, target="samples")
D, n = shape.D, shape.n_samples
eps = default_epsilon(D, n)
rows = []
for score, budget in (("sigma", None), ("scale", budget_of(eps, n, D))):
    base, w, c, load = timed(lambda: witness_search(D, n, budget=budget))
    rows.append(dict(step=f"witness search, no landmarks ({{score}})", wall=w, cpu=c, load=load))
    hm, w, c, load = timed(lambda: heat_map(D, n, base=base, budget=budget))
    rows.append(dict(step=f"full heat map ({{score}})", wall=w, cpu=c, load=load, argmin=int(hm.argmin())))
    out, w, c, load = timed(lambda: cnbs_landmarks(D, n, k, base=base, budget=budget))
    sc = out["scores"] if budget is None else monotone([v / math.sqrt(n) for v in out["scores"]])
    rows.append(dict(step=f"{{k}} landmarks ({{'cnbs' if budget is None else 'cnbs-scale'}})", wall=w, cpu=c,
                     load=load, scores=[float(v) for v in sc], landmarks=[int(v) for v in out["landmarks"]]))
print(json.dumps(dict(rows=rows, vertices=len(g.vertices), n=n, eps=eps,
                      rss=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)))
"""

#: Compiles the kernels of a variant on a small instance.
WARM_UP = r"""
import numpy as np
import importlib, importlib.util
_SEL = "shapecond.selection" if importlib.util.find_spec("shapecond.selection") else "shapecond.landmarks"  # renamed
monotone = importlib.import_module(_SEL).monotone
cnbs_landmarks, heat_map = (getattr(importlib.import_module(_SEL + ".cnbs"), f) for f in ("cnbs_landmarks", "heat_map"))
from shapecond.symmetry.scale import budget_of, default_epsilon
P = np.random.default_rng(0).normal(size=(40, 3))
D = np.sqrt(((P[:, None] - P[None]) ** 2).sum(-1))
for budget in (None, budget_of(default_epsilon(D, 40), 40, D)):
    cnbs_landmarks(D, 40, 1, budget=budget, options=importlib.import_module(_SEL + ".cnbs").CNBSOptions(effort="quick"))
print("{}")
"""

TARGETS = {"full heat map (sigma)": "10 s", "full heat map (scale)": "30 s"}


def run(code: str, src: Path | None) -> dict:
    return json.loads(run_variant(code, src)["stdout"].strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data")
    ap.add_argument("--shape", default="cat0")
    ap.add_argument("-k", type=int, default=15)
    ap.add_argument("--baseline", default=None, help="git revision of the baseline (default: merge base with main)")
    a = ap.parse_args()
    root = Path(a.data)
    root = root / "tosca_hires" if (root / "tosca_hires").is_dir() else root
    rev = a.baseline or git("merge-base", "HEAD", "main")
    sha, src = baseline_src(rev)
    code = WORKER.format(root=str(root), shape=a.shape, k=a.k)
    res = {}
    for which, path in (("baseline", src), ("ours", None)):
        run(WARM_UP, path)  # compile (or load) this variant's kernels outside the timings
        res[which] = run(code, path)
        print(which, json.dumps(res[which]["rows"]), flush=True)
    ours, base = res["ours"], res["baseline"]
    targets = dict(TARGETS, **{f"{a.k} landmarks (cnbs)": "30 s", f"{a.k} landmarks (cnbs-scale)": "60 s"})
    lines = ["## CNBS time: σ and δ(ε) on one shape (bench_cnbs_time.py)", "",
             f"Machine: {machine()}. Command: `{command_line()}`. Baseline = the package at {sha[:10]}, ours = this "
             f"tree, each step in its own fresh process in the same run. {a.shape}: {ours['vertices']} vertices, N = "
             f"{ours['n']} samples (symmetry-consistent), bijections; δ at the default ε = {ours['eps']:.4f} (the "
             f"median sample spacing). Peak memory {ours['rss']:.0f} MB (baseline {base['rss']:.0f} MB). Targets: "
             "issue 16 for σ (heat map ≤ 10 s, 15 landmarks ≤ 30 s), issue 12 for δ (≤ 30 s, ≤ 60 s), wall time "
             "on 2 cores. CPU = all threads of the process.", "",
             "| step | target | ours wall s (CPU) | baseline wall s (CPU) | wall speed-up | same result | load before "
             "(ours / baseline) | scores after each landmark (ours) |",
             "|---|---|---|---|---|---|---|---|"]
    for r, b in zip(ours["rows"], base["rows"]):
        same = ""
        if "landmarks" in r:
            same = "same landmarks" if r["landmarks"] == b["landmarks"] else \
                f"first {next((i for i, (x, y) in enumerate(zip(r['landmarks'], b['landmarks'])) if x != y), a.k)} same"
        elif "argmin" in r:
            same = "same argmin" if r["argmin"] == b["argmin"] else "other argmin"
        sc = ", ".join(f"{v:.3g}" for v in r.get("scores", []))
        lines.append(f"| {r['step']} | {targets.get(r['step'], '-')} | {r['wall']:.1f} ({r['cpu']:.1f}) | "
                     f"{b['wall']:.1f} ({b['cpu']:.1f}) | {b['wall'] / max(r['wall'], 1e-9):.2f}x | {same} | "
                     f"{r['load']:.2f} / {b['load']:.2f} | {sc} |")
    lm = [(r["step"], r["landmarks"], b["landmarks"]) for r, b in zip(ours["rows"], base["rows"]) if "landmarks" in r]
    lines += ["", "Landmarks (sample indices, in order):", ""]
    lines += [f"- {step}: ours {o}; baseline {bl}" for step, o, bl in lm]
    text = "\n".join(lines)
    print(text)
    write_section("cnbs-time", text)


if __name__ == "__main__":
    main()

"""Local symmetry score (paper Section 5, issue 5): time, peak memory, TOSCA checks, heat map.

Usage: python benchmarks/bench_local.py DATASET_DIR [--quick]

DATASET_DIR is ``shared/data`` (with ``tosca_hires/`` and ``bim_benchmark_landmarks/``).
Every case runs in a fresh interpreter so that its peak resident memory is its own.
Writes the ``local`` section of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _results import command_line, machine, run_isolated, write_section  # noqa: E402

CASE = r'''
import json, math, time, numpy as np
from pathlib import Path
from shapecond.deformation.local_score import LocalProblem
from shapecond.deformation.heatmap import local_heatmap, exact_lambda, select_local_landmarks
from shapecond.shapes.io import load_geometry
from shapecond.shapes.synthetic import bumpy_blob

def load(spec):
    kind, _, arg = spec.partition(":")
    if kind == "blob":
        g = bumpy_blob(int(arg))
        return g.vertices, g.faces, "blob%s" % arg, None
    path = Path(DATA) / "tosca_hires" / arg.rstrip("0123456789+") / (arg.rstrip("+") + ".off")
    g = load_geometry(path)
    V, F = g.vertices, g.faces
    if arg.endswith("+"):   # one loop of midpoint subdivision: ~4x the vertices, same surface
        import trimesh
        V, F = trimesh.remesh.subdivide(V, F)
    pid = Path(DATA) / "bim_benchmark_landmarks" / "TOSCA" / (arg.rstrip("0123456789+") + ".pid")
    lm = None
    if pid.exists():  # first three benchmark landmarks that are not collinear
        ids = [int(l.split()[0]) for l in pid.read_text().split("\n") if l.strip()]
        lm = list(g.to_internal(ids[:2]))
        for v in g.to_internal(ids[2:]):
            a, b, c = V[lm[0]], V[lm[1]], V[v]
            if np.linalg.norm(np.cross(b - a, c - a)) > 1e-2 * np.linalg.norm(b - a) ** 2:
                lm.append(int(v)); break
    return V, F, arg, lm

V, F, name, lm = load(SPEC)
out = {"name": name, "n": int(len(V))}
t, c = time.perf_counter(), time.process_time(); P = LocalProblem(V, F)
out["setup"], out["setup_cpu"] = time.perf_counter() - t, time.process_time() - c
out["backend"] = P.solver.backend
t, c = time.perf_counter(), time.process_time(); r = P.score()
out["score_s"], out["score_cpu"] = time.perf_counter() - t, time.process_time() - c
out["cpu"] = out["setup_cpu"] + out["score_cpu"]
out["score"] = r.score; out["lambda"] = r.lambda_min; out["zero_modes"] = list(r.zero_modes)
out["total"] = out["setup"] + out["score_s"]
if lm is not None:
    t = time.perf_counter(); r3 = P.score(lm); out["score3_s"] = time.perf_counter() - t
    out["score3"] = r3.score; out["lm"] = [int(v) for v in lm]
if HEATMAP:
    fixed = lm or []
    t, c = time.perf_counter(), time.process_time(); hm = local_heatmap(P, fixed)
    out["heat_s"], out["heat_cpu"] = time.perf_counter() - t, time.process_time() - c
    fin = hm.values[np.isfinite(hm.values)]
    out["heat_range"] = [float(fin.min()), float(fin.max())] if fin.size else None
    out["heat_best"] = int(hm.order()[0])
    if CHECK:  # ranking of the modal heat map against exact re-solves on random vertices
        from scipy.stats import spearmanr
        rng = np.random.default_rng(0)
        cand = rng.choice(np.setdiff1d(np.arange(len(V)), fixed), CHECK, replace=False)
        t = time.perf_counter()
        ex = np.array([exact_lambda(P, list(fixed) + [int(v)])[0] for v in cand])
        out["exact_each_s"] = (time.perf_counter() - t) / CHECK
        out["spearman"] = float(spearmanr(hm.lambdas[cand], ex).correlation)
        out["upper_ratio"] = float(np.median(hm.lambdas[cand] / ex))
        out["argmax_rank"] = int(np.sum(ex > ex[np.argmax(hm.lambdas[cand])]))
    if GREEDY:
        t = time.perf_counter(); sel = select_local_landmarks(P, GREEDY, start=fixed)
        out["greedy_s"] = time.perf_counter() - t; out["greedy_scores"] = list(sel.scores)
print(json.dumps(out))
'''


def run_case(data: str, spec: str, heatmap=False, check=0, greedy=0) -> dict:
    code = f"DATA={data!r}; SPEC={spec!r}; HEATMAP={heatmap}; CHECK={check}; GREEDY={greedy}\n" + CASE
    out, rss = run_isolated(code)
    d = json.loads(out.splitlines()[-1])
    d["rss"] = rss
    return d


def fmt(x, nd=3):
    if x is None:
        return "-"
    if isinstance(x, float):
        return "inf" if x == float("inf") else f"{x:.{nd}g}"
    return str(x)


def main(argv):
    if not argv:
        print(__doc__)
        return 2
    data = str(Path(argv[0]).resolve())
    quick = "--quick" in argv
    loads = [os.getloadavg()[0]]
    score_specs = ["blob:5", "tosca:centaur0", "tosca:cat0", "blob:6", "tosca:david0"]
    if not quick:
        score_specs.append("tosca:cat0+")
    rows = []
    for spec in score_specs:
        d = run_case(data, spec)
        rows.append(d)
        print(spec, json.dumps(d), flush=True)
        loads.append(os.getloadavg()[0])
    heat = [run_case(data, "blob:5", heatmap=True, check=0 if quick else 60, greedy=0 if quick else 5),
            run_case(data, "tosca:wolf0", heatmap=True, check=0 if quick else 60, greedy=0 if quick else 3),
            run_case(data, "tosca:centaur0", heatmap=True)]
    for d in heat:
        print("heat", json.dumps(d), flush=True)
    loads.append(os.getloadavg()[0])
    backends = sorted({d["backend"] for d in rows + heat})

    lines = ["## Local symmetry score sigma_inf (issue 5)", "",
             f"Machine: {machine()}. Command: `{command_line()}`. The machine may be shared with other jobs "
             f"(1-minute load average {min(loads):.1f}-{max(loads):.1f} on 2 cores, sampled between cases), "
             "so wall times can be pessimistic; the CPU seconds of the (single-threaded) computation are "
             "what an idle machine would take.", "",
             f"Springs energy, alpha = 1, zero-mode tolerance 1e-3 x 2, solver backend {', '.join(backends)} "
             "(deformation/solver.py).  *setup* = build the Hessian and the mass matrix, factorise H + sM "
             "(sparse Cholesky); *score* = shift-invert ARPACK and naming the zero modes.  *3 landmarks*: "
             "the first three non-collinear BIM benchmark landmarks of the class "
             "(solved with the same factor).  Peak memory = the peak RSS of a fresh interpreter running "
             "the case (Python + NumPy + SciPy baseline ~100 MB included).  `cat0+` is cat0 after one "
             "midpoint subdivision.", "",
             "| mesh | vertices | setup (s) | score (s) | total (s) | total CPU (s) | peak memory (MB) | lambda_min | "
             "score | score, 3 landmarks |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for d in rows:
        lines.append(f"| {d['name']} | {d['n']} | {d['setup']:.2f} | {d['score_s']:.2f} | {d['total']:.2f} | {d['cpu']:.2f} | "
                     f"{d['rss']:.0f} | {fmt(d['lambda'])} | {fmt(d['score'])} | {fmt(d.get('score3'))} |")
    blobs = {d["name"]: d["score"] for d in rows if d["name"].startswith("blob")}
    if "blob5" in blobs and "blob6" in blobs:
        rel = abs(blobs["blob5"] - blobs["blob6"]) / blobs["blob6"]
        lines += ["", f"Resolution: the same blob at 10,242 and 40,962 vertices scores {blobs['blob5']:.4f} and "
                      f"{blobs['blob6']:.4f} ({100 * rel:.2f} % apart; target < 10 %)."]
    lines += ["", "Heat map (local score with each vertex fixed, modal approximation with K = 24 modes, "
                  "DESIGN.md 3) over all vertices, on top of the landmarks shown.  *Spearman* / *median "
                  "upper ratio* / *rank*: against exact re-solves at 60 random vertices (rank = how many of "
                  "them beat, exactly, the vertex the heat map prefers).  *greedy*: `select_local_landmarks` "
                  "(refine = 4 exact re-solves per step).", "",
              "| mesh | vertices | fixed | heat map (s, wall / CPU) | peak memory (MB) | score range | Spearman | "
              "median upper ratio | rank | exact re-solve (s each) | greedy | greedy scores |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for d in heat:
        rng = d.get("heat_range")
        rng = f"{rng[0]:.3g} .. {rng[1]:.3g}" if rng else "all inf"
        greedy = (f"{d['greedy_s']:.1f} s, k={len(d['greedy_scores'])}" if "greedy_s" in d else "-")
        gs = ", ".join(fmt(x) for x in d.get("greedy_scores", [])) or "-"
        lines.append(f"| {d['name']} | {d['n']} | {len(d.get('lm') or [])} | {d['heat_s']:.2f} / {d['heat_cpu']:.2f} | {d['rss']:.0f} | "
                     f"{rng} | {fmt(d.get('spearman'))} | {fmt(d.get('upper_ratio'))} | "
                     f"{fmt(d.get('argmax_rank'))} | {fmt(d.get('exact_each_s'))} | {greedy} | {gs} |")
    big = [d for d in rows if 45000 <= d["n"] <= 60000]
    hm10 = [d for d in heat if 9000 <= d["n"] <= 11000]
    lines += ["", "Targets (2 cores): score under 5 s at ~50k vertices -- "
              + "; ".join(f"{d['name']}: {d['total']:.1f} s wall, {d['cpu']:.1f} s CPU "
                          f"({'met' if d['total'] < 5 else 'not met'} on wall time, "
                          f"{'met' if d['cpu'] < 5 else 'not met'} on CPU time)" for d in big)
              + "; full heat map at 10k vertices under 60 s -- "
              + "; ".join(f"{d['name']}: {d['heat_s']:.1f} s wall ({'met' if d['heat_s'] < 60 else 'not met'})"
                          for d in hm10) + ".",
              "Where the time goes: the Cholesky factor of the 3n x 3n matrix (most of *setup*) and ~30 "
              "triangular solves for ARPACK; both grow faster than n on a surface (factor ~n^1.5).  "
              "Exact re-solves of the heat map cost one eigen-solve per vertex (column *exact re-solve*), "
              "i.e. " + "; ".join(f"{d['exact_each_s'] * d['n'] / 60:.0f} min for every vertex of {d['name']}"
                                  for d in heat if "exact_each_s" in d)
              + "; the modal map is what makes it affordable."]
    body = "\n".join(lines)
    print(body)
    write_section("local", body)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

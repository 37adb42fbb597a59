"""Landmark selection benchmark (issue 6): CNBS against full re-solves, baselines on TOSCA, timing.

Parts (each cached in benchmarks/out/landmarks_*.json, so they can be run separately):

* ``animal``: generated near-symmetric animal (delta = 0.05), N = 100, bijection score.
  Three CNBS steps; at every step the full heat map (a fresh ``witness_search`` for every
  candidate) and its argmin; the mirror-plane checks.
* ``tosca``: the null shapes of the paper's eight classes at N = 400 (symmetry-consistent
  sampling from the class's ``.sym`` map, bijection score: the paper's setting).  FPS, PLS
  and CNBS choose 3 landmarks; σ after 1 and 3 landmarks is evaluated the same way for all
  methods: a ``witness_search`` warm-started from every witness map found on that shape
  (by any method), so that no method profits from a better search.  For CNBS the heat-map
  value is also a valid lower bound and the max of the two is reported.  Pictures for cat0,
  david0, dog0 (heat map of the first step, landmark sets) go to benchmarks/out/.
* ``timing``: one full heat map at N = 400 and 15 CNBS landmarks on cat0.
* ``pictures``: re-draw the cat0, david0, dog0 pictures from the saved results.

Usage: ``python benchmarks/bench_landmarks.py [--data ../shared/data] [--parts animal,tosca,timing]``
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import machine, peak_rss_mb, write_section  # noqa: E402

from shapecond.selection.cnbs import CNBSOptions, cnbs_landmarks, full_heat_map, heat_map  # noqa: E402
from shapecond.selection.fps import fps_landmarks  # noqa: E402
from shapecond.selection.pls import pls_landmarks  # noqa: E402
from shapecond.shapes.io import load_geometry, read_symmetry_map  # noqa: E402
from shapecond.api import metric_shape  # noqa: E402
from shapecond.shapes.synthetic import animal  # noqa: E402
from shapecond.symmetry.search import witness_search  # noqa: E402

OUT = Path(__file__).with_name("out")
CLASSES = ("cat", "centaur", "david", "dog", "horse", "michael", "victoria", "wolf")
PICTURES = ("cat", "david", "dog")

NOTES = """Analysis. Every heat-map value is a lower bound of σ with that candidate fixed (the
best map the warm-started search found). The argmin of lower bounds prefers candidates whose σ
is *underestimated*: when a candidate admits a near-isometry that none of the warm starts lead
to, its value looks low and CNBS picks it; the common evaluation (a fresh multistart search
warm-started from every map found on the shape) then finds that map and reports a higher σ.
david0 shows it: CNBS picks sample 31 (a hand) at 0.825, the value of a base witness that
already fixes it; the mirror repaired to fix the hand polishes only to 0.816, but a fresh search
with the hand fixed finds 1.05, a map that agrees with the mirror on 85 % of the samples and
re-arranges the arm, many coordinated moves away. Verifying every leader by a fresh
`witness_search` (as done for N <= 200, `FULL_VERIFY_N`) fixes this one: after 21 rounds the
argmin is sample 2 at 0.897, below PLS's 0.905; but each round costs ~3 s at N = 400, ~60 s for
this step, which would break the 3-minute budget for 15 landmarks, so it is not the default.
The paper's claim (CNBS lowest after one landmark on every class) assumes exact scores; the
differences on michael0 (0.7 %) are within the spread of the lower bounds themselves. After
three landmarks the picture is the paper's: CNBS at or below FPS everywhere, and horse0 shows
why: one landmark leaves a near-symmetry with σ = 20 for every method, which only CNBS's second
and third landmarks break."""


def _save(name, obj):
    OUT.mkdir(exist_ok=True)
    (OUT / f"landmarks_{name}.json").write_text(json.dumps(obj, indent=1, default=float))


def _load(name):
    p = OUT / f"landmarks_{name}.json"
    return json.loads(p.read_text()) if p.exists() else None


def fmt(v):
    if v is None:
        return "-"
    return "inf" if not math.isfinite(v) else (f"{v:.3g}" if v < 1e4 else f"{v:.2e}")


def part_animal():
    g = animal(delta=0.05)
    shape = metric_shape(g, n_points=100, target="samples")
    n = 100
    x = np.abs(g.vertices[shape.samples[:n], 0])
    plane = x < 1e-9
    t0 = time.perf_counter()
    out = cnbs_landmarks(shape.D, n, 3, options=CNBSOptions(keep_heat_maps=True))
    t_cnbs = time.perf_counter() - t0
    steps, L = [], []
    for c, hm in zip(out["landmarks"], out["heat_maps"]):
        t1 = time.perf_counter()
        full = full_heat_map(shape.D, n, landmarks=L)
        t_full = time.perf_counter() - t1
        comb = np.fmax(full, hm.values)
        imp = hm.improvement()
        steps.append(dict(landmarks_before=list(L), cnbs=int(c), cnbs_value=float(hm.values[c]),
                          full_argmin=int(np.nanargmin(full)), full_min=float(np.nanmin(full)),
                          full_at_cnbs=float(full[c]), combined_argmin=int(np.nanargmin(comb)),
                          combined_min=float(np.nanmin(comb)), combined_at_cnbs=float(comb[c]),
                          cnbs_off_plane=bool(not plane[c]),
                          plane_improvement_max=float(np.nanmax(imp[plane])) if plane.any() else None,
                          offplane_improvement_min=float(np.nanmin(imp[~plane])),
                          heat_seconds=hm.seconds, full_seconds=t_full, sigma_before=hm.sigma_before))
        L.append(int(c))
    res = dict(n=n, delta=0.05, cnbs_seconds=t_cnbs, n_plane=int(plane.sum()), steps=steps,
               initial=out["initial_score"])
    _save("animal", res)
    return res


def tosca_shape(data, cls, n=400):
    g = load_geometry(Path(data) / "tosca_hires" / cls / f"{cls}0.off")
    sym = Path(data) / "tosca_hires" / "symmetries" / f"{cls}.sym"
    if sym.exists():
        g = g.with_symmetry(read_symmetry_map(sym))
    return g, metric_shape(g, n_points=n, target="samples")


def part_tosca(data, classes):
    res = _load("tosca") or {}
    for cls in classes:
        if cls in res:
            continue
        print(f"[tosca] {cls}", flush=True)
        t0 = time.perf_counter()
        g, shape = tosca_shape(data, cls)
        n = shape.n_samples
        t_shape = time.perf_counter() - t0
        t1 = time.perf_counter()
        cn = cnbs_landmarks(shape.D, n, 3, options=CNBSOptions(keep_heat_maps=True))
        t_cnbs = time.perf_counter() - t1
        chosen = {"fps": fps_landmarks(shape.D, n, 3, seed=0), "pls": pls_landmarks(shape.D, n, 3)[0],
                  "cnbs": cn["landmarks"]}
        pool = []
        for hm in cn["heat_maps"]:
            for p in set(chosen["cnbs"]) | {hm.argmin()}:
                r = hm.results.get(p)
                if r is not None:
                    pool += [np.asarray(t) for t in r.maps]
        evals = {}
        for stage in range(2):  # second pass: warm starts from every map of the first
            new_pool = []
            for m, L in chosen.items():
                for j in (1, 3):
                    r = witness_search(shape.D, n, landmarks=L[:j], starts=pool, effort="default")
                    new_pool += list(r.maps)
                    key = f"{m}{j}"
                    evals[key] = max(evals.get(key, 0.0), float(r.sigma))
            pool = pool + new_pool
        for j in (1, 3):
            evals[f"cnbs{j}"] = max(evals[f"cnbs{j}"], cn["scores"][j - 1])
        hm0 = cn["heat_maps"][0]
        res[cls] = dict(vertices=g.n_vertices, initial=cn["initial_score"], chosen=chosen,
                        sample_ids=[int(shape.sample_ids[i]) for i in chosen["cnbs"]], scores=evals,
                        cnbs_scores=cn["scores"], heat_seconds=[hm.seconds for hm in cn["heat_maps"]],
                        cnbs_seconds=t_cnbs, shape_seconds=t_shape)
        np.save(OUT / f"{cls}0_heat.npy", hm0.values)
        if cls in PICTURES:
            pictures(cls, g, shape, chosen, hm0.values, hm0.sigma_before)
        _save("tosca", res)
    return res


def part_pictures(data):
    """Re-draw the pictures from the saved results (heat map recomputed if not saved)."""
    res = _load("tosca") or {}
    for cls in PICTURES:
        if cls not in res:
            continue
        g, shape = tosca_shape(data, cls)
        path = OUT / f"{cls}0_heat.npy"
        if path.exists():
            vals = np.load(path)
        else:
            vals = heat_map(shape.D, shape.n_samples).values
            np.save(path, vals)
        pictures(cls, g, shape, res[cls]["chosen"], vals, res[cls]["initial"])


def pictures(cls, g, shape, chosen, values, sigma_before):
    from shapecond.viz.heatmap import render_heatmap_png
    from shapecond.viz.render import Look, render_rows
    from shapecond.viz.scene import HeatMapStyle

    OUT.mkdir(exist_ok=True)
    vals = np.asarray(values, dtype=float).copy()
    finite = vals[np.isfinite(vals)]
    vals = np.where(np.isnan(vals), finite.max(), vals)
    title = f"{cls}0: σ with each point fixed (N = {shape.n_samples}, before: {fmt(sigma_before)})"
    render_heatmap_png(shape, vals, OUT / f"{cls}0_heatmap.png", ply=str(OUT / f"{cls}0_heatmap.ply"),
                       style=HeatMapStyle(title=title))
    rows = [dict(values=None, landmarks=[int(shape.samples[i]) for i in chosen[m]], label=m.upper())
            for m in ("fps", "pls", "cnbs")]
    render_rows(OUT / f"{cls}0_landmarks.png", g.vertices, g.faces, rows, look=Look(title=f"{cls}0: 3 landmarks"))


def part_timing(data, k=15):
    """Wall and CPU seconds (``time.process_time``: this process only, so comparable
    across machine loads) of one heat map and of ``k`` CNBS landmarks on cat0."""
    res = _load("timing") or {}
    g, shape = tosca_shape(data, "cat")
    n = shape.n_samples
    w0, c0 = time.perf_counter(), time.process_time()
    base = witness_search(shape.D, n)
    w1, c1 = time.perf_counter(), time.process_time()
    hm = heat_map(shape.D, n, base=base)
    w2, c2 = time.perf_counter(), time.process_time()
    res["heat_map"] = dict(shape="cat0", n=n, base_seconds=w1 - w0, base_cpu=c1 - c0, heat_seconds=w2 - w1,
                           heat_cpu=c2 - c1)
    np.save(OUT / "cat0_heat.npy", hm.values)
    _save("timing", res)
    w0, c0 = time.perf_counter(), time.process_time()
    cn = cnbs_landmarks(shape.D, n, k)
    res["cnbs15"] = dict(shape="cat0", n=n, k=k, seconds=time.perf_counter() - w0, cpu=time.process_time() - c0,
                         scores=cn["scores"], landmarks=[int(shape.sample_ids[i]) for i in cn["landmarks"]])
    res["peak_rss_mb"] = peak_rss_mb()
    res["load_avg"] = os.getloadavg()[0]
    _save("timing", res)
    return res


def report():
    lines = ["## Landmark selection: CNBS against full re-solves and the baselines (issue 6)", "",
             f"Machine: {machine()} (shared with other jobs: timings are upper bounds). "
             "Command: `python benchmarks/bench_landmarks.py --parts animal,tosca,timing,pictures` (parts may be "
             "run separately; each caches its figures in benchmarks/out/landmarks_*.json and this section is "
             "rebuilt from all of them).", ""]
    a = _load("animal")
    if a:
        lines += [f"### Generated animal, delta = {a['delta']}, N = {a['n']} (bijection score, "
                  f"symmetry-consistent samples, {a['n_plane']} on the mirror plane)", "",
                  f"σ without landmarks: {fmt(a['initial'])}. CNBS, 3 landmarks: {a['cnbs_seconds']:.1f} s. "
                  "Full heat map = a fresh `witness_search` (effort default) for every candidate.", "",
                  "Both heat maps are lower bounds; 'best known' is their max per candidate.", "",
                  "| step | CNBS choice | σ (CNBS heat map) | argmin of full re-solves | σ (full) at it | full at CNBS choice | argmin of best known | best known: min / at CNBS choice | CNBS off plane | max improvement on plane | min improvement off plane | heat map s | full s |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for i, s in enumerate(a["steps"], 1):
            lines.append(f"| {i} | {s['cnbs']} | {fmt(s['cnbs_value'])} | {s['full_argmin']} | {fmt(s['full_min'])} | "
                         f"{fmt(s['full_at_cnbs'])} | {s['combined_argmin']} | "
                         f"{fmt(s.get('combined_min'))} / {fmt(s.get('combined_at_cnbs'))} | {s['cnbs_off_plane']} | "
                         f"{fmt(s['plane_improvement_max'])} | {fmt(s['offplane_improvement_min'])} | "
                         f"{s['heat_seconds']:.1f} | {s['full_seconds']:.0f} |")
        gaps = [(s["full_at_cnbs"] - s["full_min"]) / s["full_min"] for s in a["steps"]]
        lines += ["", f"The full re-solves' own value at the CNBS choice exceeds their minimum by at most "
                  f"{100 * max(gaps):.2f} % (steps: " + ", ".join(f"{100 * g:.2f} %" for g in gaps) + "); "
                  "where the argmins differ the candidates are near-ties (after two landmarks σ sits at the "
                  "single-swap floor, where many candidates share one value). Exact agreement of the greedy "
                  "choice with the argmin of exact σ is tested on small instances "
                  "(tests/landmarks/test_cnbs.py)."]
        lines.append("")
    t = _load("tosca")
    if t:
        lines += ["### TOSCA null shapes, N = 400 (bijection score, symmetry-consistent sampling from the `.sym` maps)",
                  "", "σ is a lower bound with witness; all methods evaluated by the same warm-started search "
                  "(see the script's docstring). Lower is better.", "",
                  "| shape | vertices | σ before | FPS 1 | PLS 1 | CNBS 1 | FPS 3 | PLS 3 | CNBS 3 | CNBS s (3 landmarks) | heat map s |",
                  "|---|---|---|---|---|---|---|---|---|---|---|"]
        win1 = win3 = 0
        for cls, r in t.items():
            s = r["scores"]
            lines.append(f"| {cls}0 | {r['vertices']} | {fmt(r['initial'])} | {fmt(s['fps1'])} | {fmt(s['pls1'])} | "
                         f"{fmt(s['cnbs1'])} | {fmt(s['fps3'])} | {fmt(s['pls3'])} | {fmt(s['cnbs3'])} | "
                         f"{r['cnbs_seconds']:.0f} | {r['heat_seconds'][0]:.0f} |")
            win1 += s["cnbs1"] <= min(s["fps1"], s["pls1"]) * (1 + 1e-9)
            win3 += s["cnbs3"] <= s["fps3"] * (1 + 1e-9)
        lines += ["", f"CNBS lowest (ties included) after one landmark on {win1} of {len(t)} classes; "
                  f"after three, at or below FPS on {win3} of {len(t)}.", ""]
        losses = [(cls, r) for cls, r in t.items()
                  if r["scores"]["cnbs1"] > min(r["scores"]["fps1"], r["scores"]["pls1"]) * (1 + 1e-9)]
        if losses:
            lines += ["Where CNBS is not lowest after one landmark (σ at CNBS's choice: value in its own heat "
                      "map -> value found by the common evaluation; best baseline):", ""]
            for cls, r in losses:
                s = r["scores"]
                lines.append(f"- {cls}0: {fmt(r['cnbs_scores'][0])} -> {fmt(s['cnbs1'])}; "
                             f"best baseline {fmt(min(s['fps1'], s['pls1']))}")
            lines += ["", NOTES, ""]
    tm = _load("timing")
    if tm:
        load = f"load average {tm['load_avg']:.1f} on 2 cores at the end of the run" if "load_avg" in tm \
            else "load average 5-7 on 2 cores during the run"
        lines += ["### Timing (cat0, N = 400, bijection score)", "",
                  f"Wall time ({load}) and CPU time of the benchmark process (what an otherwise idle core "
                  "would take). CNBS prunes each candidate's search once it passes the incumbent "
                  "(`cnbs.heat_map(prune=True)`); the full heat map (for pictures) is not pruned.", ""]
        if "heat_map" in tm:
            h = tm["heat_map"]
            lines.append(f"- full heat map: {h['heat_seconds']:.1f} s wall, {h.get('heat_cpu', float('nan')):.1f} s CPU "
                         f"(+ {h['base_seconds']:.1f} s for the unconstrained witness search it starts from); "
                         "target < 60 s.")
        if "cnbs15" in tm:
            c = tm["cnbs15"]
            lines.append(f"- {c.get('k', 15)} CNBS landmarks: {c['seconds']:.0f} s wall, "
                         f"{c.get('cpu', float('nan')):.0f} s CPU; target < 180 s. Scores after each: "
                         + ", ".join(fmt(v) for v in c["scores"]))
        if "peak_rss_mb" in tm:
            lines.append(f"- peak memory: {tm['peak_rss_mb']:.0f} MB")
        lines.append("")
    write_section("landmarks", "\n".join(lines))
    print("\n".join(lines))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    ap.add_argument("--parts", default="animal,tosca,timing")
    ap.add_argument("--classes", default=",".join(CLASSES))
    a = ap.parse_args()
    parts = a.parts.split(",")
    if "animal" in parts:
        part_animal()
    if "tosca" in parts:
        part_tosca(a.data, a.classes.split(","))
    if "timing" in parts:
        part_timing(a.data)
    if "pictures" in parts:
        part_pictures(a.data)
    report()


if __name__ == "__main__":
    main()

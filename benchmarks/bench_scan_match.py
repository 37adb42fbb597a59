"""Where a cold match of two scan-resolution meshes spends its CPU, stage by stage (issue 35).

Usage:
    python benchmarks/bench_scan_match.py [SOURCE TARGET] [--landmarks-source IDS] [--landmarks-target IDS]
           [--matcher faq] [--baseline REV] [--no-baseline]

``sc.match`` of SOURCE → TARGET with 6 landmarks, the error bar on, **cold** (an empty
``SHAPECOND_CACHE`` for every run) and on **one core** (one BLAS and one numba thread), in a
fresh interpreter for this checkout's ``src`` (first on ``PYTHONPATH``, whatever package the
interpreter has installed) and for the package at ``--baseline`` (default: the merge base with
``main``), one after the other in the same run.  Each stage's CPU is
exclusive (a stage called inside another is not counted twice):

* geodesics and samples: ``matching.sampled.sample_surface`` (the heat method's factors, the
  farthest-point samples and their distance rows), and the landmarks' rows
  (``matching.sampled.insert_landmarks``);
* the sample matcher (``matching.pipeline.match_samples``);
* the Laplace–Beltrami bases (``shapes.laplace.laplace_basis``);
* the anchors' sides and harmonic coordinates (``matching.zoomout.Anchors.oriented`` / ``harmonic``);
* ZoomOut (``matching.zoomout.zoomout``), its final nearest-neighbour query over all
  vertices shown apart (the last ``nearest_rows`` call, or ``_nearest_in_regions`` where the final
  pass searches cell regions);
* the error bar (``matching.error_bar.bar_and_samples``);
* the rest (loading, the extension of the sample map, imports).

Memory: the process's peak RSS (``ru_maxrss``) when each stage last ends, so the stage whose
end first shows the final peak is where it occurs, and the whole run's max RSS.

Default pair (no data needed): ``demo:animal:resolution=0.0104`` and its deformation
``demo:animal:delta=0.4,resolution=0.0104`` (about 50k vertices, one vertex order), 6 ids
spread over the vertex order as landmarks on both.  The maps of the two versions are
compared vertex by vertex.  ``benchmarks/RESULTS.md`` section ``scan-match``.

"Cold" is an empty shape cache, not a cold numba cache: a baseline extracted for the first
time compiles its kernels inside its run (seconds in the error bar); run the script twice then.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import baseline_src, command_line, git, machine, run_variant, write_section  # noqa: E402

ONE_CORE = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}
DEMO = ("demo:animal:resolution=0.0104", "demo:animal:delta=0.4,resolution=0.0104")
STAGES = ["geodesics and samples", "landmark rows", "sample matcher", "Laplace–Beltrami bases",
          "anchor sides and harmonic coordinates", "ZoomOut iterations", "ZoomOut final nearest neighbours",
          "error bar"]

# the child: exclusive CPU per stage, by wrapping each stage's function wherever it is bound
CHILD = r"""
import json, resource, sys, time
import numpy as np
import shapecond as sc
import shapecond.api.matching, shapecond.matching.pipeline as P, shapecond.matching.zoomout as Z
import shapecond.matching.sampled as S, shapecond.matching.error_bar as E, shapecond.shapes.laplace as LB
cpu, stack, rss = {}, [], {}

def timed(name, f):
    def wrapper(*a, **kw):
        stack.append(0.0)
        t = time.process_time()
        try:
            return f(*a, **kw)
        finally:
            spent = time.process_time() - t
            inner = stack.pop()
            cpu[name] = cpu.get(name, 0.0) + spent - inner
            rss[name] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # the peak so far
            if stack:
                stack[-1] += spent
    return wrapper

def patch(f, name):
    w = timed(name, f)
    for mod in [m for k, m in sys.modules.items() if k.startswith("shapecond") and m is not None]:
        for attr, value in list(vars(mod).items()):
            if value is f:
                setattr(mod, attr, w)

patch(S.sample_surface, "geodesics and samples")
patch(S.insert_landmarks, "landmark rows")
patch(P.match_samples, "sample matcher")
patch(LB.laplace_basis, "Laplace–Beltrami bases")
patch(E.bar_and_samples, "error bar")
patch(Z.zoomout, "ZoomOut iterations")
Z.Anchors.oriented = timed("anchor sides and harmonic coordinates", Z.Anchors.oriented)
Z.Anchors.harmonic = timed("anchor sides and harmonic coordinates", Z.Anchors.harmonic)
_nearest, _calls = Z.nearest_rows, []
def nearest(X, Y):  # the last call (all source vertices) is the final query
    t = time.process_time(); out = _nearest(X, Y); _calls.append(time.process_time() - t); return out
Z.nearest_rows = nearest
_regions = getattr(Z, "_nearest_in_regions", None)  # the final pass searched in cell regions (newer trees)
def in_regions(*a):
    t = time.process_time(); out = _regions(*a); _calls.append(time.process_time() - t); return out
if _regions is not None:
    Z._nearest_in_regions = in_regions
t0 = time.process_time()
r = sc.match(SOURCE, TARGET, LS, LT, matcher=MATCHER)
total = time.process_time() - t0
if _calls:
    cpu["ZoomOut iterations"] -= _calls[-1]
    cpu["ZoomOut final nearest neighbours"] = _calls[-1]
np.save(OUT, r.map)
bar = r.summary.get("error_bar") or {}
print(json.dumps(dict(stages=cpu, match_cpu=total, bar=bar.get("bar"), delta=bar.get("delta"),
                      n=int(r.map.size), peaks=rss)))
"""


def spread_ids(path: str, k: int = 6) -> str:
    """``k`` input ids spread over the vertex order of ``path`` (the default landmarks)."""
    import shapecond as sc

    n = sc.load(path).n_vertices
    return ",".join(str(int(n * f)) for f in (0.002, 0.38, 0.76, 0.095, 0.57, 0.95)[:k])


def run(src: Path | None, pair: tuple, ls: str, lt: str, matcher: str, out: Path) -> dict:
    """One cold match in a fresh interpreter, one core, with its per-stage CPU."""
    code = (f"SOURCE, TARGET, MATCHER, OUT = {pair[0]!r}, {pair[1]!r}, {matcher!r}, {str(out)!r}\n"
            f"LS, LT = {[int(i) for i in ls.split(',')]!r}, {[int(i) for i in lt.split(',')]!r}\n" + CHILD)
    saved = {k: os.environ.get(k) for k in ONE_CORE}
    os.environ.update(ONE_CORE)
    try:
        with tempfile.TemporaryDirectory() as cache:
            r = run_variant(code, src=src, cache=Path(cache))
    finally:
        for k, v in saved.items():
            os.environ.pop(k) if v is None else os.environ.__setitem__(k, v)
    r.update(json.loads(r.pop("stdout").strip().splitlines()[-1]))
    return r


def table(runs: dict, agreement: float | None, reference: str | None = None) -> list[str]:
    names = list(runs)
    lines = ["| stage (CPU s, exclusive) | " + " | ".join(names) + " |", "|---|" + "---:|" * len(names)]
    for stage in STAGES + ["rest"]:
        vals = []
        for r in runs.values():
            v = r["stages"].get(stage, 0.0) if stage != "rest" else r["cpu"] - sum(r["stages"].values())
            vals.append(f"{v:.1f}")
        lines.append(f"| {stage} | " + " | ".join(vals) + " |")
    for label, key, fmt in (("**total CPU** (interpreter)", "cpu", "{:.1f}"), ("wall", "wall", "{:.1f}"),
                            ("max RSS (MB)", "rss", "{:.0f}"), ("load before", "load", "{:.1f}"),
                            ("error bar (sqrt(area))", "bar", "{:.4f}"), ("δ RMS", "delta", "{:.4f}")):
        lines.append(f"| {label} | " + " | ".join(fmt.format(r[key]) if r[key] is not None else "–"
                                                   for r in runs.values()) + " |")
    lines += ["", "| peak RSS (MB) when the stage last ends: the process's peak so far | " + " | ".join(names) + " |",
              "|---|" + "---:|" * len(names)]
    for stage in [s for s in STAGES if any(s in r.get("peaks", {}) for r in runs.values())]:
        label = "ZoomOut (its final pass included)" if stage == "ZoomOut iterations" else stage
        lines.append(f"| {label} | " + " | ".join(f"{r['peaks'][stage]:.0f}" if stage in r.get("peaks", {}) else "–"
                                                  for r in runs.values()) + " |")
    if agreement is not None:
        lines += ["", f"Maps agree on {100 * agreement:.3f} % of the {runs[names[0]]['n']:,} source vertices"
                  + (f" (this tree's against {reference})." if reference else ".")]
    return lines


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pair", nargs="*", help="SOURCE TARGET (default: two ~50k-vertex demo animals)")
    ap.add_argument("--landmarks-source", default=None, help="input ids (default: 6 spread over the vertex order)")
    ap.add_argument("--landmarks-target", default=None, help="input ids (default: the source's)")
    ap.add_argument("--matcher", default="faq")
    ap.add_argument("--baseline", default=None, help="git revision to compare with (default: merge base with main)")
    ap.add_argument("--no-baseline", action="store_true")
    ap.add_argument("--section", default="scan-match", help="RESULTS.md section to write (scan-match-200k, ...)")
    ap.add_argument("--save-map", default=None, help="write this tree's map (.npy), to compare a later run with")
    ap.add_argument("--reference-map", default=None,
                    help="a map saved by --save-map (another tree's): report this tree's agreement with it")
    a = ap.parse_args(argv)
    if len(a.pair) not in (0, 2):
        ap.error("give both SOURCE and TARGET, or neither")
    pair = tuple(a.pair) if a.pair else DEMO
    ls = a.landmarks_source or spread_ids(pair[0])
    lt = a.landmarks_target or ls
    # this checkout's package, not whichever one the interpreter has installed (an editable install of
    # another worktree ran as "this tree" before)
    trees: dict[str, Path | None] = {"this tree": Path(__file__).resolve().parents[1] / "src"}
    if not a.no_baseline:
        sha, src = baseline_src(a.baseline or git("merge-base", "HEAD", "main"))
        trees = {f"baseline {sha[:8]}": src, **trees}
    with tempfile.TemporaryDirectory() as tmp:
        runs = {name: run(src, pair, ls, lt, a.matcher, Path(tmp) / f"map{i}.npy")
                for i, (name, src) in enumerate(trees.items())}
        maps = [np.load(Path(tmp) / f"map{i}.npy") for i in range(len(trees))]
    if a.save_map:
        np.save(a.save_map, maps[-1])
    if a.reference_map:
        maps = [np.load(a.reference_map)] + maps[-1:]
    agreement = float(np.mean(maps[0] == maps[-1])) if len(maps) == 2 else None
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    body = [f"## Cold match at scan resolution, stage by stage ({machine()})", "",
            f"`{command_line()}` (this tree at {head}, uncommitted changes included)", "",
            f"Pair: `{pair[0]}` → `{pair[1]}`, landmarks {ls} → {lt}, matcher {a.matcher}, error bar on; "
            "each column a fresh interpreter with an empty cache, one BLAS/numba thread, run one after the "
            "other. CPU per stage is exclusive; the load average is the machine's (other jobs share it).", "",
            *table(runs, agreement, a.reference_map)]
    write_section(a.section, "\n".join(body))
    print("\n".join(body))


if __name__ == "__main__":
    main()

"""Geodesic rows: the blocked heat method against potpourri3d one source at a time (issues 2 and 16).

Usage: python benchmarks/bench_geodesics.py DATASET_DIR [--stages rows,dense,score,flags] [--sources 48]
       python benchmarks/bench_geodesics.py DATASET_DIR --stages matrix [--points 400] [--backends heat,fmm,exact]

DATASET_DIR is a TOSCA folder such as ../shared/data/tosca_hires.  Each stage stores its rows in
benchmarks/out/bench_geodesics.json and the section "geodesics-blocks" of benchmarks/RESULTS.md is
rebuilt from that store (stage ``matrix`` writes the older section "geodesics").  Every figure sits
beside its baseline measured in the same run: *baseline* is potpourri3d's
``MeshHeatMethodDistanceSolver`` one source per call, which is what ``DistanceSolver("heat")`` did
before issue 16; inside shapecond it is forced by making the intrinsic cover unavailable
(``intrinsic_delaunay_cover`` returns None), so FPS also asks for one row per step.

Stages:

``rows``   the eight TOSCA null shapes: set-up and ms per row for the same ``--sources`` random
           sources, potpourri3d one at a time against ``DistanceSolver.distances`` (blocks), and
           the mean / max |Δ| between the two in % of the diameter.
``dense``  cat0 and david0, N = 400, dense targets M = 3,200, cache off: ``metric_shape`` with
           each solver, each in a fresh interpreter (wall, CPU, peak memory); rows solved.
``score``  ``shapecond score cat0.off`` in fresh processes (2 cores): cold (empty cache) with each
           solver, then warm; and the warm run split into its phases.
``flags``  the eight null shapes at N = 400, M = 3,200 with each solver: σ, the resolution flag,
           and the witness's agreement with the ground-truth mirror (``bench_dense.py``'s measure).
``matrix`` the issue-2 table: the 400-sample matrix per backend with peak memory.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, run_isolated, run_variant, write_section  # noqa: E402

NULL = ["cat0", "centaur0", "david0", "dog0", "horse0", "michael0", "victoria0", "wolf0"]
STORE = Path(__file__).parent / "out" / "bench_geodesics.json"
#: Prepended to a child's code to run it on the baseline (potpourri3d, one source per solve).
BASELINE = "import shapecond.shapes.intrinsic as _i; _i.intrinsic_delaunay_cover = lambda V, F: None\n"


def mesh(root: Path, name: str) -> Path:
    return root / name.rstrip("0123456789") / f"{name}.off"


def load_store() -> dict:
    return json.loads(STORE.read_text()) if STORE.exists() else {}


def save_store(store: dict) -> None:
    STORE.parent.mkdir(parents=True, exist_ok=True)
    STORE.write_text(json.dumps(store, indent=1))


def child(code: str, env: dict | None = None) -> tuple[dict, float, float]:
    """Run ``code`` (which prints one JSON line after __OUT__) in a fresh interpreter: (result, wall, peak MB)."""
    code = code + "\nimport resource\nprint('__RSS__', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)"
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "child failed")
    out = proc.stdout.split("__OUT__", 1)[1].split("__RSS__")[0]
    return json.loads(out), wall, float(proc.stdout.rsplit("__RSS__", 1)[1])


# ---------------------------------------------------------------- rows
ROWS = """
import json, os, time
import numpy as np, potpourri3d as pp3d
from shapecond.shapes.io import load_geometry
from shapecond.shapes.geodesics import DistanceSolver
g = load_geometry({path!r})
src = np.random.default_rng(0).choice(g.n_vertices, {k}, replace=False)
os.environ["SHAPECOND_WORKERS"] = "1"
t = time.perf_counter(); ours = DistanceSolver(g, "heat"); setup = time.perf_counter() - t
del os.environ["SHAPECOND_WORKERS"]
both = DistanceSolver(g, "heat")
ours.distances(src[:2]); both.distances(src[:4])  # loads the compiled kernel, starts the helper
load = os.getloadavg()[0]
t, c = time.perf_counter(), time.process_time(); mine = ours.distances(src)
wall, cpu = time.perf_counter() - t, time.process_time() - c
t = time.perf_counter(); two = both.distances(src); wall2 = time.perf_counter() - t
t = time.perf_counter(); pp = pp3d.MeshHeatMethodDistanceSolver(g.vertices, g.faces); pp_setup = time.perf_counter() - t
t, c = time.perf_counter(), time.process_time()
ref = np.stack([np.maximum(pp.compute_distance(int(s)), 0) for s in src])
pp_wall, pp_cpu = time.perf_counter() - t, time.process_time() - c
diam = float(ref.max())
assert np.allclose(two, mine, rtol=0, atol=1e-9 * diam)
print("__OUT__" + json.dumps(dict(n=g.n_vertices, k={k}, block=ours.block, setup=setup, pp_setup=pp_setup,
      ms=wall / {k} * 1e3, cpu_ms=cpu / {k} * 1e3, ms2=wall2 / {k} * 1e3, helper=both.block > ours.block,
      pp_ms=pp_wall / {k} * 1e3, pp_cpu_ms=pp_cpu / {k} * 1e3,
      mean=float(np.abs(mine - ref).mean()) / diam * 100, max=float(np.abs(mine - ref).max()) / diam * 100,
      load=load)))
"""


def stage_rows(root, store, names, k):
    for name in names:
        r, _, _ = child(ROWS.format(path=str(mesh(root, name)), k=k))
        store.setdefault("rows", {})[name] = r
        save_store(store)
        print(f"rows {name}: ours {r['ms']:.2f} ms/row ({r['ms2']:.2f} on both cores), potpourri3d "
              f"{r['pp_ms']:.2f} ms/row, x{r['pp_ms'] / r['ms']:.1f}, mean |d| {r['mean']:.5f} %", flush=True)


# ---------------------------------------------------------------- dense
DENSE = """
import json, os, time
from shapecond.shapes import sampling
from shapecond.shapes.io import load_geometry
from shapecond.api import metric_shape
solved = [0]
_fetch = sampling._Rows.fetch
def fetch(self, v):
    before = self.computed; _fetch(self, v); solved[0] += self.computed - before
sampling._Rows.fetch = fetch
g = load_geometry({path!r})
load = os.getloadavg()[0]
t, c = time.perf_counter(), time.process_time()
sh = metric_shape(g, n_points=400, target="dense", cache=False)
print("__OUT__" + json.dumps(dict(wall=time.perf_counter() - t, cpu=time.process_time() - c, rows=solved[0] + 1,
      m=sh.n_targets, samples=[int(v) for v in sh.samples], load=load)))
"""


def stage_dense(root, store, names):
    for name in names:
        out = {}
        for which, prefix, workers in (("baseline", BASELINE, "1"), ("one_core", "", "1"), ("ours", "", "")):
            env = dict(os.environ, SHAPECOND_WORKERS=workers)
            r, wall, rss = child(prefix + DENSE.format(path=str(mesh(root, name))), env=env)
            r["rss"] = rss
            out[which] = r
        out["one_core"].pop("samples")
        a, b = np.array(out["ours"].pop("samples")), np.array(out["baseline"].pop("samples"))
        out["first_difference"] = None if np.array_equal(a, b) else int(np.argmax(a != b))
        store.setdefault("dense", {})[name] = out
        save_store(store)
        print(f"dense {name}: ours {out['ours']['wall']:.1f} s, baseline {out['baseline']['wall']:.1f} s", flush=True)


# ---------------------------------------------------------------- score
PHASES = """
import json, os, time
t0 = time.perf_counter()
from shapecond.api import metric_shape
from shapecond.symmetry.resolution import resolution_for_shape
from shapecond.symmetry.score import ScoreOptions, symmetry_score
import shapecond.symmetry.search  # noqa: F401  (loads the compiled kernels)
t1 = time.perf_counter()
shape = metric_shape({path!r})
t2 = time.perf_counter()
sc = symmetry_score(shape.D, shape.n_points, options=ScoreOptions(seed=0))
t3 = time.perf_counter()
res = resolution_for_shape(shape, seed=0, score=sc)
t4 = time.perf_counter()
print("__OUT__" + json.dumps(dict(imports=t1 - t0, load=t2 - t1, score=t3 - t2, resolution=t4 - t3,
      sigma=sc.sigma_lower, flag=res.flag)))
"""


def cli_run(path: Path, cache: Path, prefix: str = "") -> dict:
    code = prefix + ("import json, resource, sys\nfrom shapecond.cli import main\nsys.argv = ['shapecond']\n"
                     f"try:\n    main(['score', {str(path)!r}, '--json'])\nexcept SystemExit:\n    pass\n")
    r = run_variant(code, None, cache)
    report = json.loads(r.pop("stdout"))
    return dict(r, sigma=report["sigma"]["lower"], flag=report["resolution"]["flag"])


def stage_score(root, store, name="cat0"):
    path = mesh(root, name)
    out = {}
    with tempfile.TemporaryDirectory() as a, tempfile.TemporaryDirectory() as b:
        out["cold_baseline"] = cli_run(path, Path(a), BASELINE)
        out["cold"] = cli_run(path, Path(b))
        out["warm"] = cli_run(path, Path(b))
        phases, wall, _ = child(PHASES.format(path=str(path)), env=dict(os.environ, SHAPECOND_CACHE=b))
        phases["startup"] = wall - sum(phases[k] for k in ("imports", "load", "score", "resolution"))
        out["phases"] = phases
    store.setdefault("score", {})[name] = out
    save_store(store)
    print(f"score {name}: cold {out['cold']['wall']:.1f} s (baseline {out['cold_baseline']['wall']:.1f} s), "
          f"warm {out['warm']['wall']:.1f} s", flush=True)


# ---------------------------------------------------------------- flags
FLAGS = """
import json, sys
sys.path.insert(0, {bench!r})
import numpy as np
from bench_dense import mirror_targets
from shapecond.shapes.io import load_geometry
from shapecond.api import metric_shape
from shapecond.symmetry.resolution import resolution_for_shape
from shapecond.symmetry.score import ScoreOptions, symmetry_score
from pathlib import Path
g = load_geometry({path!r})
sh = metric_shape(g, n_points=400, target="dense", cache=False)
sc = symmetry_score(sh.D, 400, options=ScoreOptions(exact=False))
res = resolution_for_shape(sh, score=sc)
gt = mirror_targets(Path({root!r}), {name!r}, g, sh)
print("__OUT__" + json.dumps(dict(sigma=sc.sigma_lower, flag=res.flag,
      agree_2r=float(np.mean(sh.D[sc.witness, gt] <= 2 * sh.covering_radius)),
      moved=float(np.mean(sc.witness != np.arange(400))))))
"""


def stage_flags(root, store, names):
    for name in names:
        out = {}
        for which, prefix in (("baseline", BASELINE), ("ours", "")):
            code = FLAGS.format(bench=str(Path(__file__).parent), path=str(mesh(root, name)),
                                root=str(root.parent), name=name)
            out[which], _, _ = child(prefix + code)
        store.setdefault("flags", {})[name] = out
        save_store(store)
        print(f"flags {name}: {out['ours']['flag']} / {out['baseline']['flag']}", flush=True)


# ---------------------------------------------------------------- matrix (issue 2)
MATRIX = """
import time
from shapecond.shapes.io import load_geometry
from shapecond.api import metric_shape
from shapecond.shapes.geodesics import DistanceSolver
g = load_geometry({path!r})
t = time.perf_counter()
if {backend!r} == "exact":
    DistanceSolver(g, "exact").distances(range(20))
    seconds = (time.perf_counter() - t) * {points} / 20
else:
    metric_shape(g, n_points={points}, backend={backend!r}, target="samples", cache=False)
    seconds = time.perf_counter() - t
print(g.n_vertices, seconds)
"""


def stage_matrix(root, points, backends):
    rows = ["| mesh | vertices | backend | seconds | peak memory (MB) |", "|---|---|---|---|---|"]
    for name in ("wolf0", "cat0", "david0"):
        for backend in backends:
            code = MATRIX.format(path=str(mesh(root, name)), backend=backend, points=points)
            for label, prefix in ([("heat (potpourri3d, one source)", BASELINE)] if backend == "heat" else []) \
                    + [(backend, "")]:
                out, rss = run_isolated(prefix + code)
                n, seconds = out.split()
                note = " (extrapolated from 20 sources)" if backend == "exact" else ""
                rows.append(f"| {name} | {n} | {label} | {float(seconds):.1f}{note} | {rss:.0f} |")
                print(rows[-1], flush=True)
    body = "\n".join([f"## Geodesic matrix of {points} FPS samples (issue 2)", "",
                      f"Machine: {machine()}. Command: `{command_line()}`. Load average before: "
                      f"{os.getloadavg()[0]:.2f}.", "",
                      "Time includes FPS and the solver set-up; cache disabled. `heat` is the blocked heat "
                      "method of issue 16, `heat (potpourri3d, one source)` the solver it replaced.", ""] + rows)
    write_section("geodesics", body)


# ---------------------------------------------------------------- render
def g4(x) -> str:
    return "inf" if x in ("inf", float("inf")) else f"{float(x):.4g}"


def table(header: list[str], rows: list[str]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)] + rows + [""]


def ws(r: dict) -> str:
    """Wall seconds with CPU seconds in parentheses."""
    return f"{r['wall']:.1f} ({r['cpu']:.1f})"


def render(store: dict) -> None:
    lines = ["## Geodesic rows in bulk (issue 16 item 1)", "",
             f"Machine: {machine()}. Last command: `{command_line()}`. Rows accumulate in "
             "benchmarks/out/bench_geodesics.json. Baseline = potpourri3d's heat solver, one source per "
             "call (what `DistanceSolver` did before); ours = `shapes.heat`, the same operators, blocks of "
             "sources per solve, rows fetched ahead by FPS, a forked helper on the second core. Load = "
             "1-minute load average at the start of the measurement (other agents share the 2 cores).", ""]
    rows, dense, score, flags = (store.get(k, {}) for k in ("rows", "dense", "score", "flags"))
    if rows:
        lines += ["### Rows: the same random sources in one process", "",
                  "One core: `SHAPECOND_WORKERS=1`; both cores: with the forked helper (wall time only).", ""]
        lines += table(
            ["shape", "vertices", "set-up s (baseline)", "ms per row, one core (CPU)", "ms per row, both cores",
             "baseline ms per row (CPU)", "speed-up one core / both", "mean \\|Δ\\| % of diameter",
             "max \\|Δ\\| %", "load"],
            [f"| {k} | {r['n']} | {r['setup']:.2f} ({r['pp_setup']:.2f}) | {r['ms']:.2f} ({r['cpu_ms']:.2f}) | "
             f"{r['ms2']:.2f} | {r['pp_ms']:.2f} ({r['pp_cpu_ms']:.2f}) | {r['pp_ms'] / r['ms']:.1f}x / "
             f"{r['pp_ms'] / r['ms2']:.1f}x | {r['mean']:.2g} | {r['max']:.2g} | {r['load']:.2f} |"
             for k, r in rows.items()])
    if dense:
        lines += ["### Dense metric shape: N = 400, M = 3,200 FPS targets, cache off, fresh interpreter each", ""]
        lines += table(["shape", "ours, both cores s (CPU of the main process)", "ours, one core s (CPU)",
                        "baseline s (CPU)", "speed-up both / one core", "rows solved (ours / baseline)",
                        "peak MB (ours / baseline)", "samples", "load"],
                       [f"| {k} | {ws(r['ours'])} | {ws(r['one_core']) if 'one_core' in r else '-'} | "
                        f"{ws(r['baseline'])} | {r['baseline']['wall'] / r['ours']['wall']:.1f}x / "
                        f"{r['baseline']['wall'] / r.get('one_core', r['ours'])['wall']:.1f}x | {r['ours']['rows']} / "
                        f"{r['baseline']['rows']} | {r['ours']['rss']:.0f} / {r['baseline']['rss']:.0f} | "
                        f"{'identical' if r['first_difference'] is None else 'same first %d' % r['first_difference']}"
                        f" | {r['ours']['load']:.2f} / {r['baseline']['load']:.2f} |" for k, r in dense.items()])
    if score:
        lines += ["### `shapecond score` (N = 400, M = 3,200), fresh processes", ""]
        lines += table(["shape", "cold s (CPU)", "cold baseline s (CPU)", "warm s (CPU)",
                        "σ, flag (ours; baseline)", "load (cold / baseline / warm)"],
                       [f"| {k} | {ws(r['cold'])} | {ws(r['cold_baseline'])} | {ws(r['warm'])} | "
                        f"{g4(r['cold']['sigma'])} {r['cold']['flag']}; {g4(r['cold_baseline']['sigma'])} "
                        f"{r['cold_baseline']['flag']} | {r['cold']['load']:.2f} / {r['cold_baseline']['load']:.2f}"
                        f" / {r['warm']['load']:.2f} |" for k, r in score.items()])
        lines += ["Where the warm run's time goes (seconds, one more fresh process):", ""]
        lines += table(["shape", "interpreter start", "imports", "load cached shape", "witness search (σ)",
                        "resolution report (second search)"],
                       [f"| {k} | {p['startup']:.2f} | {p['imports']:.2f} | {p['load']:.2f} | {p['score']:.2f} | "
                        f"{p['resolution']:.2f} |" for k, p in ((k, r["phases"]) for k, r in score.items())])
    if flags:
        lines += ["### Null shapes with each solver: N = 400, M = 3,200", "",
                  "within 2r = the witness sends a sample within two covering radii of the target nearest its "
                  "ground-truth mirror image (bench_dense.py).", ""]
        lines += table(["shape", "σ ours", "σ baseline", "flag ours", "flag baseline", "within 2r ours",
                        "within 2r baseline"],
                       [f"| {k} | {g4(r['ours']['sigma'])} | {g4(r['baseline']['sigma'])} | {r['ours']['flag']} | "
                        f"{r['baseline']['flag']} | {r['ours']['agree_2r'] * 100:.1f} % | "
                        f"{r['baseline']['agree_2r'] * 100:.1f} % |" for k, r in flags.items()])
    write_section("geodesics-blocks", "\n".join(lines + [READING]))


READING = """Reading (2026-11-23, load 2.5-3.2 from other agents' jobs throughout, so no core was ever free):

* Rows: the same heat method as potpourri3d (tufted cover, mollification, intrinsic Delaunay flips,
  t = mean flipped edge length squared), so the same distances up to round-off: mean |Δ| at most
  2e-5 of the diameter (david0, michael0; 0 to print precision elsewhere).  The largest differences
  (up to 0.8 % on david0) sit at the far end of a source's distance field, near its cut locus, where
  the heat method's direction field is ill-conditioned; both solvers are 2 % off the exact geodesics
  there.  One core computes a row 3.5-5x faster than potpourri3d's one-source solve: two CHOLMOD
  solves of 12 columns each (about 0.45 ms per column instead of 1.0 for one column alone) and one
  compiled pass over the faces (0.2 ms per row on cat0).
* Dense build (N = 400, M = 3,200): FPS asks for one row at a time; the rows of the next 12 (24 with
  the helper) steps are guessed from straight-line distances and solved together, and 2-4 % of the
  guesses are wasted (rows solved vs 3,201).  Samples agree with potpourri3d's run until round-off
  flips a near-tie (cat0 at sample 1,257; david0 at sample 1, whose farthest point lies in the
  ill-conditioned region above).  The forked helper halves the solving only when the second core is
  idle: on this loaded machine it gained 24 % on david0 and lost 13 % on cat0.
* Options measured and not kept: libigl's intrinsic Delaunay triangulation (no cover, boundary edges
  never flip): 0.14-0.31 % mean |Δ| on david0, michael0, victoria0, over the 0.1 % bound; potpourri3d
  operators with extrinsic gradients on the original mesh: 0.6 %; the original cotangent Laplacian:
  6.6 %; blocks of 16 to 48 sources (the block leaves the cache: 1.5-1.9 ms per row on cat0 against
  1.3 at 4-12); FPS on a cheap proxy metric for the dense targets (it would change the samples X
  themselves, and the exact lookahead already fetches 96-98 % useful rows); threads (cholespy holds
  the GIL: two threads ran slower than one).
* Null shapes: the same resolution flag on all eight, the same σ on five; on david0, michael0 and
  victoria0 FPS took other samples after a round-off near-tie, and σ moved by +0.2 %, -1.3 % and
  +3.8 % (the witness search's result on a slightly different point set, not a change of distances).
* Score: cold minus warm is the geodesics (7 s against 28 s with potpourri3d in the same run); the
  warm run is the two witness searches (σ and the resolution report, 17.7 of 19.6 s here), imports
  (1.2 s: every sub-command and scipy.stats, trimesh, numba are imported eagerly) and 0.24 s to
  load the cached shape."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--stages", default="rows,dense,score,flags")
    ap.add_argument("--shapes", default=",".join(NULL))
    ap.add_argument("--dense-shapes", default="cat0,david0")
    ap.add_argument("--sources", type=int, default=48)
    ap.add_argument("--points", type=int, default=400)
    ap.add_argument("--backends", default="heat,fmm,exact")
    args = ap.parse_args()
    stages = args.stages.split(",")
    if "matrix" in stages:
        stage_matrix(args.dataset, args.points, args.backends.split(","))
    store = load_store()
    if "rows" in stages:
        stage_rows(args.dataset, store, args.shapes.split(","), args.sources)
    if "dense" in stages:
        stage_dense(args.dataset, store, args.dense_shapes.split(","))
    if "score" in stages:
        stage_score(args.dataset, store)
    if "flags" in stages:
        stage_flags(args.dataset, store, args.shapes.split(","))
    render(store)


if __name__ == "__main__":
    main()

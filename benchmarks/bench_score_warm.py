"""``shapecond score`` on a dense shape with cached geodesics, against an earlier commit (issue 16 item 2).

Usage: python benchmarks/bench_score_warm.py DATASET_DIR [--baseline REV] [--stages time,flags]
                                             [--shapes cat0,...] [--cache DIR]

DATASET_DIR is a TOSCA folder such as ../shared/data/tosca_hires.  Every figure sits beside its baseline
measured in the same run: *baseline* is the package at git revision ``--baseline`` (default: the
merge base of HEAD and ``main``), extracted under benchmarks/out/ and run with the same interpreter and
dependencies; *ours* is the working tree.  Each run is a fresh process (``shapecond score FILE --json``,
N = 400, M = 3,200 dense targets, the defaults).  Both variants read the same cache folder (``--cache``,
default ``$SHAPECOND_CACHE``), so "warm" means the geodesics are cached; "cold" uses a new empty folder.

Stages:

``time``   cat0: cold and warm wall and CPU time of each variant (alternating, warm twice), then one
           more warm process per variant split into phases (imports, loading the cached shape, the σ
           search, the resolution report, the scale-aware score δ).
``flags``  the eight TOSCA null shapes, warm: σ, the resolution flag, δ and the wall time of each variant.

Rows accumulate in benchmarks/out/bench_score_warm.json; the section "score-warm" of
benchmarks/RESULTS.md is rebuilt from that store.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import OUT, baseline_src, command_line, git, machine, run_variant, write_section  # noqa: E402

NULL = ["cat0", "centaur0", "david0", "dog0", "horse0", "michael0", "victoria0", "wolf0"]
STORE = OUT / "bench_score_warm.json"

CLI = """
import sys
from shapecond.cli import main
sys.argv = ['shapecond']
try:
    main({args!r})
except SystemExit:
    pass
"""

PREPARE = """
from shapecond.api import metric_shape
metric_shape({path!r})
"""

#: One warm score, timed by phase: the report's steps are wrapped where ``score_report`` looks them up.
PHASES = """
import json, sys, time
t0 = time.perf_counter()
import shapecond.symmetry.report as R
from shapecond.api import metric_shape
t1 = time.perf_counter()
shape = metric_shape({path!r})
t2 = time.perf_counter()
spent = {{}}
def timed(name, label):
    f = getattr(R, name)
    def g(*a, **k):
        t = time.perf_counter(); out = f(*a, **k); spent[label] = time.perf_counter() - t; return out
    setattr(R, name, g)
timed("symmetry_score", "sigma"); timed("resolution_for_shape", "resolution")
timed("_scale" if hasattr(R, "_scale") else "scale_score", "delta")
r = (getattr(R, "score_report", None) or getattr(R, "score_shape"))(shape)
t3 = time.perf_counter()
print("__OUT__" + json.dumps(dict(imports=t1 - t0, load=t2 - t1, total=t3 - t0, **spent)))
"""


def mesh(root: Path, name: str) -> Path:
    return root / name.rstrip("0123456789") / f"{name}.off"


def run(code: str, cache: Path, src: Path | None) -> dict:
    return run_variant(code, src, cache)


def score(path: Path, cache: Path, src: Path | None) -> dict:
    r = run(CLI.format(args=["score", str(path), "--json"]), cache, src)
    rep = json.loads(r.pop("stdout"))
    return dict(r, sigma=rep["sigma"]["lower"], flag=rep["resolution"]["flag"],
                sigma_lo=rep["resolution"]["sigma_lo"], delta=rep["scale"]["displacement"])


def variants(rev: str) -> tuple[str, dict]:
    sha, src = baseline_src(rev)
    return sha, {"baseline": src, "ours": None}


def warm_up(vs: dict, cache: Path) -> None:
    """Compile (or load) each variant's numba kernels once, outside every timing."""
    for src in vs.values():
        run(CLI.format(args=["score", "demo:animal", "--points", "24", "--json"]), cache, src)


def stage_time(root: Path, cache: Path, vs: dict, store: dict, name: str = "cat0") -> None:
    path = mesh(root, name)
    out = {}
    with tempfile.TemporaryDirectory() as a, tempfile.TemporaryDirectory() as b:
        fresh = {"baseline": Path(a), "ours": Path(b)}
        warm_up(vs, fresh["ours"])
        for which, src in vs.items():
            out[f"cold_{which}"] = score(path, fresh[which], src)
        for k in range(2):
            for which, src in vs.items():
                out[f"warm{k}_{which}"] = score(path, fresh[which], src)
        for which, src in vs.items():
            r = run(PHASES.format(path=str(path)), fresh[which], src)
            out[f"phases_{which}"] = dict(json.loads(r["stdout"].split("__OUT__", 1)[1]), wall=r["wall"])
    store.setdefault("time", {})[name] = out
    save(store)
    print(f"time {name}: warm {out['warm1_ours']['wall']:.1f} s (baseline {out['warm1_baseline']['wall']:.1f} s)",
          flush=True)


def stage_flags(root: Path, cache: Path, vs: dict, store: dict, names: list[str]) -> None:
    warm_up(vs, cache)
    for name in names:
        path = mesh(root, name)
        run(PREPARE.format(path=str(path)), cache, None)  # the geodesics, if not cached yet
        out = {which: score(path, cache, src) for which, src in vs.items()}
        store.setdefault("flags", {})[name] = out
        save(store)
        print(f"flags {name}: sigma {out['ours']['sigma']:.4g} / {out['baseline']['sigma']:.4g}, "
              f"{out['ours']['flag']} / {out['baseline']['flag']}", flush=True)


def save(store: dict) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    STORE.write_text(json.dumps(store, indent=1))


def f2(v) -> str:
    return "inf" if v == "inf" else f"{v:.2f}"


def render(store: dict) -> str:
    meta = store.get("meta", {})
    lines = ["## Warm `shapecond score` on a dense shape (issue 16 item 2)", "",
             f"Machine: {meta.get('machine', '?')}. Last command: `{meta.get('command', '?')}`. Baseline = the "
             f"package at {meta.get('baseline', '?')[:10]} (the previous main), ours = this tree; the same "
             "interpreter, dependencies and cached geodesics; every run a fresh process of `shapecond score "
             "FILE --json` (N = 400, M = 3,200 dense targets). Load = 1-minute load average at the start of "
             "each run (other agents share the 2 cores). Rows accumulate in benchmarks/out/bench_score_warm.json.",
             ""]
    for name, r in store.get("time", {}).items():
        lines += [f"### {name}: cold and warm, wall s (CPU s), load", "",
                  "| variant | cold | warm, run 1 | warm, run 2 |", "|---|---|---|---|"]
        for which in ("baseline", "ours"):
            cells = [f"{r[k]['wall']:.1f} ({r[k]['cpu']:.1f}), {r[k]['load']:.2f}"
                     for k in (f"cold_{which}", f"warm0_{which}", f"warm1_{which}")]
            lines.append(f"| {which} | " + " | ".join(cells) + " |")
        lines += ["", f"Where one more warm run of {name} spends its time (s; the interpreter's start-up is "
                  "the wall time less the total):", "",
                  "| variant | wall | imports | load cached shape | σ search | resolution report | δ(ε) | total |",
                  "|---|---|---|---|---|---|---|---|"]
        for which in ("baseline", "ours"):
            p = r[f"phases_{which}"]
            lines.append(f"| {which} | {p['wall']:.2f} | {p['imports']:.2f} | {p['load']:.2f} | {p['sigma']:.2f} | "
                         f"{p['resolution']:.2f} | {p['delta']:.2f} | {p['total']:.2f} |")
        lines.append("")
    flags = store.get("flags", {})
    if flags:
        lines += ["### The eight null shapes, warm: σ, resolution flag, δ(ε) and wall time", "",
                  "| shape | σ ours | σ baseline | flag ours | flag baseline | σ at M/2 ours / baseline | "
                  "δ ours | δ baseline | wall s ours (CPU) | wall s baseline (CPU) | load |",
                  "|---|---|---|---|---|---|---|---|---|---|---|"]
        for name, r in flags.items():
            o, b = r["ours"], r["baseline"]
            lines.append(f"| {name} | {o['sigma']:.4g} | {b['sigma']:.4g} | {o['flag']} | {b['flag']} | "
                         f"{o['sigma_lo']:.4g} / {b['sigma_lo']:.4g} | {o['delta']:.4g} | {b['delta']:.4g} | "
                         f"{o['wall']:.1f} ({o['cpu']:.1f}) | {b['wall']:.1f} ({b['cpu']:.1f}) | "
                         f"{o['load']:.2f} / {b['load']:.2f} |")
        lines.append("")
    if store.get("reading"):
        lines += [store["reading"], ""]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--baseline", default=None, help="git revision [default: merge base of HEAD and main]")
    ap.add_argument("--stages", default="time,flags")
    ap.add_argument("--shapes", default=",".join(NULL))
    ap.add_argument("--cache", type=Path, default=None, help="cache folder [default: $SHAPECOND_CACHE]")
    args = ap.parse_args()
    rev = args.baseline or git("merge-base", "HEAD", "main")
    cache = args.cache or Path(os.environ.get("SHAPECOND_CACHE") or tempfile.mkdtemp(prefix="score-warm-"))
    store = json.loads(STORE.read_text()) if STORE.exists() else {}
    sha, vs = variants(rev)
    store["meta"] = dict(machine=machine(), command=command_line(), baseline=sha)
    stages = args.stages.split(",")
    if "time" in stages:
        stage_time(args.dataset, cache, vs, store)
    if "flags" in stages:
        stage_flags(args.dataset, cache, vs, store, args.shapes.split(","))
    save(store)
    write_section("score-warm", render(store))


if __name__ == "__main__":
    main()

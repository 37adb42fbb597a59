"""CPU time of ``shapecond match`` for each matcher on one pair, this tree beside a baseline revision.

Usage:
    python benchmarks/bench_match_speed.py [SOURCE TARGET --landmarks-source IDS --landmarks-target IDS]
                                           [--baseline REV] [--repeat N] [--cache DIR]

Issue 31's time target: a 5k-vertex pair in at most 10 s, warm, on one core, every matcher, error bar
included.  Each figure is one ``python -m shapecond match SOURCE TARGET --matcher M -o MAP`` (error bar on,
the defaults otherwise) in a fresh interpreter, **warm** (the geodesics and Laplace-Beltrami bases in a
disk cache filled by an untimed first run, numba's kernels compiled) and on **one core** (one BLAS and
one numba thread): its user and system CPU seconds (the process and its children) and wall seconds, the
least CPU of ``--repeat`` runs, the two trees' runs alternated.  The baseline is the package at
``--baseline`` (default: the merge base with ``main``), run from an extracted copy, on the same pair
with the same cache (``--cache``: a shapecond cache folder to reuse, default a new one); the last column
says whether this tree's map file is the same as the baseline's.

Default pair (no data needed): ``demo:animal:resolution=0.035`` and its deformation
``demo:animal:delta=0.4,resolution=0.035`` (5,294 vertices each, one vertex order), with the source's
first 6 farthest-point samples as landmarks on both.  ``benchmarks/RESULTS.md`` section ``match-speed``.
"""

from __future__ import annotations

import argparse
import filecmp
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import ROOT, baseline_src, command_line, git, machine, write_section  # noqa: E402

ONE_CORE = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}
DEMO = ("demo:animal:resolution=0.035", "demo:animal:delta=0.4,resolution=0.035")
MATCHERS = ("lh05", "faq", "zoomout")
GOAL = 10.0  # CPU seconds (issue 31)


def demo_landmarks(source: str, k: int = 6) -> str:
    """The source's first ``k`` farthest-point samples (input ids), comma-separated."""
    import shapecond as sc
    return ",".join(str(int(v)) for v in sc.landmarks(source, k, "fps").landmarks)


def run_match(src: Path, cache: Path, pair: tuple, landmarks: tuple, matcher: str, out: Path) -> dict:
    """One ``shapecond match`` in a fresh interpreter with the package at ``src``: CPU and wall seconds."""
    env = dict(os.environ, PYTHONPATH=str(src), SHAPECOND_CACHE=str(cache), **ONE_CORE)
    cmd = [sys.executable, "-m", "shapecond", "match", *pair, "--landmarks-source", landmarks[0],
           "--landmarks-target", landmarks[1], "--matcher", matcher, "-o", str(out)]
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{matcher} at {src}: " + (proc.stderr.strip().splitlines() or ["failed"])[-1])
    user, system = after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime
    return dict(user=user, sys=system, cpu=user + system, wall=wall, load=load)


def measure(trees: dict, cache: Path, pair: tuple, landmarks: tuple, repeat: int, tmp: Path) -> dict:
    """{(tree, matcher): best run} after an untimed warm-up run of each."""
    best = {}
    for matcher in MATCHERS:
        for name, src in trees.items():  # warm-up: fills the disk cache, compiles numba's kernels
            run_match(src, cache, pair, landmarks, matcher, tmp / f"{name}-{matcher}.txt")
        for _ in range(repeat):
            for name, src in trees.items():
                r = run_match(src, cache, pair, landmarks, matcher, tmp / f"{name}-{matcher}.txt")
                if (name, matcher) not in best or r["cpu"] < best[name, matcher]["cpu"]:
                    best[name, matcher] = r
    return best


def table(best: dict, trees: dict, tmp: Path) -> list[str]:
    lines = ["| matcher | tree | user s | sys s | CPU s | wall s | load before | ≤ 10 s CPU | same map as baseline |",
             "|---|---|---|---|---|---|---|---|---|"]
    base = next(n for n in trees if n != "this tree")
    for matcher in MATCHERS:
        for name in trees:
            r = best[name, matcher]
            same = filecmp.cmp(tmp / f"this tree-{matcher}.txt", tmp / f"{base}-{matcher}.txt", shallow=False)
            lines.append(f"| {matcher} | {name} | {r['user']:.1f} | {r['sys']:.1f} | {r['cpu']:.1f} | "
                         f"{r['wall']:.1f} | {r['load']:.1f} | {'yes' if r['cpu'] <= GOAL else 'no'} | "
                         f"{('yes' if same else 'no') if name == 'this tree' else '—'} |")
    return lines


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("source", nargs="?", default=DEMO[0])
    ap.add_argument("target", nargs="?", default=DEMO[1])
    ap.add_argument("--landmarks-source", default=None, help="input ids (default: 6 FPS samples of the source)")
    ap.add_argument("--landmarks-target", default=None, help="input ids (default: the source's)")
    ap.add_argument("--baseline", default=None, help="git revision (default: the merge base with main)")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=None, help="shapecond cache folder (default: a new one)")
    a = ap.parse_args(argv)
    ls = a.landmarks_source or demo_landmarks(a.source)
    lt = a.landmarks_target or ls
    sha, base_src = baseline_src(a.baseline or git("merge-base", "HEAD", "main"))
    trees = {"this tree": ROOT / "src", f"baseline {sha[:10]}": base_src}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cache = a.cache or tmp / "cache"
        best = measure(trees, cache, (a.source, a.target), (ls, lt), a.repeat, tmp)
        rows = table(best, trees, tmp)
    text = "\n".join([
        "## Matching time per matcher, warm, one core (bench_match_speed.py)", "",
        f"Machine: {machine()}. Command: `{command_line()}`. This tree: {git('rev-parse', '--short', 'HEAD')}. "
        f"Pair: `{a.source}` → `{a.target}`, landmarks {ls} → {lt}. Each row: `shapecond match` with the error bar "
        f"in a fresh interpreter, disk cache and numba kernels warm, one BLAS and one numba thread; the least CPU "
        f"of {a.repeat} runs, the trees alternated. Goal (issue 31): ≤ {GOAL:g} s.", ""] + rows)
    write_section("match-speed", text)
    print(text)


if __name__ == "__main__":
    main()

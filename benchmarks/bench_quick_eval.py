"""``shapecond evaluate DATASET --quick`` from an empty cache and warm, against an earlier commit in one run.

Usage: ``python benchmarks/bench_quick_eval.py DATASET_DIR [--baseline REV] [--jobs 2]``

DATASET_DIR is a TOSCA folder such as ../shared/data/tosca_hires.  *baseline* is the package at git
revision ``--baseline`` (default: the merge base of HEAD and ``main``), extracted under benchmarks/out/;
*ours* is the working tree.  Each run is a fresh process of the command line (``--quick``: wolf and
centaur, 2 targets each, N = 200, every landmark method and both matchers) with its own cache folder:
empty for the cold run, then the same folder again for the warm one; the two versions' results.json are
compared value by value (clocks left out).  Before both, each variant runs a tiny score so that its
numba kernels are compiled (or loaded) outside the timings.  Wall time, and the CPU time of the whole
process tree (loky's workers included).  Writes the section ``quick-eval`` of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import baseline_src, command_line, git, machine, run_variant, write_section  # noqa: E402

CLI = """
import sys
from shapecond.cli import main
sys.argv = ['shapecond']
try:
    main({args!r})
except SystemExit as e:
    if e.code not in (0, None):
        raise
"""


#: results.json fields that are clocks, not results
CLOCKS = ("second", "time", "wall", "cpu", "load", "date", "version", "machine")


def _leaves(obj, path=()):
    """The numeric and string leaves of a JSON value, by their path of keys and list positions."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            if not any(c in str(k).lower() for c in CLOCKS):
                yield from _leaves(v, path + (str(k),))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _leaves(v, path + (i,))
    else:
        yield path, obj


def same_results(a: Path, b: Path) -> str:
    """How the two runs' results.json agree on the values both hold (clocks left out)."""
    import json

    la, lb = (dict(_leaves(json.loads(p.read_text()))) for p in (a, b))
    common = sorted(set(la) & set(lb), key=str)
    differ = [k for k in common if la[k] != lb[k]]
    only = len(set(la) ^ set(lb))
    fields = Counter(next((str(x) for x in reversed(k) if isinstance(x, str)), "?") for k in differ)
    return (f"{len(common)} values in both runs' results.json, {len(differ)} differ"
            + (f" (by field: {', '.join(f'{f} {n}' for f, n in fields.most_common())}; first: "
               f"{'/'.join(map(str, differ[0]))}: {la[differ[0]]!r} vs {lb[differ[0]]!r})" if differ else "")
            + f"; {only} held by one run only (fields added or removed between the versions)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--baseline", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    sha, src = baseline_src(a.baseline or git("merge-base", "HEAD", "main"))
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        variants = (("baseline", src, []), ("ours", None, []), ("ours, --no-error-bars", None, ["--no-error-bars"]))
        for i, (which, path, extra) in enumerate(variants):
            cache, out = Path(tmp) / f"cache-{i}", Path(tmp) / f"out-{which}"
            run_variant(CLI.format(args=["score", "demo:animal", "--points", "24", "--json"]), path,
                        Path(tmp) / "warm-up")
            args = ["evaluate", str(a.dataset), "--quick", "--jobs", str(a.jobs), "--out", str(out), *extra]
            for run in ("cold", "warm"):
                rows[(which, run)] = run_variant(CLI.format(args=args), path, cache)
                print(which, run, f"{rows[(which, run)]['wall']:.1f} s", flush=True)
        agree = same_results(Path(tmp) / "out-baseline" / "results.json", Path(tmp) / "out-ours" / "results.json")
    lines = ["## `shapecond evaluate --quick` (bench_quick_eval.py)", "",
             f"Machine: {machine()}. Command: `{command_line()}`. Baseline = the package at {sha[:10]}, ours = "
             f"this tree, in the same run; each figure one fresh process (`--quick`: wolf and centaur, 2 targets "
             f"each, N = 200, every landmark method, LH05 and FAQ, `--jobs {a.jobs}`), cold = empty cache, warm = "
             "the same cache again. CPU = the whole process tree's, loky's worker processes included. "
             "Target (issue 16): cold ≤ 30 s. `--no-error-bars`: without the error bar of every matching "
             "(a δ search each; the baseline had none).", "",
             "| variant | cold wall s (CPU s) | warm wall s (CPU s) | load before (cold / warm) |", "|---|---|---|---|"]
    for which, _, _ in variants:
        c, w = rows[(which, "cold")], rows[(which, "warm")]
        lines.append(f"| {which} | {c['wall']:.1f} ({c['tree_cpu']:.1f}) | {w['wall']:.1f} ({w['tree_cpu']:.1f}) | "
                     f"{c['load']:.2f} / {w['load']:.2f} |")
    lines += ["", f"Same numbers: {agree}."]
    text = "\n".join(lines)
    print(text)
    write_section("quick-eval", text)


if __name__ == "__main__":
    main()

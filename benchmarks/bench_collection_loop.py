"""The collection's next landmark, clicked (issues 32 and 34): one more label on every shape, measured.

Usage:
    python benchmarks/bench_collection_loop.py RELEASE [--matcher M] [--max-targets T] [--cache DIR] [--no-write]

RELEASE is a one-class remeshed release as ``bench_collection.py`` reads it (SMAL_r).  The collection is
built as there (each shape linked, its ``NAME.lmk`` holding the template's first 6 farthest-point
landmarks carried through the ``.vts`` ground truth) and matched with the one command
``shapecond batch FOLDER --what match:TEMPLATE``.  Its JSON summary's ``collection_landmark`` (the template
vertex most often suggested among the maps that say annotate more, ``batch.report.collection_landmark``)
is then annotated as a user would: a new label on the template and, at its true image through the ground
truth, on every shape; the same command is run again with ``--resume`` (every shape's landmarks changed,
so every map is matched anew).  Reported: each map's true mean error (reference points, sqrt(area) of its
target) and bar before and after, the means, the maps above 0.05, and the CPU time of each run.  Writes
the section ``collection-loop-NAME`` of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402
from bench_collection import FAIL, _classes, _ends, build_collection, run_command, true_errors  # noqa: E402

LABEL = "next1"


def annotate(cls, folder: Path, vertex: int) -> None:
    """``LABEL`` appended to every shape's ``NAME.lmk``: ``vertex`` on the template, its true image elsewhere."""
    import shapecond as sc
    from shapecond.evaluation.protocols import _reference_ids, landmark_images
    from shapecond.matching.sampled import CachedSolver

    null = sc.load(cls.null)
    ref_s, solver = _reference_ids(cls, cls.null, null), CachedSolver(null, "heat")
    for shape in cls.shapes:
        g = sc.load(shape)
        image = vertex if shape == cls.null else int(
            g.ids[landmark_images(null.to_internal([vertex]), ref_s, _reference_ids(cls, shape, g), solver)[0]])
        lmk = folder / f"{shape.stem}.lmk"
        lmk.write_text(lmk.read_text() + f"{LABEL} {image}\n")


def _maps(rows) -> dict:
    return {_ends(r): r for r in rows if r["error"] is None and r["match_source"] != r["match_target"]}


def summarise(a, cls, before, after, vertex, costs) -> str:
    b, f = _maps(before[0]), _maps(after[0])
    eb = np.array([b[k]["true_error"] for k in b])
    ea = np.array([f[k]["true_error"] for k in b if k in f])
    lines = [f"Machine: {machine()}; load average {costs[0]['load'][0]:.1f} / {costs[1]['load'][0]:.1f} before the "
             "two runs (shared machine: CPU times only).", "", f"Command: `{command_line()}`", "",
             f"Template {cls.null.stem}, {len(cls.shapes)} shapes, 6 named landmarks each, matcher "
             f"{a.matcher or 'lh05 (batch default)'}; the collection's next landmark read off the first run's "
             f"summary: template vertex {vertex} ({before[1]['collection_landmark']['maps']} of the "
             f"{before[1]['collection_landmark']['listed']} maps listed suggest it), annotated on every shape at its "
             f"true image (label `{LABEL}`). CPU of the two runs: {costs[0]['cpu']:.0f} s and {costs[1]['cpu']:.0f} s.",
             "", "| maps | n | error mean / median / worst (10⁻³ sqrt(area)) | above 50 | bar mean | listed |",
             "|---|---|---|---|---|---|"]
    for name, e, rows in (("6 landmarks", eb, b), ("6 + the collection's next", ea, f)):
        bars = [r["bar"] for r in rows.values()]
        listed = sum(1 for r in rows.values() if r["bar"] > 0.05)
        lines.append(f"| {name} | {e.size} | {1e3 * e.mean():.1f} / {1e3 * np.median(e):.1f} / {1e3 * e.max():.0f} | "
                     f"{int((e > FAIL).sum())} | {1e3 * np.mean(bars):.1f} | {listed} |")
    better = sum(f[k]["true_error"] < b[k]["true_error"] for k in b if k in f)
    worse = sum(f[k]["true_error"] > 1.05 * b[k]["true_error"] for k in b if k in f)
    lines += ["", f"Maps with a lower error after: {better} of {len(b)}; more than 5 % higher: {worse}.", "",
              "Per map (10⁻³ sqrt(area)), error before → after: " + "; ".join(
                  f"{k} {1e3 * b[k]['true_error']:.0f} → {1e3 * f[k]['true_error']:.0f}"
                  for k in sorted(b, key=lambda k: -b[k]["true_error"]) if k in f)]
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("release", type=Path)
    p.add_argument("--matcher", default=None)
    p.add_argument("--max-targets", type=int, default=None)
    p.add_argument("--cache", type=Path, default=None, help="SHAPECOND_CACHE of the runs (default: a new folder)")
    p.add_argument("--no-write", action="store_true")
    a = p.parse_args()
    a.points, a.both_directions, a.reuse = 400, False, None
    with tempfile.TemporaryDirectory(prefix="bench_collection_loop_") as tmp:
        os.environ["SHAPECOND_CACHE"] = str(a.cache or Path(tmp) / "cache")
        classes = _classes(a.release, a.max_targets)
        if len(classes) != 1:
            raise SystemExit(f"{a.release}: one class (one template) is needed, found {len(classes)}")
        folder = Path(tmp) / "collection"
        folder.mkdir()
        where = build_collection(classes, folder)
        before = run_command(classes, folder, a)
        true_errors(before[0], where)  # now: the second run writes its maps over these
        found = before[1].get("collection_landmark")
        if not found:
            raise SystemExit("the first run names no landmark for the collection (no two listed maps share one)")
        annotate(classes[0], folder, found["template_vertex"])
        after = run_command(classes, folder, a, again=True)
        true_errors(after[0], where)
        text = summarise(a, classes[0], before, after, found["template_vertex"], (before[2], after[2]))
    print(text)
    if not a.no_write:
        write_section(f"collection-loop-{a.release.name}", "## The collection's next landmark, clicked: "
                      f"{a.release.name} (bench_collection_loop.py)\n\n" + text)


if __name__ == "__main__":
    main()

"""A whole collection matched in one command (issue 34), measured against a release's ground truth.

Usage:
    python benchmarks/bench_collection.py RELEASE [--matcher M] [--points N] [--both-directions]
           [--max-targets T] [--keep DIR | --reuse DIR] [--cache DIR] [--no-write]

RELEASE is a remeshed release as ``shapecond evaluate`` reads it
(``shapecond.evaluation.datasets``: ``SMAL_r`` with ``shapes_train/`` + ``corres/``,
``TOSCA_r/vtx_5k`` flat).  Each class's null shape (the lowest-numbered, as
evaluate picks it) is its template; its first 6 farthest-point landmarks
(``sc.landmarks(..., "fps")``) are carried to every other shape of the class
through the ``.vts`` ground truth (``evaluation.protocols.landmark_images``).

In a temporary folder (never the repository, never the release) the benchmark
builds the collection a user would have: a symbolic link per shape and a
``NAME.lmk`` per shape with the 6 named landmarks (``fps1`` .. ``fps6``).  Then it
runs the one command a user would, in a fresh process:

* one class (SMAL_r): ``shapecond batch FOLDER --what match:FOLDER/TEMPLATE.off``
  (the template is in the folder, so it is matched to itself too, as a user's
  ``bones/*.off`` would; that row is reported apart);
* several classes (TOSCA_r): ``shapecond batch FOLDER --pairs PAIRS`` with one
  line ``TEMPLATE SHAPE`` per shape of each class.

From the written maps (``maps/*.txt``) and the ground truth it computes each map's
true mean geodesic error at the reference points, in units of sqrt(area) of the
map's target (``evaluation.protocols.reference_errors``), and reports the error
(mean / median / worst, maps above 0.05), the quality control of the report
(recall: of the maps above 0.05, the share in the "annotate more" list, bar >
``api.collection.ANNOTATE_MORE``; precision: of the listed, the share truly above
0.03), how often the bar holds the error (bar >= error), and the CPU time of the
command (its process tree) with the load average; the cache starts empty
(``--cache`` to give one), but for the template's samples, which building the
collection computed.  With ``--both-directions``
also the maps back (shape -> template) and whether ``cycle_error`` adds to the
bar's ranking (Spearman correlation of the true error with the bar, the cycle
error and their maximum).  Writes the section ``collection-NAME`` of
benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402

N_LANDMARKS = 6
FAIL, CLEAN = 0.05, 0.03


def _classes(release: Path, max_targets: int | None):
    from shapecond.evaluation.datasets import ClassFolder, check_layout, find_classes

    out = []
    for cls in find_classes(release).values():
        if cls.layout != "remeshed":
            raise SystemExit(f"{release}: class {cls.name} has no .vts ground truth")
        check_layout(cls)
        shapes = cls.shapes if max_targets is None else cls.shapes[:1 + max_targets]
        out.append(ClassFolder(cls.name, shapes, cls.layout))
    return out


def build_collection(classes, folder: Path) -> dict:
    """Links and ``NAME.lmk`` files in ``folder``; returns ``shapes_by_name``."""
    import shapecond as sc
    from shapecond.evaluation.protocols import _reference_ids, landmark_images
    from shapecond.matching.sampled import CachedSolver

    for cls in classes:
        null = sc.load(cls.null)
        ref_s = _reference_ids(cls, cls.null, null)
        ids = [int(v) for v in sc.landmarks(cls.null, N_LANDMARKS, "fps", force=True).landmarks][:N_LANDMARKS]
        solver = CachedSolver(null, "heat")
        for shape in cls.shapes:
            if shape == cls.null:
                image = ids
            else:
                g = sc.load(shape)
                image = [int(g.ids[v]) for v in landmark_images(null.to_internal(ids), ref_s,
                                                                _reference_ids(cls, shape, g), solver)]
            (folder / shape.name).symlink_to(shape.resolve())
            (folder / f"{shape.stem}.lmk").write_text(
                "".join(f"fps{k + 1} {v}\n" for k, v in enumerate(image)))
    return shapes_by_name(classes)


def shapes_by_name(classes) -> dict:
    """Shape name -> (its class, its path in the release)."""
    return {shape.stem: (cls, shape) for cls in classes for shape in cls.shapes}


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run_command(classes, folder: Path, a, again: bool = False) -> tuple[list, dict, dict]:
    """The user's one command; (its rows, its JSON summary, its cost, kept in ``out/cost.json``).  With
    ``--reuse`` the command is run again with ``--resume`` (nothing to compute: its summary) and the cost is
    the first run's; ``again``: run again with ``--resume`` after the landmark files changed (the rows whose
    landmarks changed are computed anew), its own cost."""
    out = folder.parent / "out" / "table.jsonl"
    out.parent.mkdir(exist_ok=a.reuse is not None or again)
    cmd = [sys.executable, "-m", "shapecond", "batch", str(folder), "--out", str(out), "--json",
           "--points", str(a.points)]
    if len(classes) == 1:
        cmd += ["--what", f"match:{folder / classes[0].null.name}"]
    else:
        pairs = out.parent / "pairs.txt"
        pairs.write_text("".join(f"{c.null.stem} {s.stem}\n" for c in classes for s in c.targets))
        cmd += ["--pairs", str(pairs)]
    cmd += (["--matcher", a.matcher] if a.matcher else []) + (["--both-directions"] if a.both_directions else [])
    cmd += ["--resume"] if a.reuse is not None or again else []
    shown = " ".join(["shapecond", *cmd[3:]]).replace(str(folder), "COLLECTION").replace(str(out.parent), "OUT")
    print(shown, flush=True)
    load0, t0, c0 = os.getloadavg()[0], time.perf_counter(), _children_cpu()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=folder)
    cost = dict(cpu=_children_cpu() - c0, wall=time.perf_counter() - t0, load=(load0, os.getloadavg()[0]),
                command=shown, status=proc.returncode)
    if proc.returncode not in (0, 3):
        raise SystemExit(f"the command failed ({proc.returncode}): {proc.stderr.strip()[-2000:]}")
    if again:
        pass
    elif a.reuse is None:
        (out.parent / "cost.json").write_text(json.dumps(cost))
    else:
        cost = json.loads((out.parent / "cost.json").read_text())
    rows = [json.loads(line) for line in out.read_text().splitlines() if line.strip()]
    return rows, json.loads(proc.stdout), cost


def true_errors(rows, where: dict) -> None:
    """Each row's ``true_error`` (None for a failed row): the map's mean error at the reference points, in
    sqrt(area) of its target; rows are grouped by target so that each target's geodesics are computed once."""
    import shapecond as sc
    from shapecond.evaluation.protocols import _reference_ids, reference_errors
    from shapecond.matching.sampled import surface_unit

    by_target = {}
    for k, r in enumerate(rows):
        r["true_error"] = None
        if r["map_file"] is not None:
            by_target.setdefault(Path(r["match_target"]).stem, []).append(k)
    for target, ks in by_target.items():
        cls, tpath = where[target]
        g = sc.load(tpath)
        ref_t = _reference_ids(cls, tpath, g)
        preds = {}
        for k in ks:
            scls, spath = where[Path(rows[k]["match_source"]).stem]
            src = sc.load(spath)
            vmap = np.loadtxt(rows[k]["map_file"], dtype=np.int64, ndmin=1)
            image = vmap[src.ids[_reference_ids(scls, spath, src)]]
            if (image < 0).any():
                rows[k]["true_error"] = math.inf
                continue
            preds[k] = g.to_internal(image)
        raw, diameter, _ = reference_errors(g, ref_t, preds, "heat")
        unit = surface_unit(g, diameter)
        for k, e in raw.items():
            rows[k]["true_error"] = float(e.mean() / unit)


def _listed(summary: dict, folder: Path) -> set:
    """(shape, direction) of every map of the report's "annotate more" list (each shape of the collection is the
    ``file`` of one task: one template, or the second of one listed pair)."""
    return {(Path(os.path.join(folder, m["file"])).stem, m["direction"]) for m in summary.get("annotate_more") or []}


def _key(r) -> tuple:
    return Path(r["file"]).stem, r["match_direction"]


def _ends(r) -> str:
    return f"{Path(r['match_source']).stem}→{Path(r['match_target']).stem}"


def _spearman(x, y) -> float:
    from scipy.stats import spearmanr

    return float(spearmanr(x, y).statistic) if len(x) > 2 else math.nan


def quality(rows, listed: set) -> dict:
    """The report's list over ``rows`` (matched maps between two shapes) against their true errors."""
    e = np.array([r["true_error"] for r in rows])
    bar = np.array([r["bar"] if r["bar"] is not None else math.nan for r in rows])
    flagged, failed = np.array([_key(r) in listed for r in rows]), e > FAIL
    q = dict(n=len(rows), mean=e.mean(), median=float(np.median(e)), worst=e.max(), failed=int(failed.sum()),
             listed=int(flagged.sum()), recall=(flagged & failed).sum() / failed.sum() if failed.any() else math.nan,
             precision=(flagged & (e > CLEAN)).sum() / flagged.sum() if flagged.any() else math.nan,
             held=float(np.mean(bar >= e)), bar_mean=float(np.nanmean(bar)))
    q["consistent"] = bool(np.array_equal(flagged, bar > _annotate_more()))
    return q


def _signals(rows) -> dict:
    """name -> one value per row of each quality signal: the bar, ε̂ (the map's distortion, from which the bar
    is computed), and with both directions the cycle error, the larger of bar and cycle and the mean of their
    ranks."""
    from scipy.stats import rankdata

    bar = np.array([r["bar"] if r["bar"] is not None else math.nan for r in rows])
    cyc = np.array([r.get("cycle_error") if r.get("cycle_error") is not None else math.nan for r in rows])
    eps = np.array([r["bar_epsilon_hat"] if r["bar_epsilon_hat"] is not None else math.nan for r in rows])
    out = {"bar": bar, "ε̂ (the map's own distortion)": eps}
    if np.isfinite(cyc).all() and np.isfinite(bar).all():
        out.update({"cycle error": cyc, "max(bar, cycle)": np.maximum(bar, cyc),
                    "mean rank of bar and cycle": (rankdata(bar) + rankdata(cyc)) / 2})
    return out


def ranking(rows) -> list[dict]:
    """How well each signal ranks the maps by true error: Spearman ρ, the AUC of telling a map above 0.03 from
    one below, and the maps flagged (and the precision: share above 0.03) by the signal's threshold that
    catches 90 % of the maps above 0.03 (0.03, not 0.05: a release's maps with 6 landmarks are rarely above
    0.05, too few to rank)."""
    from scipy.stats import mannwhitneyu

    e = np.array([r["true_error"] for r in rows])
    failed = e > CLEAN
    out = []
    for name, s in _signals(rows).items():
        q = {"signal": name, "rho": _spearman(e, s), "auc": math.nan, "flagged": None, "precision": math.nan}
        if failed.any() and not failed.all():
            q["auc"] = float(mannwhitneyu(s[failed], s[~failed]).statistic / (failed.sum() * (~failed).sum()))
            need = math.ceil(0.9 * failed.sum())
            flagged = s >= np.sort(s[failed])[::-1][need - 1]
            q.update(flagged=int(flagged.sum()), precision=float(np.mean(e[flagged] > CLEAN)))
        out.append(q)
    return out


def _annotate_more() -> float:
    from shapecond.api.collection import ANNOTATE_MORE

    return ANNOTATE_MORE


def _fmt(v, scale=1.0, digits=1) -> str:
    return "–" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v * scale:.{digits}f}"


def summarise(a, rows, summary, cost, classes) -> str:
    maps = [r for r in rows if r["error"] is None and Path(r["match_source"]).stem != Path(r["match_target"]).stem]
    self_rows = [r for r in rows if r["error"] is None and r not in maps]
    failed_rows = [r for r in rows if r["error"] is not None]
    listed = _listed(summary, Path(a.folder))
    per_row_cpu = sum(r["cpu_seconds"] or 0 for r in rows  # one task's rows share its CPU time
                      if r["match_direction"] in ("template to shape", "first to second"))
    lines = [f"Machine: {machine()}; load average {cost['load'][0]:.1f} before the command, "
             f"{cost['load'][1]:.1f} after (shared machine: CPU times only, wall time not claimed).", "",
             f"Command: `{command_line()}`", "",
             f"{len(classes)} template(s) ({', '.join(c.null.stem for c in classes)}), "
             f"{sum(len(c.shapes) for c in classes)} shapes, {N_LANDMARKS} named landmarks per shape (the template's "
             "first farthest-point samples carried through the .vts ground truth), N = "
             f"{a.points}, matcher {a.matcher or 'lh05 (batch default)'}. The one command, run in a temporary "
             f"folder of links and .lmk files: `{cost['command']}` (exit status {cost['status']}).", "",
             f"CPU time of the command (its process tree): {cost['cpu']:.0f} s, {cost['cpu'] / max(1, len(rows)):.1f} "
             f"s per map; the tasks' own cpu_seconds sum to {per_row_cpu:.0f} s. Rows: {len(rows)}, failed "
             f"{len(failed_rows)}" + (f" ({failed_rows[0]['error']})" if failed_rows else "") + ".", "",
             "True error: mean geodesic error at the reference points in 10⁻³ sqrt(area) of the map's target. "
             "Recall: of the maps above 50, the share in the report's \"annotate more\" list (bar > 0.05); "
             "precision: of the listed, the share truly above 30; held: bar ≥ error; ρ: Spearman correlation with "
             "the true error.", "",
             "| maps | n | error mean / median / worst | above 50 | listed | recall | precision | held | bar mean |",
             "|---|---|---|---|---|---|---|---|---|"]
    directions = sorted({r["match_direction"] for r in maps}, key=lambda d: d not in ("template to shape",
                                                                                      "first to second"))
    groups = [(d, [r for r in maps if d in ("all", r["match_direction"])])
              for d in directions + (["all"] if len(directions) > 1 else [])]
    for d, sel in groups:
        q = quality(sel, listed)
        lines.append(f"| {d} | {q['n']} | {_fmt(q['mean'], 1e3)} / {_fmt(q['median'], 1e3)} / {_fmt(q['worst'], 1e3, 0)} "
                     f"| {q['failed']} | {q['listed']} | {_fmt(q['recall'], 1, 2)} | {_fmt(q['precision'], 1, 2)} | "
                     f"{q['held']:.2f} | {_fmt(q['bar_mean'], 1e3)} |")
        if not q["consistent"]:
            lines.append(f"| (the report's list differs from bar > 0.05 for {d}) |")
    lines += ["", "Ranking the maps by a quality signal: Spearman ρ with the true error; AUC: the chance that a map "
              "above 30 scores higher than one below; at 90 % recall: the maps the signal's threshold flags when it "
              "catches 90 % of those above 30, and the share of them truly above 30 (precision).", "",
              "| maps | signal | ρ | AUC (above 30) | flagged at 90 % recall | precision there |", "|---|---|---|---|---|---|"]
    for d, sel in groups:
        for q in ranking(sel):
            lines.append(f"| {d} | {q['signal']} | {_fmt(q['rho'], 1, 2)} | {_fmt(q['auc'], 1, 2)} | "
                         f"{'–' if q['flagged'] is None else q['flagged']} | {_fmt(q['precision'], 1, 2)} |")
    for r in self_rows:
        lines += ["", f"The template matched to itself ({r['match_direction']}): true error "
                  f"{_fmt(r['true_error'], 1e3)}, bar {_fmt(r['bar'], 1e3)}."]
    lines += ["", "Per map (10⁻³ sqrt(area)): error / bar" + (" / cycle" if a.both_directions else "")
              + "; * listed.", ""]
    per = sorted(maps, key=lambda r: -r["true_error"])
    lines.append("; ".join(f"{_ends(r)} {_fmt(r['true_error'], 1e3, 0)}/{_fmt(r['bar'], 1e3, 0)}"
                           + (f"/{_fmt(r.get('cycle_error'), 1e3, 0)}" if a.both_directions else "")
                           + ("*" if _key(r) in listed else "") for r in per))
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("release", type=Path)
    p.add_argument("--matcher", default=None, help="--matcher of the command (default: batch's, lh05)")
    p.add_argument("--points", type=int, default=400)
    p.add_argument("--both-directions", action="store_true")
    p.add_argument("--max-targets", type=int, default=None, help="shapes per class besides the template")
    p.add_argument("--keep", type=Path, default=None, help="build the collection (collection/, out/) in this "
                   "folder outside the repository, empty or new, and keep it")
    p.add_argument("--cache", type=Path, default=None, help="SHAPECOND_CACHE of the run (default: an empty "
                   "folder, so that the CPU time is a first run's)")
    p.add_argument("--reuse", type=Path, default=None, help="a --keep folder whose command completed: measure "
                   "its maps again (the command re-run with --resume computes nothing)")
    p.add_argument("--no-write", action="store_true")
    a = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_collection_") as tmp:
        os.environ["SHAPECOND_CACHE"] = str(a.cache or Path(tmp) / "cache")
        classes = _classes(a.release, a.max_targets)
        root = a.reuse or a.keep or Path(tmp)
        if a.keep is not None and a.keep.exists() and any(a.keep.iterdir()):
            raise SystemExit(f"{a.keep}: not empty")
        folder = root / "collection"
        a.folder = str(folder)
        if a.reuse is None:
            folder.mkdir(parents=True)
        where = build_collection(classes, folder) if a.reuse is None else shapes_by_name(classes)
        rows, summary, cost = run_command(classes, folder, a)
        true_errors(rows, where)
        text = summarise(a, rows, summary, cost, classes)
    print(text)
    print(f"(wall {cost['wall']:.0f} s)")
    if not a.no_write:
        name = a.release.name if a.release.name not in ("vtx_5k",) else a.release.parent.name
        write_section(f"collection-{name}" + ("-both" if a.both_directions else ""), f"## A collection matched "
                      f"in one command: {name} (bench_collection.py)\n\n" + text)


if __name__ == "__main__":
    main()

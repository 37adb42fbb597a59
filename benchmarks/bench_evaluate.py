"""The paper's Figure 7 evaluation on TOSCA, timed, beside the paper's claims (issue 7).

Usage:
    python benchmarks/bench_evaluate.py DATASET_DIR [--jobs 2] [--quick] [--out DIR]
    python benchmarks/bench_evaluate.py --from DIR     # summarise an earlier run's results.json

Runs ``shapecond.matching.evaluation.evaluate_dataset`` (the same as
``shapecond evaluate``), writes the full report into --out, and puts a summary
in benchmarks/RESULTS.md (section ``evaluate``): time, the score after 1/3/all
landmarks, mean errors at 3 and all landmarks per matcher, Spearman's ρ, and
for each claim of the paper (Figure 7, issue 7) whether the measurement agrees.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402

PAPER_ORDER = ["horse", "victoria", "michael", "david", "dog", "centaur", "cat", "wolf"]


def _num(v):
    return math.inf if v == "inf" else (math.nan if v is None else float(v))


def _f(v):
    v = _num(v)
    return "inf" if math.isinf(v) else ("-" if math.isnan(v) else f"{v:.3g}")


def _tables(data: dict):
    """(scores, err): {(class, method): {count: σ}} and {(class, method, count, matcher): mean error}."""
    scores = {(d["cls"], d["method"]): {int(k): _num(v) for k, v in d["scores"].items()}
              for d in data["landmarks"]}
    errs = {}
    for r in data["records"]:
        errs.setdefault((r["cls"], r["method"], r["n_landmarks"], r["matcher"]), []).append(r["error"])
    return scores, {k: sum(v) / len(v) for k, v in errs.items()}


def summarise(data: dict, wall: float | None) -> str:
    st = data["settings"]
    classes = [c for c in PAPER_ORDER if c in st["classes"]] + \
        [c for c in st["classes"] if c not in PAPER_ORDER]
    methods, matchers = st["methods"], st["matchers"]
    scores, err = _tables(data)
    L = st["landmark_counts"]
    lines = ["## Figure 7 evaluation on TOSCA (issue 7)", "",
             f"Machine: {machine()}. Command: `{command_line()}`, summarising the run "
             f"`shapecond evaluate {st['dataset']} --classes {','.join(st['classes'])} "
             f"--methods {','.join(methods)} --jobs {st['n_jobs']}{' --quick' if st['quick'] else ''}`.",
             "",
             f"N = {st['n_points']}, {st['backend']} geodesics, methods {', '.join(methods)}, "
             f"matchers {', '.join(matchers)}, jobs {st['n_jobs']}"
             f"{', quick mode' if st['quick'] else ''}. Wall time: "
             + (f"{wall / 60:.1f} min" if wall else "see the run") + "; phases (s): "
             + ", ".join(f"{k} {v:.0f}" for k, v in data["seconds"].items()) + ".", "",
             "Errors: mean geodesic error of the dense map at the target's samples, % of half the "
             "target's geodesic diameter, averaged over the class's targets.", "",
             "### Score after 1 / 3 / all landmarks (Figure 7a)", "",
             "| class | L | " + " | ".join(methods) + " |", "|---|---|" + "---|" * len(methods)]
    for c in classes:
        lines.append(f"| {c} | {L[c]} | " + " | ".join(
            " / ".join(_f(v) for _, v in sorted(scores.get((c, m), {}).items())) for m in methods) + " |")
    for mt in matchers:
        lines += ["", f"### Mean error with 3 / all landmarks, {mt} (Figure 7b)", "",
                  "| class | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
        for c in classes:
            k3 = min(3, L[c])
            lines.append(f"| {c} | " + " | ".join(
                f"{_f(err.get((c, m, k3, mt)))} / {_f(err.get((c, m, L[c], mt)))}" for m in methods) + " |")
        cor = data["correlation"].get(mt, {})
        lines += ["", f"Spearman ρ(score, error), {mt}: {_f(cor.get('rho'))} "
                  f"(p = {_f(cor.get('p'))}, {cor.get('n')} cells pooled over classes); "
                  f"mean within-class ρ: {_f(cor.get('within_class'))}."]
    lines += ["", "### Against the paper", ""] + claims(classes, methods, matchers, scores, err, L, data)
    return "\n".join(lines)


def claims(classes, methods, matchers, scores, err, L, data) -> list[str]:
    out = []
    if "cnbs" not in methods or "fps" not in methods:
        return ["CNBS or FPS missing from this run: the paper's comparisons cannot be checked."]
    tol = 1e-9  # scores equal to round-off are ties
    low1 = [c for c in classes if all(scores.get((c, "cnbs"), {}).get(1, math.inf)
                                      <= scores.get((c, m), {}).get(1, math.inf) * (1 + tol)
                                      for m in methods)]
    strict = [c for c in low1 if all(scores.get((c, "cnbs"), {}).get(1, math.inf)
                                     < scores.get((c, m), {}).get(1, math.inf) * (1 - tol)
                                     for m in methods if m != "cnbs")]
    out.append(f"- Paper: after one landmark CNBS has the lowest score on every class. Measured: "
               f"lowest or tied on {len(low1)} of {len(classes)} ({', '.join(low1) or 'none'}), "
               f"strictly lowest on {len(strict)} ({', '.join(strict) or 'none'}) — "
               f"{'agrees' if len(low1) == len(classes) else 'disagrees'}.")
    for mt in matchers:
        le = [c for c in classes if err.get((c, "cnbs", min(3, L[c]), mt), math.inf)
              <= err.get((c, "fps", min(3, L[c]), mt), -math.inf)]
        need = math.ceil(6 * len(classes) / 8)
        verdict = "agrees" if len(le) >= need else "disagrees"
        out.append(f"- Paper: with 3 landmarks CNBS error at or below FPS on at least 6 of 8 classes. "
                   f"{mt}: {len(le)} of {len(classes)} ({', '.join(le) or 'none'}) — {verdict}.")
        gaps = []
        for c in classes:
            vals = [err.get((c, m, L[c], mt)) for m in methods if err.get((c, m, L[c], mt)) is not None]
            vals3 = [err.get((c, m, min(3, L[c]), mt)) for m in methods
                     if err.get((c, m, min(3, L[c]), mt)) is not None]
            if vals and vals3:
                gaps.append((max(vals) - min(vals), max(vals3) - min(vals3)))
        if gaps:
            a = sum(g[0] for g in gaps) / len(gaps)
            b = sum(g[1] for g in gaps) / len(gaps)
            out.append(f"- Paper: with all landmarks the methods come close. {mt}: mean spread "
                       f"between methods {a:.2f} points with all landmarks vs {b:.2f} with 3 — "
                       f"{'agrees' if a <= b else 'disagrees'}.")
        rho = _num(data["correlation"].get(mt, {}).get("rho"))
        p = _num(data["correlation"].get(mt, {}).get("p"))
        out.append(f"- Paper: score and error positively rank-correlated. {mt}: ρ = {_f(rho)}, "
                   f"p = {_f(p)} — {'agrees' if rho > 0 and p < 0.05 else 'disagrees (no significant positive correlation)'}.")
    return out


def dense_table(dataset: Path, cls: str = "cat", n_points: int = 400) -> str:
    """Dense extension methods compared on one pair (null shape -> next shape), FPS landmarks."""
    from shapecond.matching.evaluation import class_shapes
    from shapecond.matching.metrics import errors_from_rows, normalise
    from shapecond.matching.pipeline import match_surfaces
    from shapecond.matching.sampled import sample_surface
    from shapecond.shapes.io import load_geometry
    from shapecond.shapes.metric import metric_shape

    paths = class_shapes(Path(dataset) / cls)
    src_g, tgt_g = load_geometry(paths[0]), load_geometry(paths[1])
    src, tgt = sample_surface(src_g, n_points), sample_surface(tgt_g, n_points)
    shape = metric_shape(src_g, n_points)
    lm = [int(v) for v in shape.samples[:7]]
    rows = [f"### Dense extension, {paths[0].stem} -> {paths[1].stem} (FPS landmarks)", "",
            "| matcher | landmarks | sample map | dense: nearest sample | dense: local distances | seconds |",
            "|---|---|---|---|---|---|"]
    for matcher in ("lh05", "faq"):
        for c in (3, 7):
            e = {}
            for dense in ("nearest", "distances"):
                t0 = time.perf_counter()
                m = match_surfaces(src, tgt, lm[:c], lm[:c], matcher=matcher, dense=dense)
                sec = time.perf_counter() - t0
                e[dense] = normalise(errors_from_rows(tgt.rows, m.vertex_map[tgt.samples]),
                                     tgt.diameter).mean()
                e["sample"] = normalise(errors_from_rows(m.target.rows[m.sample_map.t],
                                                         m.source.samples), tgt.diameter).mean()
            rows.append(f"| {matcher} | {c} | {e['sample']:.2f} | {e['nearest']:.2f} | "
                        f"{e['distances']:.2f} | {sec:.1f} |")
    return "\n".join(rows)


def dense_scores(data: dict, dataset: Path, out: Path, effort: str = "quick") -> str:
    """σ with dense targets (M = 8N, DESIGN.md 1) for every landmark set of a run, and its
    rank correlation with the matching error: does it predict the error better than the
    bijection score of Figure 7a, which a two-sample swap dominates?  Cached in
    ``out/dense_scores.json`` (one dense metric shape per null shape, then ~5 s a score)."""
    from scipy.stats import spearmanr

    from shapecond.matching.evaluation import class_shapes
    from shapecond.shapes.io import load_geometry
    from shapecond.shapes.metric import metric_shape
    from shapecond.symmetry.search import witness_search

    st = data["settings"]
    path = out / "dense_scores.json"
    done = json.loads(path.read_text()) if path.exists() else {}
    by_cls = {}
    for d in data["landmarks"]:
        by_cls.setdefault(d["cls"], []).append(d)
    for cls, ds in by_cls.items():
        need = [(d, int(c)) for d in ds for c in d["scores"] if f"{cls}/{d['method']}/{c}" not in done]
        if not need:
            continue
        print(f"[dense scores] {cls}", file=sys.stderr, flush=True)
        g = load_geometry(class_shapes(Path(dataset) / cls)[0])
        shape = metric_shape(g, st["n_points"], backend=st["backend"], seed=st["seed"], target="dense")
        for d, c in need:
            idx = shape.landmark_indices(d["ids"][:c])
            r = witness_search(shape.D, shape.n_samples, [int(i) for i in idx], seed=st["seed"], effort=effort)
            done[f"{cls}/{d['method']}/{c}"] = "inf" if math.isinf(r.sigma) else r.sigma
            path.write_text(json.dumps(done, indent=1))
    scores, err = _tables(data)
    lines = [f"### Dense-target score against error (N = {st['n_points']}, M = 8N, {effort} search)", "",
             "The same landmark sets scored with dense targets (maps may send a sample to any of 8N "
             "points, so a swap of two neighbouring samples no longer dominates); cells are (class, "
             "method, 3 or all landmarks) as above.", "",
             "| matcher | ρ bijection score | ρ dense score | cells | mean within-class ρ, dense |",
             "|---|---|---|---|---|"]
    for mt in st["matchers"]:
        xb, xd, ys, per = [], [], [], {}
        for (cls, m, c, mm), e in err.items():
            key = f"{cls}/{m}/{c}"
            if mm != mt or key not in done:
                continue
            xb.append(scores.get((cls, m), {}).get(c, math.nan))
            xd.append(_num(done[key]))
            ys.append(e)
            per.setdefault(cls, []).append((_num(done[key]), e))
        rb = spearmanr(xb, ys) if len(ys) > 2 else None
        rd = spearmanr(xd, ys) if len(ys) > 2 else None
        within = [spearmanr(*zip(*v)).statistic for v in per.values()
                  if len(v) > 2 and len({a for a, _ in v}) > 1 and len({b for _, b in v}) > 1]
        lines.append(f"| {mt} | {_f(rb.statistic if rb else None)} (p = {_f(rb.pvalue if rb else None)}) | "
                     f"{_f(rd.statistic if rd else None)} (p = {_f(rd.pvalue if rd else None)}) | {len(ys)} | "
                     f"{_f(sum(within) / len(within) if within else None)} |")
    return "\n".join(lines)


def spread_table(data: dict, dataset: Path) -> str:
    """How spread out each method's landmarks are: the median geodesic distance from a
    landmark to its nearest other landmark, in diameters (1 = the shape's diameter), beside
    the sampling's covering radius r.  CNBS on the bijection score fixes swaps of adjacent
    samples once the mirror is broken, so its landmarks come in clusters of neighbours."""
    import numpy as np

    from shapecond.matching.evaluation import class_shapes
    from shapecond.shapes.io import load_geometry
    from shapecond.shapes.metric import metric_shape

    st = data["settings"]
    methods = st["methods"]
    lines = ["### Landmark spread (all landmarks, null shape)", "",
             "Median over landmarks of the geodesic distance to the nearest other landmark, in "
             "diameters; r = covering radius of the N samples.", "",
             "| class | L | r | " + " | ".join(methods) + " |", "|---|---|---|" + "---|" * len(methods)]
    sets = {(d["cls"], d["method"]): d["ids"] for d in data["landmarks"]}
    for cls in [c for c in PAPER_ORDER if c in st["classes"]] + [c for c in st["classes"] if c not in PAPER_ORDER]:
        g = load_geometry(class_shapes(Path(dataset) / cls)[0])
        shape = metric_shape(g, st["n_points"], backend=st["backend"], seed=st["seed"])
        cells = []
        for m in methods:
            idx = shape.landmark_indices(sets[(cls, m)])
            S = shape.D[np.ix_(idx, idx)].copy()
            np.fill_diagonal(S, np.inf)
            cells.append(f"{np.median(S.min(axis=1)):.3f}")
        r = shape.covering_radius
        lines.append(f"| {cls} | {len(sets[(cls, methods[0])])} | {_f(r)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", nargs="?")
    ap.add_argument("--from", dest="from_dir", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--classes", default=None)
    ap.add_argument("--methods", default="fps,pls,hks,cnbs")
    ap.add_argument("--out", default="evaluation")
    ap.add_argument("--dense-check", default=None, metavar="DATASET_DIR",
                    help="also compare the dense extension methods on cat0 -> cat1")
    ap.add_argument("--spread", default=None, metavar="DATASET_DIR",
                    help="also tabulate how clustered each method's landmarks are")
    ap.add_argument("--dense-scores", default=None, metavar="DATASET_DIR",
                    help="also score every landmark set with dense targets and correlate with the error")
    ap.add_argument("--note", default=None, help="a Markdown file appended to the section (analysis)")
    ap.add_argument("--no-write", action="store_true", help="print only; leave RESULTS.md alone")
    a = ap.parse_args()
    wall = None
    if a.from_dir:
        out = Path(a.from_dir)
    else:
        from shapecond.matching.evaluation import evaluate_dataset
        from shapecond.matching.report import write_report

        t0 = time.perf_counter()
        ev = evaluate_dataset(a.dataset, classes=a.classes.split(",") if a.classes else None,
                              methods=a.methods.split(","), n_jobs=a.jobs, quick=a.quick,
                              progress=sys.stderr.isatty())
        wall = time.perf_counter() - t0
        out = Path(a.out)
        write_report(ev, out)
    data = json.loads((out / "results.json").read_text())
    text = summarise(data, wall or sum(data["seconds"].values()))
    if a.note:
        text += "\n\n" + Path(a.note).read_text().strip()
    if a.spread:
        text += "\n\n" + spread_table(data, Path(a.spread))
    if a.dense_scores:
        text += "\n\n" + dense_scores(data, Path(a.dense_scores), out)
    if a.dense_check:
        text += "\n\n" + dense_table(Path(a.dense_check))
    print(text)
    if not a.no_write:
        write_section("evaluate", text)


if __name__ == "__main__":
    main()

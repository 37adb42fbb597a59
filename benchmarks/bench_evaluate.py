"""The paper's Figure 7 evaluation on TOSCA, timed, beside the paper's numbers and claims.

Usage:
    python benchmarks/bench_evaluate.py DATASET_DIR [--jobs 2] [--protocol both] [--out DIR]
    python benchmarks/bench_evaluate.py --from DIR [--dataset DATASET_DIR]   # summarise a run

Runs ``shapecond.evaluation.evaluate_dataset`` (the same as ``shapecond
evaluate``), writes the full report into --out, and puts a summary in
benchmarks/RESULTS.md (section ``evaluate``): time and load, the scores σ and δ(ε)
after 1/3/all landmarks, the mean errors per protocol and matcher beside the
paper's Figure 7b, LH05's candidate recall and objective against the true map,
Spearman's ρ between each score and the error, and every target of the κ-protocol
and scale-aware-score work checked.  With ``--dataset`` (or a fresh run) it also
tabulates the landmark spread, whether the first landmark is off the mirror plane,
and the distortion of the ground-truth maps themselves (the data's own floor).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, peak_rss_mb, write_section  # noqa: E402

PAPER_ORDER = ["horse", "victoria", "michael", "david", "dog", "centaur", "cat", "wolf"]
#: The paper's Figure 7b, LH05 with all landmarks: range over the landmark methods,
#: % of half the geodesic diameter (as quoted in the evaluation issue).
PAPER_LH05_ALL = {"horse": (0.61, 0.66), "victoria": (0.33, 0.39), "michael": (0.39, 0.42),
                  "david": (0.31, 0.58), "dog": (0.43, 0.47), "centaur": (0.51, 0.59),
                  "cat": (0.54, 0.56), "wolf": (0.21, 0.23)}
NEW = "cnbs-scale"


def _num(v):
    return math.inf if v == "inf" else (math.nan if v is None else float(v))


def _f(v, d=3):
    v = _num(v)
    return "inf" if math.isinf(v) else ("-" if math.isnan(v) else f"{v:.{d}g}")


def _mean(xs):
    xs = [x for x in xs if x is not None and not math.isnan(x)]
    return sum(xs) / len(xs) if xs else math.nan


def tables(data: dict):
    """scores σ, δ: {(class, method): {count: value}}; cells: {(protocol, class, method, count,
    matcher): {field: mean over targets}}."""
    sig = {(d["cls"], d["method"]): {int(k): _num(v) for k, v in d["scores"].items()} for d in data["landmarks"]}
    dlt = {(d["cls"], d["method"]): {int(k): _num(v) for k, v in d.get("scale", {}).items()}
           for d in data["landmarks"]}
    dlc = {(d["cls"], d["method"]): {int(k): _num(v) for k, v in d.get("scale_class", {}).items()}
           for d in data["landmarks"]}
    dlh = {(d["cls"], d["method"]): {int(k): _num(v) for k, v in d.get("scale_hat", {}).items()}
           for d in data["landmarks"]}
    acc = {}
    for r in data["records"]:
        key = (r.get("protocol", "independent"), r["cls"], r["method"], r["n_landmarks"], r["matcher"])
        for f in ("error", "exact", "recall", "objective_ratio", "seconds"):
            acc.setdefault(key, {}).setdefault(f, []).append(_num(r.get(f)))
    cells = {k: {f: _mean(v) for f, v in fs.items()} for k, fs in acc.items()}
    return sig, dlt, dlc, dlh, cells


def _classes(st):
    return [c for c in PAPER_ORDER if c in st["classes"]] + [c for c in st["classes"] if c not in PAPER_ORDER]


def summarise(data: dict, wall: float | None, peak: float | None = None) -> str:
    st = data["settings"]
    classes, methods, matchers = _classes(st), st["methods"], st["matchers"]
    prots = st.get("protocols", ["independent"])
    sig, dlt, dlc, dlh, cells = tables(data)
    L = st["landmark_counts"]
    lines = ["## Figure 7 evaluation on TOSCA", "",
             f"Machine: {machine()}; load average at the end {os.getloadavg()[0]:.1f}. Command: "
             f"`{command_line()}`, summarising `shapecond evaluate {st['dataset']} --classes "
             f"{','.join(st['classes'])} --methods {','.join(methods)} --protocol "
             f"{'both' if len(prots) > 1 else prots[0]} --jobs {st['n_jobs']}`.", "",
             f"N = {st['n_points']}, {st['backend']} geodesics, {sum(len(v) for v in st['targets'].values())} "
             f"targets. Wall time: " + (f"{wall / 60:.1f} min" if wall else "see the run") + "; phases (s): "
             + ", ".join(f"{k} {v:.0f}" for k, v in data["seconds"].items())
             + (f"; peak memory {peak:.0f} MB (largest process)" if peak else "") + ".", "",
             "Errors in % of half the target's geodesic diameter, averaged over the class's targets. "
             "*corresponding*: the target is sampled at the null shape's sample vertices, the error of a "
             "sample is the geodesic distance from its image to its own vertex (the κ setting); "
             "*independent*: each target has its own FPS samples, the dense map is measured at them.", ""]
    eps, eps_hat = st.get("class_epsilon") or {}, st.get("class_epsilon_hat") or {}
    for name, tab in (("σ (Eq. 5, quick search)", sig), ("δ(ε), ε = the sample spacing (quick search)", dlt),
                      ("δ(ε), ε = the class's deformation level: " + ", ".join(f"{c} {_f(eps[c])}" for c in
                                                                               _classes(st) if c in eps), dlc),
                      ("δ(ε), ε = ε̂, the class's level read off its matched maps (no ground truth): "
                       + ", ".join(f"{c} {_f(eps_hat[c])}" for c in _classes(st) if c in eps_hat), dlh)):
        if not any(tab.values()):
            continue
        lines += [f"### Score {name} after 1 / 3 / all landmarks (Figure 7a)", "",
                  "| class | L | " + " | ".join(methods) + " |", "|---|---|" + "---|" * len(methods)]
        for c in classes:
            lines.append(f"| {c} | {L[c]} | " + " | ".join(
                " / ".join(_f(v) for _, v in sorted(tab.get((c, m), {}).items())) for m in methods) + " |")
        lines.append("")
    for prot in prots:
        for mt in matchers:
            paper = prot == "corresponding" and mt == "lh05"
            lines += [f"### Mean error with 3 / all landmarks, {prot} samples, {mt} (Figure 7b)", "",
                      "| class | " + " | ".join(methods) + (" | paper LH05, all |" if paper else " |"),
                      "|---|" + "---|" * (len(methods) + (1 if paper else 0))]
            for c in classes:
                k3 = min(3, L[c])
                row = [f"{_f(cells.get((prot, c, m, k3, mt), {}).get('error'))} / "
                       f"{_f(cells.get((prot, c, m, L[c], mt), {}).get('error'))}" for m in methods]
                extra = ""
                if paper:
                    lo, hi = PAPER_LH05_ALL.get(c, (math.nan, math.nan))
                    extra = f" | {lo:g}–{hi:g}"
                lines.append(f"| {c} | " + " | ".join(row) + extra + " |")
            means = [f"{_f(_mean([cells.get((prot, c, m, min(3, L[c]), mt), {}).get('error') for c in classes]))} / "
                     f"{_f(_mean([cells.get((prot, c, m, L[c], mt), {}).get('error') for c in classes]))}"
                     for m in methods]
            lines.append("| **mean** | " + " | ".join(means) + (" | |" if paper else " |"))
            cor = data.get("correlation_by_protocol", {}).get(prot, data["correlation"]).get(mt, {})
            sc, scc, sch = cor.get("scale", {}), cor.get("scale_class", {}), cor.get("scale_hat", {})
            bars = cor.get("bars", {})
            lines += ["", f"Spearman ρ(score, error), {mt}, {cor.get('n')} (class, method, count) cells: "
                      f"σ: {_f(cor.get('rho'))} (p = {_f(cor.get('p'))}), within classes "
                      f"{_f(cor.get('within_class'))}; δ(ε = spacing): {_f(sc.get('rho'))} (p = {_f(sc.get('p'))}), "
                      f"within classes {_f(sc.get('within_class'))}; δ(ε = class): {_f(scc.get('rho'))} "
                      f"(p = {_f(scc.get('p'))}), within classes {_f(scc.get('within_class'))}; δ(ε = ε̂): "
                      f"{_f(sch.get('rho'))} (p = {_f(sch.get('p'))}), within classes {_f(sch.get('within_class'))}.",
                      "", f"Error bars ({mt}, {bars.get('n', 0)} matchings; bar and error in sqrt(area)): held "
                      f"{_f(bars.get('held'))}, median bar / error {_f(bars.get('median_ratio'))}, ρ(bar, error) "
                      f"{_f(bars.get('rho'))} pooled, {_f(bars.get('within_class'))} within classes.", ""]
    lines += ["### Checks", ""] + checks(classes, methods, matchers, prots, sig, cells, L, data)
    return "\n".join(lines)


def checks(classes, methods, matchers, prots, sig, cells, L, data) -> list[str]:
    """Every measurable target of the κ-protocol, LH05 and scale-aware-score work."""
    out = []
    prot = "corresponding" if "corresponding" in prots else prots[0]

    def err(c, m, k, mt, field="error"):
        return cells.get((prot, c, m, k, mt), {}).get(field, math.nan)

    def cls_mean(c, k_of, mt, field="error"):
        return _mean([err(c, m, k_of(c), mt, field) for m in methods])

    allk, k3 = (lambda c: L[c]), (lambda c: min(3, L[c]))
    if "lh05" in matchers and prot == "corresponding":
        ok = [c for c in classes if c in PAPER_LH05_ALL and cls_mean(c, allk, "lh05") <= 1.5 * PAPER_LH05_ALL[c][1]]
        out.append(f"- LH05, all landmarks, class mean within 1.5x the paper's Figure 7b (upper end): "
                   f"{len(ok)} of {len(classes)} ({', '.join(ok) or 'none'}); target >= 6.")
        if "faq" in matchers:
            a = _mean([cls_mean(c, allk, "lh05") for c in classes] + [cls_mean(c, k3, "lh05") for c in classes])
            b = _mean([cls_mean(c, allk, "faq") for c in classes] + [cls_mean(c, k3, "faq") for c in classes])
            out.append(f"- Mean over classes, methods and counts: LH05 {_f(a)} %, FAQ {_f(b)} % "
                       f"(ratio {_f(a / b if b else math.nan)}; target <= 1.2).")
        rs = [r for r in data["records"] if r.get("protocol") == prot and r["matcher"] == "lh05"]
        ratios = [_num(r.get("objective_ratio")) for r in rs]
        below = [r for r in rs if _num(r.get("objective_ratio")) < 1 - 1e-9]
        out.append(f"- LH05's objective over the true map's: min {_f(min(ratios, default=math.nan), 6)}, "
                   f"below 1 in {len(below)} of {len(rs)} matchings"
                   + (f" (worst: {', '.join(sorted({r['target'] for r in sorted(below, key=lambda r: _num(r['objective_ratio']))[:4]}))})"
                      if below else "") + "; target: never.")
        rec = {c: _mean([err(c, m, k3(c), "lh05", "recall") for m in methods]) for c in classes}
        out.append("- LH05 candidate recall with 3 landmarks (class mean over methods): "
                   + ", ".join(f"{c} {_f(v)}" for c, v in rec.items())
                   + f"; min {_f(min(rec.values(), default=math.nan))} (target >= 0.95).")
    for mt in matchers:
        worse = [(c, m, err(c, m, L[c], mt) / err(c, m, k3(c), mt)) for c in classes for m in methods
                 if err(c, m, k3(c), mt) > 0 and err(c, m, L[c], mt) > 1.05 * err(c, m, k3(c), mt)]
        out.append(f"- {mt}: cells where all landmarks err more than 1.05x the first 3: {len(worse)} of "
                   f"{len(classes) * len(methods)}" + (" (" + ", ".join(f"{c}/{m} x{_f(q)}" for c, m, q in worse)
                                                      + ")" if worse else "") + ".")
    if "cnbs" in methods and "fps" in methods:
        for mt in matchers:
            le = [c for c in classes if err(c, "cnbs", k3(c), mt) <= err(c, "fps", k3(c), mt)]
            out.append(f"- Paper: with 3 landmarks CNBS error at or below FPS on >= 6 of 8 classes. {mt}: "
                       f"{len(le)} of {len(classes)} ({', '.join(le) or 'none'}).")
    if NEW in methods:
        for mt in matchers:
            beats = [c for c in classes if all(err(c, NEW, k3(c), mt) <= err(c, b, k3(c), mt) for b in ("fps", "pls")
                                               if b in methods)]
            avg3 = {m: _mean([err(c, m, k3(c), mt) for c in classes]) for m in methods}
            avgL = {m: _mean([err(c, m, L[c], mt) for c in classes]) for m in methods}
            best3, bestL = min(avg3, key=avg3.get), min(avgL, key=avgL.get)
            out.append(f"- {NEW}, {mt}, 3 landmarks: at or below FPS and PLS on {len(beats)} of {len(classes)} "
                       f"({', '.join(beats) or 'none'}; target >= 6); mean over classes {_f(avg3[NEW])} "
                       f"(lowest: {best3} {_f(avg3[best3])}); all landmarks {_f(avgL[NEW])} vs best {bestL} "
                       f"{_f(avgL[bestL])} (x{_f(avgL[NEW] / avgL[bestL] if avgL[bestL] else math.nan)}; "
                       f"target <= 1.1).")
        for mt in matchers:
            cor = data.get("correlation_by_protocol", {}).get(prot, data["correlation"]).get(mt, {})
            for key, name in (("scale", "ε = the sample spacing"), ("scale_class", "ε = the class's level")):
                sc = cor.get(key, {})
                out.append(f"- δ({name}) predicts the error ({mt}): ρ = {_f(sc.get('rho'))}, p = {_f(sc.get('p'))} "
                           f"(target ρ >= 0.6, p < 0.01); mean within-class ρ {_f(sc.get('within_class'))}.")
    return out


def geometry_tables(data: dict, dataset: Path) -> str:
    """Landmark spread, first landmark against the mirror plane, and the ground truth's own distortion."""
    import numpy as np

    from shapecond.evaluation.datasets import read_class
    from shapecond.matching.sampled import sample_surface, surface_at
    from shapecond.shapes.io import load_geometry, read_symmetry_map
    from shapecond.api import metric_shape

    st = data["settings"]
    methods = st["methods"]
    sets = {(d["cls"], d["method"]): d["ids"] for d in data["landmarks"]}
    spread = ["### Landmark spread (all landmarks, null shape)", "",
              "Median over landmarks of the geodesic distance to the nearest other landmark, in covering "
              "radii r of the N samples (r in diameters). `†` marks a first landmark within 2r of its mirror "
              "image (on the mirror plane, where it leaves the mirror map feasible; classes with a `.sym` map).", "",
              "| class | L | r | " + " | ".join(methods) + " |", "|---|---|---|" + "---|" * len(methods)]
    gt = ["### The ground truth's own distortion (corresponding samples)", "",
          "Distortion of the true map between the null shape's N samples and the same vertices of each "
          "target: RMS over pairs in sample spacings h (the default ε of δ), and the median relative "
          "distortion |D − D̃| / D.  Where the true map distorts more, a distortion-minimising matcher "
          "may prefer a wrong map.", "",
          "| class | targets | RMS / h (median, max) | median relative |", "|---|---|---|---|"]
    for cls in _classes(st):
        paths = list(read_class(Path(dataset) / cls).shapes)
        g = load_geometry(paths[0])
        shape = metric_shape(g, st["n_points"], backend=st["backend"], seed=st["seed"], target="samples")
        r = shape.covering_radius
        sym = None
        sym_file = Path(dataset) / "symmetries" / f"{cls}.sym"
        if sym_file.exists():
            sym = g.with_symmetry(read_symmetry_map(sym_file)).symmetry
        cells = []
        for m in methods:
            idx = shape.landmark_indices(sets[(cls, m)])
            S = shape.D[np.ix_(idx, idx)].copy()
            np.fill_diagonal(S, np.inf)
            mark = ""
            if sym is not None:
                v = int(shape.samples[idx[0]])
                src = sample_surface(g, st["n_points"], st["backend"], st["seed"])
                row = np.flatnonzero(src.samples == v)
                d = (src.rows[row[0], sym[v]] / src.rows.max()) if row.size else math.nan
                mark = " †" if d < 2 * r else ""
            cells.append(f"{np.median(S.min(axis=1)) / r:.1f}{mark}")
        spread.append(f"| {cls} | {len(sets[(cls, methods[0])])} | {_f(r)} | " + " | ".join(cells) + " |")
        null = sample_surface(g, st["n_points"], st["backend"], st["seed"])
        Ds = null.D
        h = np.median((Ds + np.diag(np.full(len(Ds), np.inf))).min(axis=1))
        iu = np.triu_indices(len(Ds), 1)
        rms, rel = [], []
        for p in paths[1:]:
            if p.stem not in st["targets"][cls]:
                continue
            t = surface_at(load_geometry(p), null.samples, st["backend"])
            E = np.abs(Ds - t.D)[iu]
            rms.append(float(np.sqrt(np.mean(E ** 2))) / h)
            rel.append(float(np.median(E / np.maximum(Ds[iu], h))))
        gt.append(f"| {cls} | {len(rms)} | {np.median(rms):.2f}, {max(rms):.2f} | {np.median(rel):.3f} |")
    return "\n".join(spread) + "\n\n" + "\n".join(gt)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", nargs="?")
    ap.add_argument("--from", dest="from_dir", default=None)
    ap.add_argument("--dataset", dest="dataset_opt", default=None,
                    help="with --from: the dataset, for the spread and ground-truth tables")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--classes", default=None)
    ap.add_argument("--methods", default="fps,pls,hks,cnbs,cnbs-scale")
    ap.add_argument("--protocol", default="corresponding", choices=["corresponding", "independent", "both"])
    ap.add_argument("--matchers", default="lh05,faq")
    ap.add_argument("--max-targets", type=int, default=None)
    ap.add_argument("--section", default="evaluate", help="the RESULTS.md section to write")
    ap.add_argument("--out", default="evaluation")
    ap.add_argument("--note", default=None, help="a Markdown file appended to the section (analysis)")
    ap.add_argument("--no-write", action="store_true", help="print only; leave RESULTS.md alone")
    a = ap.parse_args()
    wall = peak = None
    dataset = a.dataset or a.dataset_opt
    if a.from_dir:
        out = Path(a.from_dir)
        timing = out / "bench_timing.json"  # the timed run's wall time and peak memory
        if timing.exists():
            wall, peak = json.loads(timing.read_text()).values()
    else:
        from shapecond.evaluation import EvaluationOptions, evaluate_dataset
        from shapecond.evaluation.report import write_report

        t0 = time.perf_counter()
        ev = evaluate_dataset(a.dataset, options=EvaluationOptions(classes=a.classes.split(",") if a.classes else None, methods=a.methods.split(","), n_jobs=a.jobs, quick=a.quick, progress=sys.stderr.isatty(), protocol=a.protocol, matchers=a.matchers.split(","), max_targets=a.max_targets))
        wall = time.perf_counter() - t0
        peak = peak_rss_mb()
        out = Path(a.out)
        write_report(ev, out)
        (out / "bench_timing.json").write_text(json.dumps({"wall": wall, "peak": peak}))
    data = json.loads((out / "results.json").read_text())
    text = summarise(data, wall, peak)
    if a.note:
        text += "\n\n" + Path(a.note).read_text().strip()
    if dataset:
        text += "\n\n" + geometry_tables(data, Path(dataset))
    print(text)
    if not a.no_write:
        write_section(a.section, text)


if __name__ == "__main__":
    main()

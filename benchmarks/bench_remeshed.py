"""The paper's Figure 7 where users live: differently meshed shapes, dense maps, a functional-map peer.

Usage:
    python benchmarks/make_remeshed.py ../shared/data/tosca_hires --out DATA     # once (cache folder)
    python benchmarks/bench_remeshed.py DATA [--jobs 2] [--counts 3,6] [--max-targets T] [--out DIR] [--no-peer]
    python benchmarks/bench_remeshed.py DATA --from DIR                          # summarise a run

1. ``shapecond.evaluate`` (the remeshed protocol, chosen by the ``corres/``
   folders) in a fresh interpreter with an empty cache: landmarks of every
   method on each class's null shape, every matcher with 3, 6 and all of them,
   errors at the ``.vts`` reference points in units of sqrt(area); wall and CPU
   time of the whole process tree, and the load.
2. The peer, in the same run: pyFM (``pip install pyfmaps``, benchmark-only)
   functional maps fed the same landmark pairs, with the settings of pyFM's README
   example (WKS descriptors with the landmarks, every 5th kept, 35 eigenfunctions,
   weights descr 1, Laplacian 1e-2, descriptor commutativity 1e-1, no orientation
   term), refined by 15 ZoomOut steps of 1; its error is measured by the same
   function (``evaluation.protocols.reference_errors``).
3. ``benchmarks/RESULTS.md``, section ``remeshed``: mean error per class, method,
   count and matcher beside the peer; the checks of the remeshed issue.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import OUT, command_line, machine, run_variant, write_section  # noqa: E402

PAPER_ORDER = ["horse", "victoria", "michael", "david", "dog", "centaur", "cat", "wolf"]
PEER = "pyfm"


def evaluate_code(dataset: Path, out: Path, a) -> str:
    classes = tuple(a.classes.split(",")) if a.classes else None
    return (f"import shapecond as sc\nfrom shapecond.evaluation.report import write_report\n"
            f"ev = sc.evaluate({str(dataset)!r}, classes={classes!r}, methods={tuple(a.methods.split(','))!r}, "
            f"matchers={tuple(a.matchers.split(','))!r}, counts={tuple(int(c) for c in a.counts.split(','))!r}, "
            f"n_jobs={a.jobs}, n_points={a.points}, max_targets={a.max_targets!r}, force=True"
            f"{', error_bars=False' if a.no_bars else ''})\nwrite_report(ev, {str(out)!r})\n")


def peer_task(cls_dir: str, target: str, sets: dict, counts: list) -> list:
    """pyFM with the landmark pairs of every method and count on one target (module docstring)."""
    import warnings

    from pyFM.functional import FunctionalMapping
    from pyFM.mesh import TriMesh

    from shapecond.evaluation.datasets import read_class
    from shapecond.evaluation.protocols import _reference_ids, landmark_images, reference_errors
    from shapecond.matching.sampled import CachedSolver, surface_unit
    from shapecond.shapes.io import load_geometry

    warnings.filterwarnings("ignore")
    cls = read_class(cls_dir)
    tp = next(p for p in cls.targets if p.stem == target)
    null, g = load_geometry(cls.null), load_geometry(tp)
    ref_s, ref_t = _reference_ids(cls, cls.null, null), _reference_ids(cls, tp, g)
    m_t = TriMesh(np.asarray(g.vertices), np.asarray(g.faces)).process(200)   # pyFM's mesh1: the target
    m_s = TriMesh(np.asarray(null.vertices), np.asarray(null.faces)).process(200)
    solver = CachedSolver(null)
    maps, seconds = {}, {}
    for method, lm in sets.items():
        images = landmark_images(lm, ref_s, ref_t, solver)
        for c in counts:
            c = min(c, len(lm))
            t0 = time.process_time()
            model = FunctionalMapping(m_t, m_s)
            model.preprocess(n_descr=100, descr_type="WKS", landmarks=np.column_stack([images[:c], lm[:c]]),
                             subsample_step=5, k_process=200)
            model.fit(K=(35, 35), w_descr=1e0, w_lap=1e-2, w_dcomm=1e-1, w_orient=0)
            p2p = model.get_p2p(FM=model.zoomout_refine(nit=15, step=1))   # source vertex -> target vertex
            maps[(method, c)], seconds[(method, c)] = p2p[ref_s], time.process_time() - t0
    raw, diameter, _ = reference_errors(g, ref_t, maps, "heat")
    unit = surface_unit(g, diameter)
    return [dict(cls=cls.name, target=target, method=m, n_landmarks=c, matcher=PEER,
                 error_area=float(e.mean() / unit), error=float(100 * e.mean() / (0.5 * diameter)),
                 cpu=seconds[(m, c)]) for (m, c), e in raw.items()]


def run_peer(dataset: Path, results: dict, counts: list, jobs: int) -> list:
    from joblib import Parallel, delayed

    sets = {}
    for d in results["landmarks"]:
        sets.setdefault(d["cls"], {})[d["method"]] = d["vertices"]
    tasks = [(str(dataset / cls), t, sets[cls], sorted(set(counts) | {results["settings"]["landmark_counts"][cls]}))
             for cls, targets in results["settings"]["targets"].items() for t in targets]
    out = Parallel(n_jobs=jobs)(delayed(peer_task)(*t) for t in tasks)
    return [r for rows in out for r in rows]


def _f(v, d=2):
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{1000 * v:.{d}f}"


def _rho(v):
    return "-" if v is None or math.isnan(v) else f"{v:.2f}"


def _mean(xs):
    xs = [x for x in xs if x is not None and not math.isnan(x)]
    return sum(xs) / len(xs) if xs else math.nan


def cells(records) -> dict:
    """(cls, method, n_landmarks, matcher) -> mean error / sqrt(area) over the targets."""
    acc = {}
    for r in records:
        acc.setdefault((r["cls"], r["method"], r["n_landmarks"], r["matcher"]), []).append(r["error_area"])
    return {k: _mean(v) for k, v in acc.items()}


def summarise(results: dict, peer: list, timing: dict) -> str:
    st = results["settings"]
    recs = [r for r in results["records"] if r["protocol"] == "remeshed"]
    allc = cells(recs + peer)
    classes = [c for c in PAPER_ORDER if c in st["classes"]] + [c for c in st["classes"] if c not in PAPER_ORDER]
    matchers = st["matchers"] + ([PEER] if peer else [])
    lines = [f"Machine: {machine()}. Command: `{command_line()}`.", "",
             f"Evaluation (cold cache, {st['n_jobs']} jobs): {timing['wall'] / 60:.1f} min wall, "
             f"{timing['cpu'] / 60:.1f} min CPU of the process tree, load average {timing['load']:.1f} at the start; "
             f"peer: {timing.get('peer_wall', 0) / 60:.1f} min wall.", "",
             "Errors: mean over the reference points of the target's geodesic distance between the image and the "
             "true vertex / sqrt(target area), **× 10⁻³**, mean over the targets of each class.", ""]
    lines += _table(allc, classes, st, matchers)
    lines += _checks(allc, recs, peer, classes, st)
    lines += _bars(recs, st)
    lines += _levels(results, st)
    return "\n".join(lines)


def _levels(results: dict, st) -> list:
    """Spearman ρ between δ and the mean error over (class, method, count) cells, δ at the sample spacing
    and at each class's level read off its matched maps (``evaluation.report.correlations``)."""
    cor = results.get("correlation_by_protocol", {}).get("remeshed") or results.get("correlation", {})
    eps = st.get("class_epsilon_hat") or {}
    if not eps:
        return []
    out = ["", "δ(ε) at each class's level read off its matched maps (ε̂ = the median RMS distortion of the class's "
           "maps, no ground truth; diameters): " + ", ".join(f"{c} {v:.4f}" for c, v in eps.items()) + ". Spearman ρ "
           "between δ and the mean error over (class, method, count) cells, pooled / mean within class:", "",
           "| matcher | δ(ε = sample spacing) | δ(ε = ε̂ of the class) |", "|---|---|---|"]
    for m in st["matchers"]:
        sc, sh = cor.get(m, {}).get("scale", {}), cor.get(m, {}).get("scale_hat", {})
        out.append(f"| {m} | {_rho(sc.get('rho'))} / {_rho(sc.get('within_class'))} | "
                   f"{_rho(sh.get('rho'))} / {_rho(sh.get('within_class'))} |")
    return out


def _bars(recs, st) -> list:
    """The error bars' calibration (``evaluation.report.bar_calibration``) per matcher, when recorded."""
    from types import SimpleNamespace

    from shapecond.evaluation.report import bar_calibration

    rows = [SimpleNamespace(**{**r, "bar": _num(r.get("bar")), "error_area": _num(r.get("error_area"))}) for r in recs]
    if not any(math.isfinite(r.bar) for r in rows):
        return []
    out = ["", "Error bars without ground truth (the mean displacement of the witness of δ(ε̂) on the null shape's "
           "first 200 samples with the landmarks, at least their resolution h/2; ε̂ the map's own RMS distortion; bar "
           "and mean error in sqrt(area)): held = share of matchings whose error is at most their bar "
           "(target ≥ 0.9), ratio = median bar / error (target ≤ 5), ρ = Spearman between bar and error, pooled "
           "and the mean within classes (targets ≥ 0.6 and ≥ 0.4).", "",
           "| matcher | matchings | held | median bar / error | ρ pooled | ρ within class | median ε̂ | median bar |",
           "|---|---|---|---|---|---|---|---|"]
    for m in st["matchers"]:
        mine = [r for r in rows if r.matcher == m]
        b = bar_calibration(mine)
        eps = [r.epsilon_hat for r in mine if r.epsilon_hat is not None]
        bars = [r.bar for r in mine if math.isfinite(r.bar)]
        out.append(f"| {m} | {b['n']} | {b['held']:.2f} | {b['median_ratio']:.2f} | {b['rho']:.2f} | "
                   f"{b['within_class']:.2f} | {_f(float(np.median(eps)) if eps else None)} | "
                   f"{_f(float(np.median(bars)) if bars else None)} |")
    return out + ["", "(ε̂ and bar columns × 10⁻³.)"]


def _num(v) -> float:
    return math.nan if v is None or isinstance(v, str) else float(v)


def _counts(st, cls):
    L = st["landmark_counts"][cls]
    return sorted({min(c, L) for c in st["counts"]} | {L})


def _table(allc, classes, st, matchers) -> list:
    out = []
    for cls in classes:
        cnt = _counts(st, cls)
        out += [f"**{cls}** (counts {' / '.join(map(str, cnt))})", "",
                "| method | " + " | ".join(matchers) + " |", "|---|" + "---|" * len(matchers)]
        for m in st["methods"]:
            out.append(f"| {m} | " + " | ".join(" / ".join(_f(allc.get((cls, m, c, mt))) for c in cnt)
                                                 for mt in matchers) + " |")
        out.append("")
    return out


def _checks(allc, recs, peer, classes, st) -> list:
    ours = [m for m in st["matchers"]]
    out = ["Checks of the remeshed issue:", ""]
    if peer and 6 in st["counts"]:
        best = {m: _mean([allc.get((c, meth, min(6, st["landmark_counts"][c]), m)) for c in classes
                          for meth in st["methods"]]) for m in ours}
        bm = min(best, key=best.get)
        pv = _mean([allc.get((c, meth, min(6, st["landmark_counts"][c]), PEER)) for c in classes
                    for meth in st["methods"]])
        out.append(f"- 6 landmarks, mean over classes and methods: best matcher {bm} {_f(best[bm])} against the "
                   f"peer's {_f(pv)}: ratio {best[bm] / pv:.2f} (target ≤ 0.5); every matcher: "
                   + ", ".join(f"{m} {_f(v)}" for m, v in best.items()))
    worst = {c: max(min(allc.get((c, meth, st["landmark_counts"][c], m), math.inf) for m in ours)
                    for meth in st["methods"]) for c in classes}
    out.append("- all landmarks, best matcher per method, worst method per class (target ≤ 15): "
               + ", ".join(f"{c} {_f(v)}" for c, v in worst.items()))
    three = [r for r in recs if r["n_landmarks"] == min(3, st["landmark_counts"][r["cls"]])]
    flips = sum(1 for r in three if r.get("flipped") == 1.0)
    known = sum(1 for r in three if r.get("flipped") is not None and not math.isnan(r.get("flipped")))
    out.append(f"- 3 landmarks: {flips} flipped of {known} matchings with a reference symmetry (target 0)")
    worse = []
    for (c, meth, n, m), v in allc.items():
        if m in ours and n == st["landmark_counts"][c] and n > 3:
            v3 = allc.get((c, meth, min(3, n), m))
            if v3 is not None and v > 1.05 * v3:
                worse.append(f"{c}/{meth}/{m} {_f(v3)} → {_f(v)}")
    out.append(f"- all landmarks worse than 1.05 × 3 landmarks: {len(worse)} cells"
               + (": " + "; ".join(worse) if worse else ""))
    for m in ours:
        wins = 0
        for c in classes:
            e = {meth: allc.get((c, meth, min(3, st["landmark_counts"][c]), m), math.inf) for meth in st["methods"]}
            if "cnbs-scale" in e and e["cnbs-scale"] <= min(e.get("fps", math.inf), e.get("pls", math.inf)):
                wins += 1
        out.append(f"- 3 landmarks, {m}: CNBS-scale at or below FPS and PLS on {wins} of {len(classes)} classes "
                   "(target ≥ 6 of 8)")
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dataset", type=Path, help="remeshed dataset (make_remeshed.py's output)")
    ap.add_argument("--classes", default=",".join(PAPER_ORDER))
    ap.add_argument("--methods", default="fps,pls,hks,cnbs,cnbs-scale")
    ap.add_argument("--matchers", default="lh05,faq,zoomout")
    ap.add_argument("--counts", default="3,6")
    ap.add_argument("--points", type=int, default=400)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--max-targets", type=int, default=None, help="at most this many targets per class")
    ap.add_argument("--out", type=Path, default=OUT / "remeshed")
    ap.add_argument("--from", dest="from_dir", type=Path, default=None)
    ap.add_argument("--no-peer", action="store_true")
    ap.add_argument("--no-bars", action="store_true", help="no error bars (a δ search per matching)")
    ap.add_argument("--section", default="remeshed", help="RESULTS.md section to write (a partial run: another name)")
    a = ap.parse_args(argv)
    out = a.from_dir or a.out
    if a.from_dir is None:
        with tempfile.TemporaryDirectory() as cache:
            r = run_variant(evaluate_code(a.dataset, out, a), cache=Path(cache))
        timing = dict(wall=r["wall"], cpu=r["tree_cpu"], load=r["load"])
        results = json.loads((out / "results.json").read_text())
        peer = []
        if not a.no_peer:
            t0 = time.perf_counter()
            peer = run_peer(a.dataset, results, [int(c) for c in a.counts.split(",")], a.jobs)
            timing["peer_wall"] = time.perf_counter() - t0
        (out / "bench.json").write_text(json.dumps(dict(timing=timing, peer=peer)))
    bench = json.loads((out / "bench.json").read_text())
    results = json.loads((out / "results.json").read_text())
    text = summarise(results, bench["peer"], bench["timing"])
    write_section(a.section, "## Figure 7 on remeshed TOSCA: dense maps between differently meshed shapes "
                  f"(bench_remeshed.py{'' if a.section == 'remeshed' else ', ' + a.section})\n\n" + text)
    print(text)


if __name__ == "__main__":
    main()

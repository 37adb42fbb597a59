"""Markdown report and PNG plots of an evaluation (paper Figure 7a/7b).

Tables: the symmetry score after 1, 3 and all landmarks per class and method
(Figure 7a); the mean dense matching error per class, method, matcher and
landmark count (Figure 7b, % of half the target's geodesic diameter, and the
Princeton normalisation by sqrt(area)); for each class, whether the method
with the lowest score also has the lowest error; and Spearman's rank
correlation between score and error over all (class, method, landmark count)
cells, per matcher (the paper's claim: a lower score predicts easier matching,
i.e. a positive correlation).  Plots: cumulative error curves per class and
score against error.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from shapecond.errors import InputError
from shapecond.evaluation.datasets import find_classes
from shapecond.jsonable import dumps, fmt
from shapecond.matching.metrics import cumulative_curve
from shapecond.output import staged_outputs, write_text

THRESHOLDS = np.linspace(0.0, 50.0, 101)  # % of half the geodesic diameter
#: The field's curve: fraction of reference points within a geodesic error of x sqrt(area) (Kim et al. 2011).
AREA_THRESHOLDS = np.linspace(0.0, 0.25, 101)
#: A matching erring more than this (sqrt(area)) has failed (off-isometry targets, issue tables).
FAILED = 0.05
#: Per-class curve panels are drawn up to this many classes (a pairs list makes a group per source).
MAX_PANELS = 16


def protocols(ev) -> list:
    """The protocols of an evaluation's records, in the settings' order."""
    return list(ev.settings.get("protocols") or ["independent"])


def by_protocol(ev, protocol):
    """The same evaluation restricted to the records of one protocol."""
    return replace(ev, records=[r for r in ev.records if getattr(r, "protocol", "independent") == protocol])


def mean_errors(records, key="error"):
    """{(cls, method, n_landmarks, matcher): mean over targets of the per-target mean}."""
    acc = defaultdict(list)
    for r in records:
        acc[(r.cls, r.method, r.n_landmarks, r.matcher)].append(getattr(r, key))
    return {k: float(np.mean(v)) for k, v in acc.items()}


def score_table(landmarks, key="scores"):
    """{(cls, method): {count: score}} (``key="floor"``: the best-single-swap floor)."""
    return {(d["cls"], d["method"]): {int(c): s for c, s in d.get(key, {}).items()}
            for d in landmarks}


def _cells(ev, matcher, cls=None, key="scores"):
    scores = score_table(ev.landmarks, key)
    xs, ys = [], []
    for (c_, method, c, m), e in mean_errors(ev.records).items():
        s = scores.get((c_, method), {}).get(c)
        if m == matcher and s is not None and (cls is None or c_ == cls):
            xs.append(1e12 if math.isinf(s) else s)
            ys.append(e)
    return xs, ys


def correlation(ev, matcher, key="scores"):
    """Spearman ρ (and p) between score and mean error over (class, method, count) cells.

    ``key``: "scores" (σ, Eq. 5) or "scale" (δ(ε), ``shapecond.symmetry.scale``).

    Pooled over classes, so differences between classes count too (a class
    with higher scores and higher errors raises ρ); see ``within_class``.
    """
    xs, ys = _cells(ev, matcher, key=key)
    if len(xs) < 3 or len(set(xs)) < 2 or len(set(ys)) < 2:
        return math.nan, math.nan, len(xs)
    res = spearmanr(xs, ys)
    return float(res.statistic), float(res.pvalue), len(xs)


def within_class(ev, matcher, key="scores"):
    """Mean over classes of Spearman ρ computed inside each class (NaN-free classes only)."""
    rhos = []
    for cls in ev.settings["classes"]:
        xs, ys = _cells(ev, matcher, cls, key)
        if len(xs) >= 3 and len(set(xs)) > 1 and len(set(ys)) > 1:
            rhos.append(float(spearmanr(xs, ys).statistic))
    return (float(np.mean(rhos)) if rhos else math.nan), len(rhos)


def _at_floor(score, floor):
    return score is not None and floor is not None and math.isfinite(score) and \
        abs(score - floor) <= 1e-9 * max(1.0, abs(floor))


def _fmt(v, d=3):
    return fmt(v, d)


def markdown(ev, plots=()) -> str:
    """The report text (see module docstring)."""
    st = ev.settings
    methods, matchers, classes = st["methods"], st["matchers"], st["classes"]
    scores = score_table(ev.landmarks)
    out = ["# Landmark evaluation (paper Section 7, Figure 7)", "",
           f"Dataset `{st['dataset']}`; N = {st['n_points']} samples, {st['backend']} geodesics, "
           f"seed {st['seed']}{', quick mode' if st['quick'] else ''}. "
           + (f"The {len(st['pairs'])} listed pairs, grouped by source (a row per source). " if st.get("pairs")
              else "Null shape matched to every other shape of its class. ")
           + "Protocols: "
           "*corresponding* — shapes with one vertex order, the target's samples are the null shape's "
           "sample vertices (the κ setting; error of sample x = geodesic distance from T(x) to x's own "
           "vertex), errors in % of half the target's geodesic diameter (paper); "
           "*independent* — each target has its own FPS samples and the dense map is measured "
           "at them; *remeshed* — every shape has its own mesh and `.vts` ground truth, the dense map "
           f"({st.get('dense', 'zoomout')}) is measured at the reference points in the field's unit, "
           "geodesic error / sqrt(target area).", "",
           "Timings (s): " + ", ".join(f"{k} {v:.0f}" for k, v in ev.seconds.items()), ""]
    floors = score_table(ev.landmarks, "floor")
    out += ["## Symmetry score after 1, 3 and all landmarks (Figure 7a)", "",
            "σ lower bounds with the landmarks fixed, every method scored by the same quick witness "
            "search (CNBS's own heat-map values are not used, so one estimator is compared). `*` marks a value equal to the best single swap "
            "avoiding the landmarks (the floor): there the score does not see the landmarks.", "",
            ] + _score_rows(st, scores, floors)
    scale = score_table(ev.landmarks, "scale")
    if any(scale.values()):
        out += ["", "## Scale-aware score δ(ε) after 1, 3 and all landmarks", "",
                "RMS displacement of the widest self-map whose distortion (and that of every landmark's "
                "distance row) stays within ε = the median sample spacing; quick search, the same for "
                "every method.", ""] + _score_rows(st, scale)
    at_class = score_table(ev.landmarks, "scale_class")
    if any(at_class.values()):
        eps = st.get("class_epsilon", {})
        out += ["", "## δ(ε) at each class's own deformation level", "",
                "ε = the median RMS distortion of the class's ground-truth maps (corresponding samples): "
                + ", ".join(f"{c} {_fmt(v)}" for c, v in eps.items()) + " (diameters).", ""]
        out += _score_rows(st, at_class)
    at_hat = score_table(ev.landmarks, "scale_hat")
    if any(at_hat.values()):
        eps = st.get("class_epsilon_hat", {})
        out += ["", "## δ(ε) at each class's level read off its matched maps (no ground truth)", "",
                "ε = the median RMS distortion ε̂ of the maps the matchers found for the class "
                "(`matching.error_bar`): " + ", ".join(f"{c} {_fmt(v)}" for c, v in eps.items()) + " (diameters).", ""]
        out += _score_rows(st, at_hat)
    for prot in protocols(ev):
        sub = by_protocol(ev, prot)
        if prot == "remeshed":
            out += _pooled_section(sub)
        out += _error_sections(sub, prot, scores)
    out += ["", "## Landmarks (null shape, file vertex ids)", ""]
    for d in sorted(ev.landmarks, key=lambda d: (d["cls"], d["method"])):
        out.append(f"- {d['cls']} {d['method']} ({d['seconds']:.1f} s): {d['ids']}")
    if plots:
        out += ["", "## Plots", ""] + [f"![{Path(p).stem}]({Path(p).name})" for p in plots]
    return "\n".join(out) + "\n"


def _score_rows(st, table, floors=None) -> list[str]:
    """A Figure 7a table: the score after 1, 3 and all landmarks per class and method; with
    ``floors``, ``*`` marks a value equal to the best single swap avoiding the landmarks."""
    methods = st["methods"]
    out = ["| class | L | " + " | ".join(f"{m} 1 / 3 / L" for m in methods) + " |",
           "|---|---|" + "---|" * len(methods)]
    for cls in st["classes"]:
        cells = []
        for m in methods:
            sc, fl = table.get((cls, m), {}), (floors or {}).get((cls, m), {})
            cells.append(" / ".join(_fmt(sc.get(c)) + ("*" if _at_floor(sc.get(c), fl.get(c)) else "")
                                    for c in sorted(sc)))
        out.append(f"| {cls} | {st['landmark_counts'][cls]} | " + " | ".join(cells) + " |")
    return out


def pooled(records) -> dict:
    """{(method, n_landmarks, matcher): summary over every matching} in units of sqrt(area): mean,
    median and worst error, matchings, failed (error > ``FAILED``), flipped, the share held by its
    error bar (NaN without bars) and the failed matchings with a bar, and held, as (held, of)."""
    acc = defaultdict(list)
    for r in records:
        acc[(r.method, r.n_landmarks, r.matcher)].append(r)
    out = {}
    for k, rs in acc.items():
        e = np.array([r.error_area for r in rs])
        flips = [r.flipped for r in rs if np.isfinite(r.flipped)]
        held = [r.error_area <= r.bar for r in rs if np.isfinite(r.bar)]
        failed_held = [r.error_area <= r.bar for r in rs if np.isfinite(r.bar) and r.error_area > FAILED]
        out[k] = dict(n=len(rs), mean=float(np.mean(e)), median=float(np.median(e)), worst=float(np.max(e)),
                      failed=int(np.sum(e > FAILED)), flipped=int(np.sum(flips)) if flips else None,
                      held=float(np.mean(held)) if held else math.nan,
                      failed_held=(int(np.sum(failed_held)), len(failed_held)))
    return out


def _pooled_section(ev) -> list[str]:
    """Every matching of the remeshed protocol pooled (the field's tables: a mean over the pairs)."""
    table = pooled(ev.records)
    out = ["", "## All matchings pooled, remeshed protocol (geodesic error / sqrt(area))", "",
           f"Mean, median and worst over the matchings; failed: error > {FAILED}; flipped: mean error over half "
           "the mean mirror distance (where the ground truth has mirror images); held: the share of matchings "
           "whose error bar is at least the error (and of the failed ones).", "",
           "| method | L | matcher | matchings | mean | median | worst | failed | flipped | held | failed held |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for (m, c, matcher), d in sorted(table.items()):
        out.append(f"| {m} | {c} | {matcher} | {d['n']} | {_fmt(d['mean'], 4)} | {_fmt(d['median'], 4)} | "
                   f"{_fmt(d['worst'], 4)} | {d['failed']} | {'-' if d['flipped'] is None else d['flipped']} | "
                   f"{_fmt(d['held'])} | {d['failed_held'][0]} of {d['failed_held'][1]} |")
    return out


def _error_sections(ev, protocol, scores) -> list[str]:
    """Figure 7b tables, correlations and the other error measures of one protocol."""
    st = ev.settings
    methods, classes = st["methods"], st["classes"]
    key = "error_area" if protocol == "remeshed" else "error"
    errs = mean_errors(ev.records, key)
    unit = "geodesic error / sqrt(area)" if key == "error_area" else "% of half the geodesic diameter"
    extra = [f"{c} / L" if c != 3 else "3 / L" for c in st.get("counts", [3])]
    out = []
    for matcher in st["matchers"]:
        out += ["", f"## Mean error, {protocol} protocol, matcher {matcher} (Figure 7b; {unit})", "",
                "| class | " + " | ".join(f"{m} {' / '.join(str(c) for c in st.get('counts', [3]))} / L"
                                         for m in methods) + " | best at 3 | lowest score at 3 |",
                "|---|" + "---|" * (len(methods) + 2)]
        for cls in classes:
            L = st["landmark_counts"][cls]
            cnt = sorted({min(c, L) for c in st.get("counts", [3])} | {L})
            cells, at3, sc3 = [], {}, {}
            for m in methods:
                vals = [errs.get((cls, m, c, matcher)) for c in cnt]
                cells.append(" / ".join(_fmt(v, 2 if key == "error_area" else 3) for v in vals))
                at3[m] = vals[0]
                sc3[m] = scores.get((cls, m), {}).get(cnt[0])
            best = min((v, m) for m, v in at3.items() if v is not None)[1] if any(
                v is not None for v in at3.values()) else "-"
            low = min((v, m) for m, v in sc3.items() if v is not None)[1] if any(
                v is not None for v in sc3.values()) else "-"
            out.append(f"| {cls} | " + " | ".join(cells) + f" | {best} | {low} |")
        for key, name in (("scores", "σ"), ("scale", "δ(ε = sample spacing)"),
                          ("scale_class", "δ(ε = the class's deformation level)"),
                          ("scale_hat", "δ(ε = ε̂, the level read off the matched maps)")):
            rho, p, n = correlation(ev, matcher, key)
            rw, nw = within_class(ev, matcher, key)
            out += ["", f"Spearman rank correlation between the score {name} and error ({matcher}, {n} "
                    f"class/method/count cells): ρ = {_fmt(rho)}, p = {_fmt(p)}; within classes "
                    f"(mean of per-class ρ over {nw} classes): {_fmt(rw)}."]
    out += ["", f"## Error bars without ground truth, {protocol} protocol", "",
            "Each matching's bar is the mean displacement of the witness of δ(ε̂) on the null shape with its "
            "landmarks, ε̂ the RMS distortion of the map itself (`matching.error_bar`); both bar and mean error "
            "in units of sqrt(area). Held: the share of "
            "matchings whose error is at most their bar; ratio: the median of bar / error; ρ: Spearman between "
            "bar and error over the matchings, pooled and within classes.", "",
            "| matcher | matchings | held | median bar / error | ρ pooled | ρ within class |", "|---|---|---|---|---|---|"]
    for matcher in st["matchers"]:
        b = bar_calibration([r for r in ev.records if r.matcher == matcher])
        out.append(f"| {matcher} | {b['n']} | {_fmt(b['held'])} | {_fmt(b['median_ratio'])} | {_fmt(b['rho'])} | "
                   f"{_fmt(b['within_class'])} |")
    cols = ("error_area", "sample_error", "exact", "recall", "objective_ratio", "flipped", "epsilon_hat", "bar")
    tables = {c: mean_errors(ev.records, c) for c in cols}
    pct = mean_errors(ev.records, "error")
    out += ["", f"## Other measures, {protocol} protocol", "",
            "Means over the targets: error / sqrt(area); the sample map's own error; the fraction "
            "of samples mapped exactly, the recall of LH05's candidates and LH05's objective over "
            "the true map's (corresponding samples only); the fraction of targets matched flipped "
            "(remeshed classes with a reference symmetry).", "",
            "| class | method | matcher | L | % half diam. | / sqrt(area) | sample map % | exact | "
            "recall | objective / truth | flipped | ε̂ | bar |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for cell in sorted(pct):
        cls, m, c, matcher = cell
        out.append(f"| {cls} | {m} | {matcher} | {c} | {_fmt(pct[cell])} | "
                   + " | ".join(_fmt(tables[col].get(cell), 4 if col == "objective_ratio" else 3)
                                for col in cols) + " |")
    return out


def plot(ev, out_dir) -> list[Path]:
    """Per protocol: cumulative error curves (one panel per class) and score-vs-error scatter, as PNGs."""
    return [p for prot in protocols(ev) for p in _plot(by_protocol(ev, prot), prot, out_dir)]


def _plot(ev, protocol, out_dir) -> list[Path]:
    """One protocol's cumulative error curves and score-vs-error scatter.

    Figures are built without pyplot (``viz.render.new_figure``), so the caller's
    matplotlib backend is never changed; each PNG is written atomically.
    """
    from shapecond.viz.render import new_figure, save_figure

    out_dir = Path(out_dir)
    paths = []
    st = ev.settings
    if protocol == "remeshed":
        paths.append(_field_curves(ev, out_dir))
    for matcher in st["matchers"]:
        classes = st["classes"]
        if len(classes) > MAX_PANELS:
            continue
        cols = min(4, len(classes))
        rows = math.ceil(len(classes) / cols)
        fig = new_figure(figsize=(4 * cols, 3.2 * rows))
        axes = fig.subplots(rows, cols, squeeze=False)
        for ax, cls in zip(axes.ravel(), classes):
            by = defaultdict(list)
            for r in ev.records:
                if r.cls == cls and r.matcher == matcher:
                    by[(r.method, r.n_landmarks)].append(r.errors)
            # the range where the curves differ: up to the 99th percentile of the class's errors
            every = np.concatenate([e for errs in by.values() for e in errs]) if by else np.zeros(1)
            top = max(1.0, float(np.quantile(every, 0.99)))
            x = THRESHOLDS[THRESHOLDS <= top] if top >= 5.0 else np.linspace(0.0, top, 101)
            low = 1.0
            for (m, c), errs in sorted(by.items()):
                y = cumulative_curve(np.concatenate(errs), x)
                low = min(low, float(y[0]))
                ax.plot(x, y, label=f"{m} {c}", linestyle="-" if c <= 3 else "--")
            ax.set_title(cls)
            ax.set_xlabel("error, % of half diameter")
            ax.set_ylim(max(0.0, low - 0.05), 1.005)
            ax.legend(fontsize=6)
        for ax in axes.ravel()[len(classes):]:
            ax.axis("off")
        fig.suptitle(f"{protocol} samples, {matcher}: fraction of samples with error below x")
        fig.tight_layout(rect=(0, 0, 1, 0.96))
        p = out_dir / f"error_curves_{protocol}_{matcher}.png"
        save_figure(fig, p, dpi=90, bbox_inches=None)
        paths.append(p)
    scores = score_table(ev.landmarks)
    errs = mean_errors(ev.records)
    points = {}
    for matcher in st["matchers"]:
        for m in st["methods"]:
            for (cls, mm, c, mt), e in errs.items():
                s = scores.get((cls, mm), {}).get(c)
                if mm == m and mt == matcher and s is not None and math.isfinite(s) and s > 0:
                    points.setdefault((m, matcher), []).append((s, e))
    if not points:  # no scores (``scores=False``): no axis to put the errors against
        return paths
    fig = new_figure(figsize=(5, 4))
    ax = fig.subplots()
    for matcher, marker in zip(st["matchers"], "os^"):
        for m in st["methods"]:
            xy = np.array(points.get((m, matcher), np.zeros((0, 2))))
            ax.scatter(xy[:, 0], xy[:, 1], marker=marker, label=f"{m} ({matcher})", s=18)
    ax.set_xscale("log")
    ax.set_xlabel("symmetry score σ with the landmarks fixed")
    ax.set_ylabel("mean error, % of half diameter")
    ax.legend(fontsize=6)
    fig.tight_layout()
    ax.set_title(f"{protocol} samples")
    p = out_dir / f"score_vs_error_{protocol}.png"
    save_figure(fig, p, dpi=90, bbox_inches=None)
    return paths + [p]


def _field_curves(ev, out_dir) -> Path:
    """The field's curve pooled over every matching: one panel per matcher, one curve per landmark
    method and count, the fraction of reference points within x sqrt(area), x in 0–0.25."""
    from shapecond.viz.render import new_figure, save_figure

    matchers = ev.settings["matchers"]
    fig = new_figure(figsize=(4.2 * len(matchers), 3.4))
    axes = fig.subplots(1, len(matchers), squeeze=False)[0]
    for ax, matcher in zip(axes, matchers):
        by = defaultdict(list)
        for r in ev.records:  # the per-point errors are kept in % of half the diameter: rescale
            if r.matcher == matcher and r.error > 0 and np.isfinite(r.error_area):
                by[(r.method, r.n_landmarks)].append(r.errors * (r.error_area / r.error))
        for (m, c), errs in sorted(by.items()):
            ax.plot(AREA_THRESHOLDS, cumulative_curve(np.concatenate(errs), AREA_THRESHOLDS),
                    label=f"{m} {c}", linestyle="-" if c <= 3 else "--")
        ax.set_title(matcher)
        ax.set_xlabel("geodesic error / sqrt(area)")
        ax.set_ylim(0.0, 1.005)
        ax.legend(fontsize=6)
    axes[0].set_ylabel("fraction of reference points")
    fig.tight_layout()
    p = Path(out_dir) / "field_curves_remeshed.png"
    save_figure(fig, p, dpi=90, bbox_inches=None)
    return p


def correlations(ev) -> dict:
    """{matcher: {rho, p, n, within_class, scale: {...}, scale_class: {...}, scale_hat: {...}, bars: {...}}}:
    ``correlation`` and ``within_class`` of σ, of δ(ε) at the sample spacing (``scale``), at each
    class's own deformation level (``scale_class``) and at the level read off its matched maps
    (``scale_hat``), and the calibration of the per-matching error
    bars (``bar_calibration``)."""
    out = {}
    for m in ev.settings["matchers"]:
        out[m] = dict(zip(("rho", "p", "n"), correlation(ev, m)), within_class=within_class(ev, m)[0])
        for key in ("scale", "scale_class", "scale_hat"):
            out[m][key] = dict(zip(("rho", "p", "n"), correlation(ev, m, key)),
                               within_class=within_class(ev, m, key)[0])
        out[m]["bars"] = bar_calibration([r for r in ev.records if r.matcher == m])
    return out


def bar_calibration(records) -> dict:
    """How the error bars (the mean displacement of δ(ε̂)'s witness) hold the errors (both in units of
    sqrt(area)), over records with both.

    ``held``: fraction of matchings whose error is at most their bar; ``median_ratio``: median of
    bar / error; ``rho``: Spearman's ρ between bar and error over the matchings, and
    ``within_class``: the mean of the per-class ρ.
    """
    rs = [r for r in records if np.isfinite(r.bar) and np.isfinite(r.error_area) and r.error_area > 0]
    if not rs:
        return dict(n=0, held=math.nan, median_ratio=math.nan, rho=math.nan, within_class=math.nan)
    bar, err = np.array([r.bar for r in rs]), np.array([r.error_area for r in rs])
    rho = float(spearmanr(bar, err).statistic) if len(rs) >= 3 and np.ptp(bar) > 0 and np.ptp(err) > 0 else math.nan
    per = []
    for cls in sorted({r.cls for r in rs}):
        b = [r.bar for r in rs if r.cls == cls]
        e = [r.error_area for r in rs if r.cls == cls]
        if len(b) >= 3 and np.ptp(b) > 0 and np.ptp(e) > 0:
            per.append(float(spearmanr(b, e).statistic))
    return dict(n=len(rs), held=float(np.mean(err <= bar)), median_ratio=float(np.median(bar / err)), rho=rho,
                within_class=float(np.mean(per)) if per else math.nan)


def null_shapes(ev) -> dict:
    """Class -> path of its null shape, None for a class whose folder cannot be read any more."""
    if "nulls" in ev.settings:  # written by the run (a pairs list's groups are not class folders)
        return {c: (Path(p) if Path(p).is_file() else None) for c, p in ev.settings["nulls"].items()}
    try:
        found = find_classes(Path(ev.settings["dataset"]), ev.settings["classes"])
    except (InputError, OSError, KeyError):
        found = {}
    return {c: (found[c].null if c in found else None) for c in ev.settings["classes"]}


def write_report(ev, out_dir) -> Path:
    """Write report.md, report.html (``viz.pages.evaluation_page``), results.json and the PNGs into
    ``out_dir``; return the report path.

    The files appear together (``output.staged_outputs``): a run killed while writing them leaves
    the folder's previous report, results and plots as they were, never the new results beside an
    earlier run's report.  A figure or page that fails still leaves the new results.json (and what
    was written before it failed) in place before the error propagates.
    """
    from shapecond.viz.pages import write_evaluation_html

    out_dir = Path(out_dir)
    data = dict(ev.to_dict(), correlation=correlations(by_protocol(ev, protocols(ev)[0])),
                correlation_by_protocol={p: correlations(by_protocol(ev, p)) for p in protocols(ev)})
    with staged_outputs(out_dir, publish_on_error=True) as stage:  # the numbers outlive a failing figure
        write_text(stage / "results.json", dumps(data, indent=1))
        plots = plot(ev, stage)
        write_text(stage / "report.md", markdown(ev, plots))
        write_evaluation_html(ev, stage, markdown(ev, plots), null_shapes(ev))
    return out_dir / "report.md"

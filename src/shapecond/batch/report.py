"""``report.html`` of a batch matched to a template: which maps to trust and where to annotate more.

Written beside the table after every ``--what match:TEMPLATE`` run, from the
batch's rows (those already in the table included): the shapes sorted by their
error bar, a histogram of the bars, the shapes whose bar says "annotate more"
(bar above ``api.collection.ANNOTATE_MORE`` = 0.05 sqrt(area), the mean geodesic
error at which the shape-correspondence literature counts a map as failed) with
the suggested next landmark, and the shapes that failed.  One self-contained
file (the histogram is an inline PNG), written atomically.
"""

from __future__ import annotations

import base64
import html
import io
import math
import os
from pathlib import Path

#: The report's file name, beside the table.
REPORT_NAME = "report.html"

_STYLE = ("body{font-family:sans-serif;margin:2em;max-width:70em}table{border-collapse:collapse}"
          "td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}td:first-child{text-align:left}"
          ".bad{background:#fde0dc}")


def _num(v, digits=3) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return f"{v:.{digits}g}" if isinstance(v, float) else str(v)


def _histogram(bars, threshold) -> str:
    """An ``<img>`` of the histogram of the bars (empty without matplotlib or bars)."""
    if not bars:
        return ""
    try:
        from ..viz.render import new_figure
    except ImportError:  # pragma: no cover - matplotlib is a dependency
        return ""
    fig = new_figure((6.0, 3.0))
    ax = fig.add_subplot(1, 1, 1)
    ax.hist(bars, bins=min(30, max(5, len(bars))), color="#4477aa")
    ax.axvline(threshold, color="#cc3311", linestyle="--", label=f"annotate more (> {threshold:g})")
    ax.set_xlabel("error bar (sqrt(area) of the template)")
    ax.set_ylabel("shapes")
    ax.legend()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<p><img alt="histogram of the error bars" src="data:image/png;base64,{data}"></p>'


def _table(header, rows, bad=()) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join(f'<tr{" class=bad" if k in bad else ""}>' + "".join(f"<td>{html.escape(str(c))}</td>" for c in r)
                   + "</tr>" for k, r in enumerate(rows))
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def report_html(rows: list[dict]) -> str:
    """The report page of the batch rows ``rows`` (module docstring)."""
    from ..api.collection import ANNOTATE_MORE

    ok = sorted((r for r in rows if r["error"] is None and r["bar"] is not None), key=lambda r: (r["bar"], r["file"]))
    failed = [r for r in rows if r["error"] is not None]
    more = [r for r in ok if r["bar"] > ANNOTATE_MORE]
    template = next((r["match_template"] for r in rows if r.get("match_template")), None)
    name = {r["file"]: Path(r["file"]).stem for r in rows}
    out = [(f"<p>Template {html.escape(str(template or '?'))} matched to {len(rows)} shapes (direction: template to "
            f"shape; every map gives the shape's vertex id of each template vertex id): {len(ok)} matched, "
            f"{len(more)} of them say <b>annotate more</b>, {len(failed)} failed.</p>"),
           ("<p>The bar is the mean error a map that fits the landmarks and distorts distances no more than this one "
            "may have, in units of the template's sqrt(area) (it held the true error in 92 % of held-out pairs). "
            f"Above {ANNOTATE_MORE:g} sqrt(area), where the shape-correspondence literature counts a map as "
            "failed, the report says annotate more.</p>"),
           _histogram([r["bar"] for r in ok], ANNOTATE_MORE), "<h2>Annotate more</h2>"]
    out.append(_table(["shape", "bar", "pairs", "next landmark: template vertex", "its provisional image",
                       "bar after"],
                      [[name[r["file"]], _num(r["bar"]), r["landmark_pairs"], _num(r["suggest_source_id"]),
                        _num(r["suggest_image_id"]), _num(r["suggest_bar_after"])] for r in more])
               if more else "<p>No shape: every map's bar is below the threshold.</p>")
    out.append("<h2>Every shape, by its bar</h2>")
    out.append(_table(["shape", "bar", "ε", "ε̂", "pairs", "labels", "map", "seconds"],
                      [[name[r["file"]], _num(r["bar"]), _num(r["bar_epsilon"]), _num(r["bar_epsilon_hat"]),
                        r["landmark_pairs"], r["landmark_labels"] or "", os.path.basename(r["map_file"] or ""),
                        _num(r["seconds"], 2)] for r in ok],
                      bad={k for k, r in enumerate(ok) if r["bar"] > ANNOTATE_MORE}))
    if failed:
        out.append("<h2>Failed</h2>")
        out.append(_table(["shape", "error"], [[name[r["file"]], r["error"]] for r in failed]))
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>shapecond batch: matched to "
            f"a template</title><style>{_STYLE}</style></head><body><h1>Matched to a template</h1>\n"
            + "\n".join(out) + "\n</body></html>\n")


def write_report(out, rows: list[dict]) -> Path:
    """Write ``report.html`` beside the table ``out`` (atomically); return its path."""
    from ..output import write_text

    return write_text(Path(out).absolute().parent / REPORT_NAME, report_html(rows))

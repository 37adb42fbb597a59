"""``report.html`` of a matched batch: which maps to trust and where to annotate more.

Written beside the table after every ``--what match:TEMPLATE`` (or ``--pairs``) run, from the
batch's rows (those already in the table included): the maps sorted by their
error bar with their cycle error beside it (maps matched both ways), a
histogram of the bars, the maps whose bar says "annotate more" (bar above
``api.collection.ANNOTATE_MORE`` = 0.05 sqrt(area), the mean geodesic error at
which the shape-correspondence literature counts a map as failed), the largest
bar first, with the suggested next landmark, and the maps that failed.  Each map
that has its compact view (``views/NAME.json``, ``matches.read_view``) is shown
with it: a small turnable picture of its target coloured by the transfer or by
the error bar's doubt (``viz.mapview``), all drawn by one renderer.  The views
of a report are kept under ``MAX_VIEW_BYTES``: beyond it the views of the
"annotate more" list are kept first, then those of the largest bars, and the
report says how many were left out.  One self-contained file (the histogram is
an inline PNG, the viewer and three.js inlined once when there are views),
written atomically.
"""

from __future__ import annotations

import base64
import html
import io
import math
import os
from pathlib import Path

from ..api.collection import ANNOTATE_MORE
from ..output import write_text
from .matches import read_view

#: The report's file name, beside the table.
REPORT_NAME = "report.html"
#: The most bytes of view data a report embeds (about 48 kB a map: some 600 maps).
MAX_VIEW_BYTES = 30_000_000

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
    ax.set_xlabel("error bar (sqrt(area) of the map's source)")
    ax.set_ylabel("shapes")
    ax.legend()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<p><img alt="histogram of the error bars" src="data:image/png;base64,{data}"></p>'


class _Html(str):
    """A table cell that is HTML already (not escaped)."""


def _table(header, rows, bad=()) -> str:
    def cell(c):
        return c if isinstance(c, _Html) else html.escape(str(c))

    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join(f'<tr{" class=bad" if k in bad else ""}>' + "".join(f"<td>{cell(c)}</td>" for c in r)
                   + "</tr>" for k, r in enumerate(rows))
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _kept_views(ok, more, views: dict) -> tuple[dict, int]:
    """({index in ``ok``: payload} of the views the report embeds, how many were left out): all of them
    within ``MAX_VIEW_BYTES``, else the "annotate more" list's first (the largest bar first), then the
    other maps from the largest bar down, while they fit."""
    from ..viz.mapview import payload_json

    index = {id(r): k for k, r in enumerate(ok)}
    first = [index[id(r)] for r in more]
    rest = set(range(len(ok))) - set(first)
    order = first + sorted(rest, reverse=True)  # ``ok`` is sorted by bar
    have = [k for k in order if views.get(ok[k]["map_file"]) is not None]
    kept, total = {}, 0
    for k in have:
        size = len(payload_json(views[ok[k]["map_file"]]))
        if total + size > MAX_VIEW_BYTES:
            continue
        kept[k], total = views[ok[k]["map_file"]], total + size
    return dict(sorted(kept.items())), len(have) - len(kept)


def _views_note(kept: dict, left_out: int) -> str:
    """What the views show (and which were left out), for a report with views."""
    if not kept:
        return ""
    from ..viz.mapview import VIEW_VERTICES

    out = ("<p>Each view shows the map's target (the shape its source is mapped onto: from a template, the "
           "shape of the row), decimated to at most "
           f"{VIEW_VERTICES:,} vertices; drag it to turn it, double-click to turn it back. <b>transfer</b>: every "
           "vertex takes the colour of the source vertex mapped nearest to it, the source coloured by position: "
           "smooth where the map is right, a seam or a patch where it flips or collapses. <b>doubt</b>: the error "
           "bar's doubt of that source vertex (how far the widest map that fits the landmarks and distorts no "
           "more than this one moves it, from 0 to the map's largest doubt, in sqrt(area) of the source); the "
           "magenta diamond is the provisional image of the suggested next landmark.</p>")
    if left_out:
        out += (f"<p><b>{left_out} views left out</b> to keep the report under {MAX_VIEW_BYTES / 1e6:g} MB of "
                "view data: kept are those of the annotate-more list, then of the largest bars.</p>")
    return out


def _label(row) -> str:
    """A row's map as a person reads it: ``source → target`` (shape names), or the shape's name."""
    if row.get("match_source") and row.get("match_target"):
        return f"{Path(row['match_source']).stem} → {Path(row['match_target']).stem}"
    return Path(row["file"]).stem


def _intro(rows, ok, more, failed) -> str:
    template = next((r["match_template"] for r in rows if r.get("match_template")), None)
    if template is not None:
        ways = ("template to shape and shape to template" if any(r.get("match_direction") == "shape to template"
                                                                 for r in rows) else "template to shape")
        head = f"Template {html.escape(str(template))} matched to {len({r['file'] for r in rows})} shapes ({ways})"
    else:
        head = f"{len({r['file'] for r in rows})} shapes matched in listed pairs"
    return (f"<p>{head}: {len(rows)} maps (each map gives, for every vertex id of its source, the vertex id of "
            f"its image on the target), {len(ok)} matched, {len(more)} of them say <b>annotate more</b>, "
            f"{len(failed)} failed.</p>")


def annotate_more(rows) -> list[dict]:
    """The matched rows whose bar says "annotate more" (``api.collection.ANNOTATE_MORE``), the largest bar
    first (ties: by file)."""
    return sorted((r for r in rows if r["error"] is None and r["bar"] is not None and r["bar"] > ANNOTATE_MORE),
                  key=lambda r: (-r["bar"], r["file"]))


def collection_landmark(rows) -> dict | None:
    """The next landmark of the whole collection, or None: the template vertex suggested most often among the
    maps whose bar says annotate more (template to shape: their suggestions are template vertices), when two
    maps or more share it.  A new label there, annotated on the template and on every shape, gives each of
    those maps one more landmark pair.  Returns ``{"template_vertex", "maps", "listed"}``: the vertex, how
    many listed maps suggest it, and how many listed maps suggest a template vertex."""
    from collections import Counter

    ids = Counter(int(r["suggest_source_id"]) for r in annotate_more(rows)
                  if r.get("match_direction") == "template to shape" and r.get("suggest_source_id") is not None)
    if not ids or ids.most_common(1)[0][1] < 2:
        return None
    vertex, count = ids.most_common(1)[0]
    return {"template_vertex": vertex, "maps": count, "listed": sum(ids.values())}


def _collection_advice(rows) -> str:
    """``collection_landmark`` in words."""
    found = collection_landmark(rows)
    if found is None:
        return ""
    return (f"<p><b>One landmark for the collection:</b> template vertex {found['template_vertex']} is the next "
            f"landmark of {found['maps']} of the {found['listed']} maps listed (template to shape). A new label "
            "there, annotated on the template and on every shape (its provisional image on each is in the table), "
            "gives each map one more landmark pair.</p>")


def report_html(rows: list[dict], views: dict | None = None) -> str:
    """The report page of the batch rows ``rows`` (module docstring); ``views``: {map file: view payload}."""
    from ..viz.mapview import view_cell

    ok = sorted((r for r in rows if r["error"] is None and r["bar"] is not None),
                key=lambda r: (r["bar"], r["file"], _label(r)))
    failed = [r for r in rows if r["error"] is not None]
    more = annotate_more(ok)  # the most urgent first
    kept, left_out = _kept_views(ok, more, views or {})
    index = {id(r): k for k, r in enumerate(ok)}

    def view(r):
        k = index[id(r)]
        return [_Html(view_cell(k, _label(r)) if k in kept else "")] if kept else []

    out = [_intro(rows, ok, more, failed),
           ("<p>The bar is the mean error a map that fits the landmarks and distorts distances no more than this one "
            "may have, in units of the sqrt(area) of the map's source (it held the true error in 92 % of held-out "
            f"pairs). Above {ANNOTATE_MORE:g} sqrt(area), where the shape-correspondence literature counts a map as "
            "failed, the report says annotate more: the bar cannot certify such a map, which does not make it wrong "
            "(on two released benchmarks the bar averaged 7.5–9.4 times the true error). Where the maps were "
            "matched both ways, a large cycle beside a large bar is the likelier failure.</p>")]
    if any(r.get("cycle_error") is not None for r in ok):
        out.append("<p>The cycle (maps matched both ways) is a second signal beside the bar: the mean geodesic "
                   "distance between each sample of the source and its image under the map followed by the map "
                   "back (source → target → source), in sqrt(area) of the source; near 0 for a consistent pair "
                   "of maps.</p>")
    out += [_views_note(kept, left_out), _histogram([r["bar"] for r in ok], ANNOTATE_MORE), "<h2>Annotate more</h2>"]
    shown = ["view"] if kept else []
    out.append(_collection_advice(rows))
    out.append(_table(["map", *shown, "bar", "cycle", "pairs", "next landmark: source vertex",
                       "its provisional image", "bar after"],
                      [[_label(r), *view(r), _num(r["bar"]), _num(r.get("cycle_error")), r["landmark_pairs"],
                        _num(r["suggest_source_id"]), _num(r["suggest_image_id"]), _num(r["suggest_bar_after"])]
                       for r in more])
               if more else "<p>No shape: every map's bar is below the threshold.</p>")
    out.append("<h2>Every map, by its bar</h2>")
    out.append(_table(["map", *shown, "bar", "cycle", "ε", "ε̂", "pairs", "labels", "map file", "seconds"],
                      [[_label(r), *view(r), _num(r["bar"]), _num(r.get("cycle_error")), _num(r["bar_epsilon"]),
                        _num(r["bar_epsilon_hat"]), r["landmark_pairs"], r["landmark_labels"] or "",
                        os.path.basename(r["map_file"] or ""), _num(r["seconds"], 2)] for r in ok],
                      bad={k for k, r in enumerate(ok) if r["bar"] > ANNOTATE_MORE}))
    if failed:
        out.append("<h2>Failed</h2>")
        out.append(_table(["map", "error"], [[_label(r), r["error"]] for r in failed]))
    return _document(out, kept)


def _document(body: list[str], kept: dict) -> str:
    """The whole page: ``body``, and with views their data, the viewer's style and scripts."""
    head = tail = ""
    if kept:
        from ..viz.html import asset, viewer_scripts
        from ..viz.mapview import views_html

        head = f"<style>{asset('viewer.css')}</style>"
        tail = views_html(kept) + "\n" + "\n".join(viewer_scripts())
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>shapecond batch: matched "
            f"maps</title>{head}<style>{_STYLE}</style></head><body><h1>Matched maps</h1>\n"
            + "\n".join(b for b in body if b) + f"\n{tail}</body></html>\n")


def write_report(out, rows: list[dict]) -> Path:
    """Write ``report.html`` beside the table ``out`` (atomically), with the views of its maps
    (``matches.read_view``); return its path."""
    views = {r["map_file"]: read_view(r) for r in rows if r["error"] is None and r.get("map_file")}
    return write_text(Path(out).absolute().parent / REPORT_NAME, report_html(rows, views))

"""Small turnable views of matched maps, many to a page (the ``report.html`` of a matched batch).

``map_view`` turns one ``MatchResult`` into a compact payload, on the worker
that matched it: the map's **target** decimated for display (``html.decimate``,
the full pages' vertex clustering: each cluster drawn at one of its vertices),
stood upright (``scene.guess_up`` of the decimated shape), with two colourings
computed as the match page computes them (``pages``):

* **transfer**: each drawn vertex takes the position colour
  (``scene.position_colours``) of the source vertex whose image under the map
  lies nearest to it (``pages.transfer_sources``): where the map is right the
  source's colours carry over smoothly, a flip or a collapse shows as a seam;
* **doubt**: the error bar's doubt field (``MatchResult.doubt``, one
  computation, the match's own) of that same source vertex, in the match
  page's doubt colours (``pages.doubt_colouring``: turbo from 0 to the largest
  doubt on the source).

The payload is JSON (``payload_json``): positions quantised to uint16 on the
bounding box, faces as uint16 indices (uint32 above 65,535 vertices), colours
as uint8 RGB, each array in base64: about 48 kB for ``VIEW_VERTICES`` vertices
(a point cloud, drawn as points, about 24 kB).  The batch writes it beside the
map (``views/NAME.json``, atomically) with the key of the row it belongs to;
``views_html`` and ``view_cell`` put views in a page, drawn by the viewer
script's ``MapViews`` (one WebGL renderer for all of them, each view copied to
its own 2-D canvas when it scrolls into sight and while it is turned: a
browser keeps only about 16 live WebGL contexts).
"""

from __future__ import annotations

import base64
import html
import json

import numpy as np

from .html import _json, decimate
from .pages import doubt_colouring, internal_map, transfer_sources
from .scene import (AMBIENT, DEFAULT_VIEWS, DIFFUSE, Place, colour_layer, guess_up, make_scene, position_colours,
                    up_frame)

#: Vertices of a view (the target decimated to at most this many).
VIEW_VERTICES = 1500
#: Version of the payload's layout (the viewer script reads this one).
VIEW_FORMAT = 1
#: Quantisation levels of a coordinate (uint16).
_LEVELS = 65535


def _b64(a, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode("ascii")


def _rgb(rgba) -> str:
    return _b64(np.round(np.clip(np.asarray(rgba)[:, :3], 0.0, 1.0) * 255), np.uint8)


def _quantised(D: np.ndarray) -> tuple[list, list, str]:
    """(lower corner, step, base64 uint16 levels) of display coordinates ``D``."""
    lo, hi = D.min(axis=0), D.max(axis=0)
    step = np.where(hi > lo, (hi - lo) / _LEVELS, 1.0)
    q = np.clip(np.round((D - lo) / step), 0, _LEVELS)
    return [float(x) for x in lo], [float(x) for x in step], _b64(q, np.uint16)


def _decimated(tgt, max_vertices: int):
    """(kept target vertices (internal indices), their faces in the kept numbering or None)."""
    n = tgt.n_vertices
    scene = make_scene(tgt.vertices, tgt.faces, [], ids=np.arange(n), place=Place(None))
    shown, _ = decimate(scene, max_vertices)
    return np.asarray(shown.ids, dtype=np.int64), shown.faces


def map_view(result, max_vertices: int = VIEW_VERTICES) -> dict:
    """The compact view of a ``MatchResult`` between two surfaces (module docstring), JSON-ready.

    Parameters
    ----------
    result : a ``MatchResult`` of ``shapecond.match`` (its ``drawing``, ``map``, ``doubt`` and summary).
    max_vertices : the target is decimated to at most this many vertices.

    Returns
    -------
    dict: ``format``, ``n`` (vertices drawn), ``vertices`` (the target's), ``lo`` and ``step`` (positions
    are ``lo + step * level``), ``positions`` (uint16 levels, x y z per vertex), ``faces`` (None: a point
    cloud) and ``index`` ("uint16" or "uint32"), ``transfer`` and ``doubt`` (uint8 RGB per vertex; ``doubt``
    None without an error bar), ``doubt_scale`` (``lo``, ``hi``, ``label``, ``stops``), ``suggest`` (the
    display position of the first suggested landmark's provisional image on the target, or None),
    ``view`` (elevation, azimuth), ``shading``.  Deterministic.
    """
    src, tgt = result.drawing[:2]
    keep, faces = _decimated(tgt, max_vertices)
    carried = transfer_sources(tgt, internal_map(result), keep)
    V = np.asarray(tgt.vertices, float)[keep]
    up = guess_up(_Drawn(V, faces))
    centre, frame = V.mean(axis=0), up_frame(up, V)
    lo, step, positions = _quantised((V - centre) @ frame.T)
    transfer = position_colours(np.asarray(src.vertices, float))[carried]
    out = {"format": VIEW_FORMAT, "n": int(keep.size), "vertices": int(tgt.n_vertices), "lo": lo, "step": step,
           "positions": positions, "faces": None, "index": "uint16", "transfer": _rgb(transfer), "doubt": None,
           "doubt_scale": None, "suggest": None, "view": list(DEFAULT_VIEWS[0]), "shading": [AMBIENT, DIFFUSE]}
    if faces is not None:
        out["index"] = "uint16" if keep.size <= _LEVELS + 1 else "uint32"
        out["faces"] = _b64(faces, np.uint16 if out["index"] == "uint16" else np.uint32)
    if result.doubt is not None:
        doubt = np.asarray(result.doubt, float)[src.ids]  # per source vertex (internal index)
        colouring = doubt_colouring(doubt)
        shown = doubt[carried]
        out["doubt"] = _rgb(colour_layer(np.where(np.isfinite(shown), shown, 0.0), shown.size, colouring).rgba)
        bar = colour_layer(np.zeros(1), 1, colouring).colorbar
        out["doubt_scale"] = {"lo": bar.lo, "hi": bar.hi, "label": bar.label, "stops": bar.stops(9)}
    first = (result.summary.get("suggestions") or [None])[0]
    if first is not None and first.get("image_id") is not None:
        v = int(tgt.to_internal([first["image_id"]])[0])
        out["suggest"] = [float(x) for x in (np.asarray(tgt.vertices[v], float) - centre) @ frame.T]
    return out


class _Drawn:
    """A decimated shape as ``scene.guess_up`` reads it (``vertices``, ``faces``)."""

    def __init__(self, vertices, faces):
        self.vertices, self.faces = vertices, faces


def payload_json(view: dict) -> str:
    """A view as the text of its file (sorted keys, compact): the same view, the same bytes."""
    return json.dumps(view, sort_keys=True, separators=(",", ":"), allow_nan=False)


def views_html(views: dict) -> str:
    """The data of the views ``{key: payload}`` for a page (one ``script.sc-mapdata`` each; ``key`` is what
    ``view_cell`` names)."""
    return "".join(f'<script type="application/json" class="sc-mapdata" data-view="{html.escape(str(k))}">'
                   f"{_json(v)}</script>" for k, v in views.items())


def view_cell(key, title: str = "") -> str:
    """The place of one view in a page (its data given to ``views_html`` under ``key``)."""
    return (f'<div class="sc-mapview" data-view="{html.escape(str(key))}" '
            f'title="{html.escape(title)}"></div>')

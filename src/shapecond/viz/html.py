"""Self-contained HTML pages with 3-D viewers of shapecond's scenes (``viz.scene``).

A page is one file that opens offline in any current browser: the stylesheet,
the viewer script and the 3-D library are inlined, every scene's arrays are
embedded as base64 in a JSON block, and nothing is fetched (no ``http`` URL
in the file).  The viewer turns the shape (drag, wheel), jumps to the PNGs'
views, switches between the scene's colourings (heat map, witness, landmarks...)
and, on hover, reads out the vertex id (the input's own) and the value under
the pointer.  The scene is the render data the PNGs are drawn from
(``render.draw_scene``): the same colours, views, landmark styles and shading.

The 3-D library is three.js (version ``THREE_VERSION``, its unmodified
``build/three.module.min.js`` from the npm registry, MIT licence shipped beside
it as ``assets/three.LICENSE``).  Chosen on size and speed: 0.69 MB inlined, a
WebGL renderer that draws a 100k-face mesh in one call and picks a vertex under
the pointer in milliseconds, against ~3.5 MB for plotly.js (which alone would
use most of a page's size budget) with slower picking on large meshes.  The
release is the last one shipped as one self-contained minified module (later
ones split it in two files or ship no minified build); the page turns its
text into a module through a blob URL, so no server is needed.

Size.  A mesh costs about 45 bytes per vertex (positions, faces, ids) plus 4-10
per colouring; a mesh above ``MAX_DISPLAY_VERTICES`` vertices is decimated for
display by vertex clustering (``decimate``): each cluster is drawn at one of
its vertices, which keeps its id and values, and the page says so.
"""

from __future__ import annotations

import base64
import hashlib
import html
import json
from importlib import resources

import numpy as np

from ..errors import InputError
from .scene import AMBIENT, DIFFUSE, FACING, Scene, landmark_colour, view_label

#: three.js release inlined in every page, and the SHA-256 of its vendored file.
THREE_VERSION = "0.170.0"
THREE_SHA256 = "08fd7545d13d2c7fb65ab691530a802dafefd638596501854f267d0fb13c39e7"
#: Meshes with more vertices are decimated for display (a 50k-vertex page is about 3 MB).
MAX_DISPLAY_VERTICES = 50_000


def asset(name: str) -> str:
    """Text of a file shipped in ``shapecond/viz/assets``."""
    return resources.files("shapecond.viz").joinpath("assets", name).read_text(encoding="utf-8")


def three_source() -> str:
    """The vendored three.js module, checked against ``THREE_SHA256``."""
    text = asset("three.module.min.js")
    if hashlib.sha256(text.encode("utf-8")).hexdigest() != THREE_SHA256:
        raise RuntimeError("the vendored three.js differs from the release it claims to be")
    return text


def _b64(a, dtype) -> str | None:
    if a is None:
        return None
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode("ascii")


def _hex(rgb) -> str:
    return "#" + "".join(f"{int(round(255 * float(c))):02x}" for c in rgb[:3])


# --- decimation ---------------------------------------------------------------------------

def _clusters(V: np.ndarray, h: float):
    keys = np.floor((V - V.min(axis=0)) / h).astype(np.int64)
    size = keys.max(axis=0) + 1
    if np.prod(size.astype(float)) < 2.0 ** 62:  # one int64 per cell, in the order of the rows (ten times faster)
        keys = (keys[:, 0] * size[1] + keys[:, 1]) * size[2] + keys[:, 2]
        _, first, label = np.unique(keys, return_index=True, return_inverse=True)
    else:
        _, first, label = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return first, label.ravel()


def decimate(scene: Scene, max_vertices: int = MAX_DISPLAY_VERTICES) -> tuple[Scene, str | None]:
    """The scene with at most ``max_vertices`` vertices, and a note saying what was done (None: untouched).

    Vertex clustering on a grid (the cell found by bisection): each cluster is
    drawn at its lowest-index vertex, whose id and values it keeps; faces whose
    corners fall into fewer than three clusters are dropped.  Landmark markers keep
    their exact positions; segments are unchanged.
    """
    n = scene.n_vertices
    if n <= max_vertices:
        return scene, None
    V = scene.vertices
    lo, hi = 1e-9, float(np.ptp(V, axis=0).max()) or 1.0
    first, label = _clusters(V, hi)
    for _ in range(40):  # the largest grid cell at which the clusters still exceed the budget, then one step up
        mid = np.sqrt(lo * hi)
        f, lab = _clusters(V, mid)
        if len(f) > max_vertices:
            lo = mid
        else:
            hi, first, label = mid, f, lab
        if hi / lo < 1.01:
            break
    order = np.argsort(first, kind="stable")  # clusters numbered by their representative's index
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    rep, label = first[order], rank[label]
    faces = None
    if scene.faces is not None:
        F = label[scene.faces]
        F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
        faces = np.unique(np.sort(F, axis=1), axis=0, return_index=True)[1]
        faces = F[np.sort(faces)]
    layers = [_decimated_layer(lay, rep, label) for lay in scene.layers]
    partner = None if scene.partner is None else np.where(scene.partner[rep] >= 0, label[scene.partner[rep]], -1)
    parts = tuple((name, int(np.searchsorted(rep, a)), int(np.searchsorted(rep, b))) for name, a, b in scene.parts)
    from dataclasses import replace

    note = (f"display mesh decimated from {n:,} to {rep.size:,} vertices (vertex clustering); hover reads "
            "the id and values of the vertex each cluster is drawn at")
    out = replace(scene, vertices=V[rep], faces=faces, layers=tuple(layers), ids=scene.ids[rep],
                  partner=partner, parts=parts, normals=None if scene.normals is None else scene.normals[rep])
    return out, note


def _decimated_layer(layer, rep, label):
    from dataclasses import replace

    return replace(layer, rgba=layer.rgba[rep], values=None if layer.values is None else layer.values[rep],
                   landmarks=tuple(int(label[v]) for v in layer.landmarks))


# --- scene data and pages -------------------------------------------------------------------

def _landmarks_json(scene: Scene, full: Scene, layer, full_layer) -> list:
    """Markers of one layer: positions and normals from the undecimated scene ``full``."""
    out = []
    for i, (v, v0) in enumerate(zip(layer.landmarks, full_layer.landmarks)):
        rank = layer.rank(i)
        part = next((name + " " for name, a, b in full.parts if a <= v0 < b), "")
        out.append(dict(vertex=int(v), position=[float(x) for x in full.vertices[v0]],
                        normal=None if full.normals is None else [float(x) for x in full.normals[v0]],
                        colour=_hex(landmark_colour(rank)), label=str(rank + 1),
                        name=f"{part}vertex {int(full.ids[v0])}",
                        note=layer.notes[i] if i < len(layer.notes) else None))
    return out


def _suggestions_json(full: Scene) -> list:
    """Suggested points: positions, normals and ids from the undecimated scene, with their labels."""
    out = []
    for k, (v, label) in enumerate(full.suggestions):
        v = int(v)
        if not 0 <= v < full.n_vertices:
            raise InputError(f"suggested vertex index {v} out of range")
        part = next((name + " " for name, a, b in full.parts if a <= v < b), "")
        out.append(dict(position=[float(x) for x in full.vertices[v]], label=f"S{k + 1}", note=str(label or ""),
                        normal=None if full.normals is None else [float(x) for x in full.normals[v]],
                        name=f"{part}vertex {int(full.ids[v])}", id=int(full.ids[v])))
    return out


def scene_data(scene: Scene, max_vertices: int = MAX_DISPLAY_VERTICES) -> dict:
    """The JSON-ready data of one viewer (decimated beyond ``max_vertices``), deterministic."""
    shown, note = decimate(scene, max_vertices)
    layers = []
    for lay, full in zip(shown.layers, scene.layers):
        bar = lay.colorbar
        vals = None if lay.values is None else np.where(np.isfinite(lay.values), lay.values, np.inf)
        layers.append(dict(
            label=lay.label, colours=_b64(np.round(np.clip(lay.rgba[:, :3], 0, 1) * 255), np.uint8),
            values=_b64(vals, np.float32), value_name=lay.value_name,
            colorbar=None if bar is None else dict(lo=bar.lo, hi=bar.hi, label=bar.label, stops=bar.stops()),
            landmarks=_landmarks_json(shown, scene, lay, full),
            segments=None if lay.segments is None or not len(lay.segments) else _b64(lay.segments, np.float32)))
    ids = None if np.array_equal(shown.ids, np.arange(shown.n_vertices)) else _b64(shown.ids, np.int32)
    return dict(n=shown.n_vertices, positions=_b64(shown.vertices, np.float32),
                faces=None if shown.faces is None else _b64(shown.faces, np.uint32), ids=ids,
                partner=None if shown.partner is None else _b64(shown.partner, np.int32),
                parts=[list(p) for p in shown.parts], layers=layers,
                views=[list(v) for v in shown.views], view_labels=[view_label(*v) for v in shown.views],
                shading=[AMBIENT, DIFFUSE], facing=FACING, point_size=max(3.0, np.sqrt(shown.point_size) * 2),
                title=shown.title, notes=list(shown.notes) + ([note] if note else []),
                suggestions=_suggestions_json(scene), picking=scene.picking,
                marker_colours=[_hex(landmark_colour(0)), _hex(landmark_colour(3))])


def _json(obj) -> str:
    """JSON safe inside a <script> element (no "<", so no "</script>")."""
    return json.dumps(obj, separators=(",", ":"), allow_nan=False).replace("<", "\\u003c")


def viewer(scene: Scene, max_vertices: int = MAX_DISPLAY_VERTICES, heading: str | None = None) -> str:
    """HTML of one viewer (a ``div.sc-viewer`` holding its scene's data) for ``page``."""
    data = scene_data(scene, max_vertices)
    notes = "".join(f'<div class="sc-notes">{html.escape(t)}</div>' for t in data["notes"])
    head = f"<h2>{html.escape(heading)}</h2>" if heading else ""
    title = f'<div class="sc-caption">{html.escape(scene.title)}</div>' if scene.title else ""
    return (f'{head}{title}<div class="sc-viewer"><script type="application/json" class="sc-data">'
            f"{_json(data)}</script></div>{notes}")


def table(header, rows) -> str:
    """An HTML table from a header and rows of cells (escaped)."""
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def summary(lines) -> str:
    """A block of preformatted summary lines (escaped)."""
    return f'<div class="sc-summary">{html.escape(chr(10).join(lines))}</div>'


def viewer_scripts() -> list[str]:
    """The ``<script>`` elements a page with viewers ends with: three.js (as text, ``three_source``) and the
    viewer script, which draws every ``div.sc-viewer`` and ``div.sc-mapview`` of the page."""
    three = three_source()
    for bad in ("</script", "<!--", "<script"):
        if bad in three.lower():
            raise RuntimeError("the vendored three.js cannot be inlined in a <script> element")
    return [f'<script type="text/plain" id="sc-three">{three}</script>', f"<script>{asset('viewer.js')}</script>"]


def page(title: str, body) -> str:
    """A complete self-contained HTML document: ``title`` and the HTML fragments ``body``."""
    scripts = viewer_scripts()
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f'<meta name="generator" content="shapecond; three.js {THREE_VERSION} (MIT licence)">',
        f"<title>{html.escape(title)}</title>", f"<style>{asset('viewer.css')}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>", *body, *scripts, "</body></html>", ""])


def inline(document: str, height: int = 640) -> str:
    """A page as an ``<iframe srcdoc>`` for Jupyter's ``_repr_html_`` (its scripts stay in the frame)."""
    if not isinstance(document, str) or "<html" not in document:
        raise InputError("inline() needs a complete HTML page")
    return (f'<iframe srcdoc="{html.escape(document, quote=True)}" style="width:100%;height:{int(height)}px;'
            'border:1px solid #ddd" sandbox="allow-scripts"></iframe>')

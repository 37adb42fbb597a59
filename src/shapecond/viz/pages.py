"""The HTML pages of the commands and results (``--html FILE``, ``result.to_html``, ``report.html``).

Each function returns a complete self-contained document (``html.page``) built
from the same scenes as the PNGs (``viz.scene``):

* ``score_page``: the witness map (reference colours, their pull-back through
  the witness, the moved samples as chords) and the scale-aware witness;
* ``heatmap_page``: the score with each sample fixed, its colour scale and, on
  hover, each vertex's id and (interpolated) value;
* ``landmarks_page``: the landmarks in order with the score after each;
* ``match_page``: the colour transfer source -> target through the map, the
  landmarks linked, the error field when the ground truth is given, suggested
  points, and landmark pairs picked by clicking with the command that uses them;
* ``local_page``: the local score with each vertex fixed (the doubt field);
* ``evaluation_page``: the evaluation report's text and plots, and a viewer per
  class (the null shape with each method's landmarks).
"""

from __future__ import annotations

import html as _html
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..jsonable import fmt
from ..matching.problem import truth_errors
from ..output import write_text
from ..shapes.io import load_geometry
from .html import MAX_DISPLAY_VERTICES, inline, page, summary, table, viewer
from .truth import truth_map
from .scene import (DEFAULT_VIEWS, Colouring, HeatMapStyle, Place, colour_layer, guess_up, heatmap_scene, idw,
                    landmark_scene, make_scene, position_colours, shape_points, up_frame, witness_scene)


def _name(shape) -> str:
    geom = getattr(shape, "geometry", None)
    return getattr(geom, "name", None) or "a distance matrix"


def score_page(result, title: str | None = None) -> str:
    """Page of a ``ScoreResult``: witness map and scale-aware witness with the score's summary."""
    shape, sc = result.shape, result.score
    if getattr(shape, "geometry", None) is None:
        note = "a distance matrix has no surface: its points are placed by classical MDS"
    else:
        note = None
    scene = witness_scene(shape, sc.witness, landmarks=tuple(sc.landmarks), place=Place(up=None, title=title))
    layers = list(scene.layers)
    if result.scale is not None:
        wide = witness_scene(shape, result.scale.witness, landmarks=tuple(sc.landmarks)).layers[1]
        layers.append(replace(wide, label=f"scale-aware witness, δ(ε) = {fmt(result.scale.displacement)}"))
    scene = scene.with_layers(layers)
    if note:
        scene = replace(scene, notes=(note,))
    lo, hi = result.sigma
    lines = [f"sigma    [{fmt(lo)}, {fmt(hi)}]   kappa [{fmt(result.kappa[0])}, {fmt(result.kappa[1])}]",
             f"samples  N = {sc.n_points}, targets M = {sc.n_targets}",
             f"landmarks {', '.join(map(str, result.landmarks)) or 'none'}",
             f"verdict  {result.verdict}"]
    body = [summary(lines), viewer(scene),
            "<p>Row <b>reference</b>: every vertex coloured by its position. Row <b>witness</b>: every vertex "
            "takes the reference colour of the image of its nearest sample under the witness map, the "
            "near-isometry that makes the shape hard to match; chords join moved samples to their images. "
            "Where the map is the identity the two agree; a mirror symmetry swaps left and right colours.</p>"]
    return page(f"shapecond score: the witness map of {_name(shape)}", body)


def heatmap_page(shape, values, *, landmarks=(), lines=(), style: HeatMapStyle = HeatMapStyle()) -> str:
    """Page of a heat map: ``values`` per sample drawn with ``style`` (as ``render_heatmap_png``), ``lines``
    of summary."""
    scene = heatmap_scene(shape, values, landmarks=landmarks, style=style)
    body = [summary(lines) if lines else "", viewer(scene),
            "<p>Low values are good landmarks: fixing that point breaks the near-symmetries. Values are "
            "computed at the samples and interpolated between them (hover shows the interpolated value).</p>"]
    return page(f"shapecond heatmap: {_name(shape)}", body)


def landmarks_page(shape, result, *, up=None, title=None) -> str:
    """Page of a ``LandmarkResult`` on its ``MetricShape``: landmarks in order with the score after each."""
    V, F, pts, ids = shape_points(shape)
    verts = list(result.vertices) if shape.geometry is not None else [int(pts[i]) for i in result.sample_indices]
    name = "δ(ε)" if result.score == "scale" else "σ"
    notes = [f"{name} after: {fmt(s)}" for s in result.scores] if result.scores else ()
    scene = landmark_scene(V, F, verts, notes=notes, label=f"{result.method} landmarks", ids=ids,
                           place=Place(up or guess_up(shape.geometry), title=title))
    rows = [(i + 1, v, fmt(s) if i < len(result.scores) else "-")
            for i, (v, s) in enumerate(zip(result.landmarks, list(result.scores) + [None] * len(result.landmarks)))]
    body = [summary([f"method {result.method}, {shape.n_samples} samples, {result.seconds:.2f} s",
                     f"{name} without these landmarks: {fmt(result.initial_score)}"]),
            viewer(scene), table(["#", "vertex id", f"{name} after"], rows)]
    return page(f"shapecond landmarks: {result.method} on {_name(shape)}", body)


def local_page(geometry, heatmap, fixed=(), *, result=None, title=None) -> str:
    """Page of the local score's doubt field: σ_∞ with each vertex fixed (``deformation.heatmap``)."""
    vals = np.asarray(heatmap.values, dtype=float)
    finite = vals[np.isfinite(vals)]
    top = float(finite.max()) if finite.size else 1.0
    label = "σ_inf with the vertex fixed"
    layer = replace(colour_layer(np.where(np.isfinite(vals), vals, top), len(vals), Colouring("viridis", label=label),
                                 hover=vals), value_name=label, landmarks=[int(v) for v in fixed], label="doubt field")
    scene = make_scene(geometry.vertices, geometry.faces, [layer], ids=geometry.ids,
                       place=Place(guess_up(geometry), title=title))
    lines = [] if result is None else [f"local score σ_inf {fmt(result.score)}, λ_min {fmt(result.lambda_min)}",
                                       f"zero modes: {', '.join(result.zero_modes) or 'none'}"]
    body = [summary(lines) if lines else "", viewer(scene),
            "<p>Where fixing one more vertex would lower the local score most (low values: good landmarks "
            "for deformation-based matching); modal approximation, infinite where zero modes remain "
            "(drawn with the largest finite value).</p>"]
    return page(f"shapecond local: {geometry.name}", body)


# --- matching ---------------------------------------------------------------------------------

def _pair(src, tgt, up=None):
    """Display coordinates of two shapes side by side (the target beside the source along y), both turned
    so that ``up`` (default: ``guess_up`` of the two together) is vertical."""
    up = up or guess_up(src, tgt)
    out = []
    for g in (src, tgt):
        V = np.asarray(g.vertices, float)
        out.append((V - V.mean(axis=0)) @ up_frame(up, V).T)
    a, b = out
    gap = 0.15 * max(np.ptp(a[:, 1]), np.ptp(b[:, 1]))
    b = b + np.array([0.0, a[:, 1].max() - b[:, 1].min() + gap, 0.0])
    return a, b


@dataclass(frozen=True)
class MatchFields:
    """What a match page shows beyond the map.

    Attributes
    ----------
    truth : the ground truth, target internal index per source internal index (-1: none), for the
        error field; or None
    errors : the map's errors against ``truth`` as ``matching.problem.MatchProblem.truth_errors`` computed
        them (errors at the samples, % of half the target's diameter; their source internal indices), or
        None: computed here from ``truth`` (``matching.problem.truth_errors``)
    doubt, doubt_text : the error bar's doubt field (sqrt(area) units per source internal index,
        ``matching.error_bar``) and its sentence; or None
    suggestions : points of the source worth fixing next, ((source internal index, label), ...) in order,
        drawn with their own markers and listed with their labels (e.g. the error bar expected after each)
    command : the paths as given on the command line (``match_picking``), for the command the page
        builds from the landmarks picked on it; or None (placeholders)
    up : the vertical direction of both shapes (``scene.up_frame``); None: ``guess_up(source, target)``
    """

    truth: np.ndarray | None = None
    errors: tuple | None = None
    doubt: np.ndarray | None = None
    doubt_text: str = ""
    suggestions: tuple = ()
    command: dict | None = None
    up: str | None = None


def transfer_sources(tgt, vmap, at=None) -> np.ndarray:
    """The colour transfer's carry: for each target vertex of ``at`` (internal indices; None: every one),
    the source vertex (internal index) whose image under ``vmap`` lies nearest to it (Euclidean).

    A target vertex is drawn with the colour (and the doubt) of that source vertex: where the map is
    right the source's position colours carry over smoothly.
    """
    from scipy.spatial import cKDTree

    T = np.asarray(tgt.vertices, float)
    ok = np.flatnonzero(vmap >= 0)
    _, near = cKDTree(T[vmap[ok]]).query(T if at is None else T[np.asarray(at, dtype=np.int64)])
    return ok[near]


def doubt_colouring(doubt) -> Colouring:
    """The colours of the error bar's doubt field ``doubt`` (per source vertex, sqrt(area); NaN: none):
    turbo from 0 to its largest finite value."""
    finite = np.asarray(doubt, float)[np.isfinite(doubt)]
    top = float(finite.max()) if finite.size else 0.0
    return Colouring("turbo", 0.0, top or 1.0, "error bar's doubt, sqrt(area)")


def internal_map(result) -> np.ndarray:
    """A ``MatchResult``'s map as internal indices of its drawing's shapes (-1: a dropped vertex)."""
    src, tgt = result.drawing[:2]
    vmap = np.full(src.n_vertices, -1, dtype=np.int64)
    ok = result.map[src.ids] >= 0
    vmap[ok] = tgt.to_internal(result.map[src.ids][ok])
    return vmap


def _match_layers(src, tgt, vmap, a, b, lms, lmt, fields: MatchFields):
    n_s = src.n_vertices
    ref = position_colours(np.asarray(src.vertices, float))
    colours = np.vstack([ref, ref[transfer_sources(tgt, vmap)]])
    marks = [int(v) for v in lms] + [n_s + int(v) for v in lmt]
    ranks = tuple(range(len(lms))) * 2
    seg = np.stack([a[list(lms)], b[list(lmt)]], axis=1) if len(lms) else None
    layers = [replace(colour_layer(colours, len(colours)), landmarks=marks, ranks=ranks, segments=seg,
                      label="colour transfer source → target")]
    notes = []
    truth = fields.truth
    if truth is not None:
        err, samples = fields.errors if fields.errors is not None else truth_errors(src, tgt, vmap, truth)
        field = idw(np.asarray(src.vertices, float), samples, err)  # interpolated between the samples
        top = float(err.max()) if err.size else 1.0
        full = np.concatenate([field, np.full(tgt.n_vertices, np.nan)])
        name = "error, % of half the target's diameter"
        lay = replace(colour_layer(np.where(np.isfinite(full), full, 0.0), len(full),
                                   Colouring("magma_r", 0.0, top or 1.0, name), hover=full),
                      value_name=name, landmarks=marks, ranks=ranks, segments=seg, label="error field (on the source)")
        lay.rgba[n_s:] = (0.75, 0.75, 0.75, 1.0)
        layers.append(lay)
        notes.append(f"error field: geodesic distance on the target between the matched and the true vertex, "
                     f"measured at {samples.size} source samples (mean {np.mean(err):.3g} %, median "
                     f"{np.median(err):.3g} %) and interpolated between them")
    if fields.doubt is not None:
        full = np.concatenate([np.asarray(fields.doubt, float), np.full(tgt.n_vertices, np.nan)])
        lay = replace(colour_layer(np.where(np.isfinite(full), full, 0.0), len(full), doubt_colouring(full),
                                   hover=full),
                      value_name="doubt, sqrt(area)", landmarks=marks, ranks=ranks, segments=seg,
                      label="error bar's doubt (on the source)")
        lay.rgba[n_s:] = (0.75, 0.75, 0.75, 1.0)
        layers.append(lay)
        notes.append("doubt: how far the widest map that fits the landmarks and distorts no more than this one "
                     "moves each point, without ground truth: " + fields.doubt_text)
    return layers, notes


#: The words of the command a match page builds, and what it shows for those it was not given.
COMMAND_WORDS = (("source", "SOURCE"), ("target", "TARGET"), ("output", "MAP.txt"), ("html", "PAGE.html"),
                 ("options", ""))


def match_picking(src, tgt, landmarks_source, landmarks_target, command=None) -> dict:
    """What a match page needs to build ``shapecond match`` commands from landmarks picked by clicking.

    ``command``: the paths as given on the command line (keys ``source``, ``target``,
    ``output``, ``html``; a missing one is shown as a placeholder), shell-quoted here, and
    ``options``: the other options of the run, as a list of words (``--matcher faq``...), repeated;
    ``pairs``: the landmark pairs so far as file vertex ids.
    """
    import shlex

    given = dict(command or {})
    unknown = set(given) - {k for k, _ in COMMAND_WORDS}
    if unknown:
        raise InputError(f"unknown command word(s) {', '.join(sorted(unknown))}; "
                         f"known: {', '.join(k for k, _ in COMMAND_WORDS)}")
    options = " ".join(shlex.quote(str(w)) for w in given.pop("options", None) or ())
    words = {k: shlex.quote(str(given[k])) if given.get(k) is not None else shown for k, shown in COMMAND_WORDS}
    words["options"] = options
    pairs = [[int(src.ids[int(a)]), int(tgt.ids[int(b)])] for a, b in zip(landmarks_source, landmarks_target)]
    return dict(words, pairs=pairs, placeholders=[k for k, _ in COMMAND_WORDS[:4] if given.get(k) is None])


def _suggestions(src, suggestions) -> tuple:
    out = []
    for item in suggestions:
        v, label = item
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 0 <= int(v) < src.n_vertices:
            raise InputError(f"a suggestion needs a source vertex index in 0..{src.n_vertices - 1}, got {v!r}")
        out.append((int(v), "" if label is None else str(label)))
    return tuple(out)


def match_page(src, tgt, vmap, landmarks_source=(), landmarks_target=(), *, fields: MatchFields = MatchFields(),
               title=None, lines=()) -> str:
    """Page of a dense map between two Geometries; ``vmap``: target internal index per source internal
    index (-1: none); landmarks as internal indices; ``fields``: the error and doubt fields, the suggested
    points, the command line's paths and the up direction (``MatchFields``).  Source left, target right;
    a click on a source vertex, then on a target vertex, appends a landmark pair to the command shown."""
    if not (getattr(src, "vertices", None) is not None and getattr(tgt, "vertices", None) is not None):
        raise InputError("a map between distance matrices has no surface to draw")
    vmap = np.asarray(vmap, dtype=np.int64)
    suggestions = _suggestions(src, fields.suggestions)
    picking = match_picking(src, tgt, landmarks_source, landmarks_target, fields.command)
    a, b = _pair(src, tgt, fields.up)
    if fields.truth is not None:
        fields = replace(fields, truth=np.asarray(fields.truth, dtype=np.int64))
    layers, notes = _match_layers(src, tgt, vmap, a, b, landmarks_source, landmarks_target, fields)
    F = None
    if src.faces is not None and tgt.faces is not None:
        F = np.vstack([src.faces, tgt.faces + src.n_vertices])
    elif src.faces is not None or tgt.faces is not None:
        raise InputError("draw two meshes or two point clouds, not one of each")
    n_s = src.n_vertices
    scene = make_scene(np.vstack([a, b]), F, layers, ids=np.concatenate([src.ids, tgt.ids]),
                       place=Place(None, title=title, notes=tuple(notes)))
    scene = replace(scene, parts=(("source", 0, n_s), ("target", n_s, n_s + tgt.n_vertices)),
                    partner=np.concatenate([np.where(vmap >= 0, vmap + n_s, -1), np.full(tgt.n_vertices, -1)]),
                    suggestions=suggestions, picking=picking)
    body = [summary(lines) if lines else "", viewer(scene, max(MAX_DISPLAY_VERTICES, 2 * 30_000)),
            "<p>Left the source, coloured by position; right the target, each vertex coloured like the source "
            "vertex mapped nearest to it: where the map is right the colours carry over smoothly. Landmarks "
            "are numbered alike on both shapes and joined. Hover a source vertex: its image is marked on the "
            "target. <b>Pick landmarks</b>: click a source vertex, then the target vertex it corresponds to; "
            "the pair is appended to the command below the view (run it to match again with it)"
            + (", and the suggested points (S1, S2, ...) are where a landmark should help most" if suggestions
               else "") + ".</p>"]
    return page(f"shapecond match: {src.name} → {tgt.name}", body)


# --- evaluation -----------------------------------------------------------------------------------

def markdown_html(text: str, folder) -> str:
    """The report's Markdown (headings, paragraphs, lists, tables, images) as HTML; images are inlined
    from ``folder`` as data URIs (PNG)."""
    import base64
    import re

    def inline(s):
        s = _html.escape(s)
        s = re.sub(r"`([^`]+)`", r"<code>\1</code>", s)
        return re.sub(r"\*([^*\s][^*]*)\*", r"<em>\1</em>", s)

    out, rows, items = [], [], []

    def flush():
        if rows:
            cells = [[c.strip() for c in r.strip().strip("|").split("|")] for r in rows if not set(r) <= set("|-: ")]
            out.append(table(cells[0], cells[1:]).replace("<td>", "<td>"))
            rows.clear()
        if items:
            out.append("<ul>" + "".join(f"<li>{inline(i)}</li>" for i in items) + "</ul>")
            items.clear()

    for line in text.splitlines():
        if line.startswith("|"):
            rows.append(line)
            continue
        if line.startswith("- "):
            items.append(line[2:])
            continue
        flush()
        img = re.fullmatch(r"!\[([^\]]*)\]\(([^)]+)\)", line.strip())
        if img:
            p = Path(folder) / img.group(2)
            if p.exists():
                data = base64.b64encode(p.read_bytes()).decode("ascii")
                out.append(f'<p><img alt="{_html.escape(img.group(1))}" src="data:image/png;base64,{data}"></p>')
        elif line.startswith("## "):
            out.append(f"<h2>{inline(line[3:])}</h2>")
        elif line.startswith("# "):
            continue  # the page's own title
        elif line.strip():
            out.append(f"<p>{inline(line)}</p>")
    flush()
    return "\n".join(out)


def class_scene(geometry, sets: dict, scores: dict, cls: str):
    """The null shape of a class with one layer per landmark method (``sets[method]`` internal vertices,
    ``scores[method]`` {count: score})."""
    layers = []
    for method, verts in sets.items():
        sc = scores.get(method, {})
        notes = tuple(f"σ after {i + 1}: {fmt(sc[i + 1])}" if (i + 1) in sc else "" for i in range(len(verts)))
        layers.append(dict(values=None, landmarks=list(verts), notes=notes, label=method))
    return make_scene(geometry.vertices, geometry.faces, layers, ids=geometry.ids,
                      place=Place(guess_up(geometry), DEFAULT_VIEWS, f"{cls}: null shape with each method's landmarks"))


def evaluation_page(ev, folder, text: str, nulls: dict, max_vertices: int = 15_000) -> str:
    """``report.html``: the report's Markdown ``text`` (tables, plots from ``folder``) and a viewer per class.

    ``nulls[cls]``: the path of the class's null shape (None when it cannot be read any more).
    """
    body = [markdown_html(text, folder), "<h2>Landmarks on the null shapes</h2>"]
    for cls in ev.settings["classes"]:
        path = nulls.get(cls)
        if path is None:
            body.append(f"<p>{_html.escape(cls)}: the class folder is not readable any more; no viewer.</p>")
            continue
        g = load_geometry(path)
        sets = {d["method"]: d["vertices"] for d in ev.landmarks if d["cls"] == cls}
        scores = {d["method"]: {int(c): v for c, v in d.get("scores", {}).items()}
                  for d in ev.landmarks if d["cls"] == cls}
        body.append(viewer(class_scene(g, sets, scores, cls), max_vertices, heading=cls))
    return page("Landmark evaluation (paper Section 7, Figure 7)", body)


def demo_page(shape, score, small, values, chosen) -> str:
    """``demo.html`` of ``shapecond demo``: the witness map, the heat map and the CNBS landmarks."""
    witness = witness_scene(shape, score.witness, place=Place("y", title="the witness map of the symmetry score"))
    heat = heatmap_scene(small, values, style=HeatMapStyle("y", title="σ with each point fixed (CNBS heat map)"))
    g = small.geometry
    notes = [f"σ after: {fmt(s)}" for s in chosen.scores]
    marks = landmark_scene(g.vertices, g.faces, [int(small.samples[i]) for i in chosen.sample_indices], notes=notes,
                           ids=g.ids, place=Place("y", title="three CNBS landmarks"))
    lo, hi = score.sigma_lower, score.sigma_upper
    body = [summary([f"sigma [{fmt(lo)}, {fmt(hi)}] on demo:animal ({g.n_vertices} vertices, N = {shape.n_points})",
                     f"CNBS landmarks (N = {small.n_points}): {', '.join(map(str, chosen.landmarks))}"]),
            viewer(witness, heading="Witness map"), viewer(heat, heading="Heat map"),
            viewer(marks, heading="Landmarks")]
    return page("shapecond demo: the generated animal", body)


# --- results of the Python interface ------------------------------------------------------------

@dataclass(frozen=True)
class PageOptions:
    """The options of a result's page (``result_page``; ``PAGE_OPTIONS`` says which each result type takes).

    Attributes
    ----------
    title : the page's title.
    up : the shapes' vertical direction (None: guessed, ``scene.guess_up``).
    cmap, colorbar_label : a heat map's colours (None: ``scene.HeatMapStyle``'s).
    truth, suggestions, command : a match's ground truth, suggested landmarks and command paths
        (``MatchFields``).
    """

    title: str | None = None
    up: str | None = None
    cmap: str | None = None
    colorbar_label: str | None = None
    truth: object = None
    suggestions: tuple = ()
    command: object = None


#: For each result type: the ``PageOptions`` its ``to_html`` takes.
PAGE_OPTIONS = {"ScoreResult": ("title",), "HeatMapResult": ("up", "title", "cmap", "colorbar_label"),
                "LandmarkResult": ("up", "title"), "MatchResult": ("truth", "suggestions", "command", "up", "title"),
                "LocalResult": ("title",)}


def page_options(result, options: dict) -> PageOptions:
    """The ``PageOptions`` of ``to_html``'s keywords ``options`` for ``result``; an option its page does not
    take is refused in one line, before anything is drawn."""
    kind = type(result).__name__
    if kind not in PAGE_OPTIONS:
        raise InputError(f"no HTML page for a {kind}")
    unknown = sorted(set(options) - set(PAGE_OPTIONS[kind]))
    if unknown:
        raise InputError(f"to_html() got an unknown option {unknown[0]!r} "
                         f"(its options: {', '.join(PAGE_OPTIONS[kind])})")
    return PageOptions(**options)


def result_page(result, options: PageOptions = PageOptions()) -> str:
    """The page of a result of ``shapecond``'s functions (score, heatmap, landmarks, match, local_score);
    ``options`` as ``page_options`` makes them."""
    kind, o = type(result).__name__, options
    if kind not in PAGE_OPTIONS:
        raise InputError(f"no HTML page for a {kind}")
    if kind == "ScoreResult":
        return score_page(result, o.title)
    if kind == "HeatMapResult":
        style = HeatMapStyle(o.up, title=o.title, cmap=o.cmap or HeatMapStyle.cmap,
                             colorbar_label=o.colorbar_label or HeatMapStyle.colorbar_label)
        return heatmap_page(result.shape, result.plot_values(), landmarks=range(len(result.landmarks)),
                            lines=[f"{result.score} before: {fmt(result.sigma_before)}; best landmark: vertex "
                                   f"{result.best} ({fmt(result.best_value)})"], style=style)
    if kind == "LandmarkResult":
        if getattr(result, "shape", None) is None:
            raise InputError("this LandmarkResult does not know its shape; use shapecond.landmarks()")
        return landmarks_page(result.shape, result, up=o.up, title=o.title)
    if kind == "MatchResult":
        return _match_result_page(result, o)
    hm = result.doubt()  # InputError when the result does not know its mesh
    g = result.drawing[0]
    return local_page(g, hm, g.to_internal(result.landmarks), result=result, title=o.title)


def _match_result_page(result, o: PageOptions) -> str:
    drawing = getattr(result, "drawing", None)
    if drawing is None:
        raise InputError("a map between distance matrices has no surface to draw")
    src, tgt, ls, lt = drawing
    vmap = internal_map(result)
    t = None if o.truth is None else truth_map(o.truth, src, tgt)
    problem = getattr(result, "problem", None)  # the match's own: the errors computed once, by it
    errors = None if t is None or problem is None else problem.truth_errors(t)
    s = result.summary
    lines = [f"{s.get('matcher')} map, {s.get('n_landmarks')} landmarks, N = {s.get('n_points')} samples"]
    doubt = None if result.doubt is None else result.doubt[src.ids]
    suggestions = o.suggestions
    if not suggestions and s.get("suggestions"):  # the match's own (``MatchResult.suggest``)
        suggestions = tuple((int(src.to_internal([p["source_id"]])[0]),
                             f"image {p['image_id']}, bar after it {p['bar_after']:.3g}") for p in s["suggestions"])
    fields = MatchFields(t, errors, doubt, s.get("error_bar", {}).get("text", ""), tuple(suggestions), o.command,
                         o.up)
    return match_page(src, tgt, vmap, ls, lt, fields=fields, lines=lines, title=o.title)


def write_result(result, path, options: PageOptions = PageOptions()) -> str:
    """Write ``result_page(result, options)`` to ``path`` atomically; return the path."""
    return str(write_text(path, result_page(result, options)))


def inline_result(result, height: int = 640):
    """``_repr_html_`` of a result: its page in an iframe, or None when it has nothing to draw."""
    try:
        return inline(result_page(result), height)
    except InputError:
        return None


def write_evaluation_html(ev, folder, text: str, nulls: dict) -> str:
    """Write ``report.html`` (``evaluation_page``) into ``folder`` atomically; return its path."""
    return str(write_text(Path(folder) / "report.html", evaluation_page(ev, folder, text, nulls)))

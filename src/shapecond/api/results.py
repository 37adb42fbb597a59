"""What the Python interface returns: the results of the maths with their pictures.

The maths returns plain results (``symmetry.report.ScoreReport``,
``selection.result.LandmarkSelection``, ``deformation.local_score.LocalScore``)
and never imports the pictures.  Here each one becomes a result of the
interface, the same fields plus:

* ``plot(fig=None, path=None)``: a matplotlib Figure (four views), drawn onto
  ``fig`` without touching the global backend, or written to ``path`` (PNG);
* ``to_html(path)``: a self-contained page to turn in a browser (``viz.pages``);
* ``_repr_html_()``: that page inline in a notebook;
* a short ``repr`` (a few numbers, never whole arrays) and ``to_dict()``, valid
  JSON as it is (``inf`` as ``"inf"``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..deformation.heatmap import local_heatmap
from ..deformation.local_score import LocalScore
from ..errors import InputError
from ..jsonable import fmt, jsonable
from ..limits import check_cost, local_seconds
from ..selection.result import LandmarkSelection
from ..symmetry.condition import ProbeResult
from ..symmetry.report import ScoreReport
from ..symmetry.starts import classical_mds


def check_style(style: dict, known) -> None:
    """``InputError`` in one line for a keyword of a ``plot`` call's ``style`` that is not one of ``known``."""
    unknown = sorted(set(style) - set(known))
    if unknown:
        raise InputError(f"plot() got an unknown option {unknown[0]!r} (its options: {', '.join(sorted(known))})")


def style_of(cls, style: dict, defaults: dict):
    """The drawing options ``cls`` (a frozen dataclass of ``viz``) of a ``plot`` call's keywords ``style`` over
    ``defaults`` (a dict of fields); a keyword that is not one of its fields is refused (``check_style``)."""
    check_style(style, {f.name for f in fields(cls)})
    return cls(**{**defaults, **style})


#: The colouring keywords of a field picture and the ``viz.scene.Colouring`` fields they set (``look_of``).
PAINT = {"cmap": "cmap", "vmin": "vmin", "vmax": "vmax", "colorbar_label": "label"}


def look_of(style: dict, colouring, defaults: dict):
    """The ``viz.render.Look`` of a ``plot`` call's keywords ``style``: the fields of ``Look`` a user sets
    (not its ``colouring`` and ``extra``) and the colouring keywords ``PAINT`` (over ``colouring``, a
    ``viz.scene.Colouring``)."""
    from ..viz.render import Look

    known = {f.name for f in fields(Look)} - {"colouring", "extra"} | set(PAINT)
    check_style(style, known)
    look = {k: v for k, v in style.items() if k not in PAINT}
    paint = {PAINT[k]: v for k, v in style.items() if k in PAINT}
    return Look(**{**defaults, **look, "colouring": replace(colouring, **paint)})


def promote(result, cls, extra: dict | None = None):
    """``result`` (a maths dataclass) as the interface's subclass ``cls``, with the fields ``extra`` set."""
    values = {f.name: getattr(result, f.name) for f in fields(result) if f.init}
    return cls(**values, **(extra or {}))


class Pictures:
    """``to_html`` and ``_repr_html_`` of every result (``viz.pages`` chooses the page by type)."""

    def to_html(self, path, **kw) -> str:
        """Write this result as a self-contained HTML page; returns the path.  ``kw``: the options of its
        page (``viz.pages.PAGE_OPTIONS``: ``title``, ``up``...; a match's ``truth``, see ``MatchResult``), an
        unknown one refused in one line."""
        from ..viz.pages import page_options, write_result

        return write_result(self, path, page_options(self, kw))

    def _repr_html_(self):
        from ..viz.pages import inline_result

        return inline_result(self)


@dataclass(frozen=True, eq=False, repr=False)
class ScoreResult(ScoreReport, Pictures):
    """σ bracket (paper Eq. 5), κ bracket (Theorem 4.1), witness, δ(ε) and verdict of one shape.

    Attributes beyond ``ScoreReport``'s: none; ``.sigma``, ``.kappa``,
    ``.witness_ids``, ``.verdict``, ``.scale`` (δ(ε)) are the report's.
    """

    def plot(self, fig=None, path=None, *, scale: bool = False, max_segments: int = 80, up: str | None = None,
             views: tuple | None = None, title: str | None = None, point_size: float | None = None):
        """The witness map (``scale=True``: the scale-aware witness of δ(ε)) drawn on the shape, its
        ``max_segments`` longest moves as chords; ``up`` (None: guessed), ``views`` (None: the four default
        views), ``title`` and ``point_size`` as ``viz.scene.Place``'s.

        Onto ``fig`` (or a new Figure) and returned, or written to ``path`` (PNG; returns the path).
        """
        from ..viz.scene import Place
        from ..viz.witness import render_witness_png

        place = Place(up=up, views=Place.views if views is None else views, title=title, point_size=point_size)
        if self.shape.geometry is None and path is not None:
            raise InputError("a witness picture needs a mesh or point cloud")
        witness = self.scale.witness if scale else self.score.witness
        return render_witness_png(self.shape, witness, path, landmarks=tuple(self.score.landmarks), fig=fig,
                                  place=place, max_segments=max_segments)


@dataclass(frozen=True)
class LandmarkResult(LandmarkSelection, Pictures):
    """Landmarks in selection order (the input's ids) with the score after each (paper Section 6)."""

    def __repr__(self) -> str:
        scores = ", ".join("-" if s is None else f"{s:.4g}" for s in self.scores)
        return f"LandmarkResult({self.method}, landmarks={list(self.landmarks)}, {self.score} after each: [{scores}])"

    def plot(self, fig=None, path=None, *, up: str = "z", views: tuple | None = None, title: str | None = None,
             point_size: float | None = None, labels: bool = True, dpi: int = 110):
        """The landmarks (paper Figure 6 colours) drawn on the shape; onto ``fig`` or written to ``path``.
        ``up``, ``views`` (None: the four default views), ``title``, ``point_size`` (None: 6, or 30 for a
        small point cloud or a distance matrix's points), ``labels`` (number them) and ``dpi``: as
        ``viz.render.Look``'s."""
        from ..viz.render import Look, new_figure, render_png

        shape = self.shape
        if shape.geometry is not None:
            V, F, verts = shape.geometry.vertices, shape.geometry.faces, list(self.vertices)
        else:  # a distance matrix: its points placed by classical MDS
            V, F, verts = classical_mds(shape.D), None, list(self.sample_indices)
        if point_size is None:
            point_size = 6.0 if F is not None or len(V) > 2000 else 30.0
        look = Look(views=Look.views if views is None else views, up=up, title=title, point_size=point_size,
                    labels=labels, dpi=dpi)
        if path is None:
            fig = fig if fig is not None else new_figure()
        return render_png(path, V, F, None, verts, fig=fig, look=look)


class FieldPicture:
    """``plot`` of a result that draws a per-vertex field on its source mesh (``LocalResult``'s doubt field,
    ``MatchResult``'s error bar's doubt): ``picture_field`` says what."""

    def picture_field(self):
        """(Geometry, per-vertex values in its internal order, internal landmark ids, ``viz.scene.Colouring``,
        the default title)."""
        raise NotImplementedError

    def plot(self, fig=None, path=None, **style):
        """The field drawn on the mesh, landmarks ringed; onto ``fig`` (or a new Figure) and returned, or
        written to ``path`` (PNG).  ``style``: the fields of ``viz.render.Look`` (``up`` (None: guessed),
        ``views``, ``title``, ``dpi``...) and ``cmap``, ``vmin``, ``vmax``, ``colorbar_label`` (``look_of``);
        another is refused in one line."""
        from ..viz.render import new_figure, render_png
        from ..viz.scene import guess_up

        g, values, landmarks, colouring, title = self.picture_field()
        look = look_of(style, colouring, {"title": title, "up": style.get("up") or guess_up(g)})
        if path is None:
            fig = fig if fig is not None else new_figure()
        return render_png(path, g.vertices, g.faces, values, landmarks=landmarks, fig=fig, look=look)


@dataclass(frozen=True, eq=False, repr=False)
class LocalResult(LocalScore, FieldPicture, Pictures):
    """Local symmetry score σ_∞ = sqrt(2/λ_min) (paper Section 5) with its mesh, to draw the doubt field."""

    drawing: tuple = field(repr=False, default=None)  # (Geometry, its LocalProblem, zero_tol)
    _doubt: dict = field(repr=False, default_factory=dict, compare=False)

    def doubt(self):
        """The local score with each vertex fixed in turn (modal approximation, ``deformation.heatmap``);
        computed once, from the factorisation the score used."""
        if self.drawing is None:
            raise InputError("this result does not know its mesh; use shapecond.local_score()")
        if "field" not in self._doubt:
            g, problem, zero_tol = self.drawing
            n = g.n_vertices
            check_cost(f"the doubt field of {n} vertices", local_seconds(n, doubt=True) - local_seconds(n), force=True)
            self._doubt["field"] = local_heatmap(problem, g.to_internal(self.landmarks), zero_tol=zero_tol)
        return self._doubt["field"]

    def picture_field(self):
        """The doubt field (``doubt``) for ``plot``."""
        from ..viz.scene import Colouring

        hm = self.doubt()
        g = self.drawing[0]
        return (g, hm.values, [int(v) for v in g.to_internal(self.landmarks)],
                Colouring(label="sigma_inf with the vertex fixed"), f"{g.name}: local score with each vertex fixed")


@dataclass(frozen=True, repr=False)
class KappaResult(ProbeResult):
    """Probes of the condition number κ (paper Eq. 4) on the shape's samples, with σ ≤ κ ≤ 2σ + 1.

    Attributes beyond ``ProbeResult``'s: ``shape`` (the MetricShape probed), ``landmark_ids``
    (input ids fixed), ``trials`` (probes asked for).
    """

    shape: object = field(default=None, repr=False, compare=False)
    landmark_ids: tuple = ()
    trials: int = 0

    def __repr__(self) -> str:
        lo, hi = self.kappa
        return (f"KappaResult(sigma={fmt(self.sigma)}, kappa=[{fmt(lo)}, {fmt(hi)}], {len(self.ratios)} probes, "
                f"max {fmt(self.kappa_probe_max)})")

    def to_dict(self) -> dict:
        """The JSON object of ``shapecond kappa --json``."""
        return jsonable({"n_points": self.shape.n_points, "landmarks": list(self.landmark_ids),
                         "samples": self.shape.sample_ids, "trials": self.trials, **super().to_dict()})


@dataclass(frozen=True, eq=False)
class HeatMapResult(Pictures):
    """σ (or δ(ε)) with each sample fixed as a landmark (paper Figures 1 and 4), in the input's ids.

    Attributes
    ----------
    samples : (N,) input ids of the samples; ``values[i]`` is the score with ``samples[i]``
        fixed (NaN for the landmarks already fixed).
    sigma_before : the score with only ``landmarks`` fixed.
    best, best_value : the best next landmark and the score with it fixed.
    landmarks : the landmarks already fixed (input ids).
    score : "sigma" (σ, Eq. 5) or "scale" (δ(ε)).
    epsilon : the distortion level ε of δ (None for σ).
    """

    samples: np.ndarray
    values: np.ndarray
    sigma_before: float
    best: int
    best_value: float
    landmarks: tuple
    seconds: float
    shape: object = field(repr=False)
    score: str = "sigma"
    epsilon: float | None = None

    def to_dict(self) -> dict:
        """The JSON object of ``shapecond heatmap --json``."""
        return jsonable({"landmarks": list(self.landmarks), "score": self.score, "epsilon": self.epsilon,
                         "sigma_before": self.sigma_before, "samples": self.samples,
                         "values": [None if np.isnan(v) else float(v) for v in self.values],
                         "best": self.best, "best_value": self.best_value, "seconds": self.seconds})

    def __repr__(self) -> str:
        return (f"HeatMapResult(N={self.samples.size}, sigma_before={self.sigma_before:.4g}, best={self.best}, "
                f"best_value={self.best_value:.4g}, landmarks={list(self.landmarks)})")

    def plot_values(self) -> np.ndarray:
        """The values drawn: landmarks at ``sigma_before``, non-finite ones at the largest finite value."""
        vals = np.where(np.isnan(self.values), self.sigma_before, self.values)
        vals = np.where(np.isfinite(vals), vals, np.nan)
        return np.where(np.isnan(vals), np.nanmax(vals) if np.any(np.isfinite(vals)) else 1.0, vals)

    def title(self) -> str:
        """One line: the score before and the best landmark."""
        name = "delta" if self.score == "scale" else "sigma"
        return (f"{name} with each point fixed (before: {fmt(self.sigma_before)}; best: {fmt(self.best_value)} "
                f"at vertex {self.best})")

    def plot(self, fig=None, path=None, *, ply=None, **style):
        """The heat map drawn on the shape; onto ``fig`` (or a new Figure) or written to ``path``
        (``ply=FILE``: also a coloured PLY).  ``style``: the fields of ``viz.scene.HeatMapStyle`` (``up``,
        ``views``, ``title``, ``method``, ``cmap``, ``colorbar_label``, ``log``)."""
        from ..viz.heatmap import render_heatmap_png
        from ..viz.scene import HeatMapStyle

        hm_style = style_of(HeatMapStyle, style, {"title": self.title()})
        return render_heatmap_png(self.shape, self.plot_values(), path, landmarks=list(range(len(self.landmarks))),
                                  ply=ply, fig=fig, style=hm_style)


@dataclass(frozen=True, eq=False)
class MatchResult(FieldPicture, Pictures):
    """A dense map source -> target in input ids (``map[i]`` = target id of source id i, -1: dropped).

    Attributes
    ----------
    map : (n,) int64 target id of every source id.
    summary : the JSON summary of ``shapecond match`` (matcher, counts, options).
    drawing : (source Geometry, target Geometry, their landmarks as internal ids), for pictures.
    doubt : (n,) the error bar's doubt field at every source id (``matching.error_bar``; NaN for a
        dropped vertex), or None.
    advice : callable k -> the k next landmarks (``matching.problem.MatchProblem.suggest`` of this
        match), or None without an error bar; use ``suggest``.
    problem : the ``matching.problem.MatchProblem`` the map was read off (None for distance matrices):
        what the page's error field is computed by (``MatchProblem.truth_errors``).

    ``to_html(path, truth=...)`` writes the map's page (colour transfer, linked landmarks, the error bar's
    doubt field and, with ``truth``, the error field): ``truth`` is one target id per source id (-1: none),
    "same-ids", the path of such a map file, or ``"SOURCE.vts,TARGET.vts"``, the two shapes' reference files
    of a remeshed release (the error is then measured at the source's reference vertices;
    ``viz.truth.truth_map``).
    """

    map: np.ndarray
    summary: dict
    drawing: tuple = field(default=None, repr=False)
    doubt: np.ndarray | None = field(default=None, repr=False)
    advice: object = field(default=None, repr=False)
    problem: object = field(default=None, repr=False)

    def suggest(self, k: int = 1) -> list[dict]:
        """The ``k`` next landmarks of this match, in order (``matching.suggest``): each its source id,
        its provisional image's target id under the found map, the expected gain and the bar expected
        after it.  Recorded in ``summary["suggestions"]`` and in the summary's ``verdict``."""
        if self.advice is None:
            raise InputError("suggesting landmarks reads the error bar: match two surfaces with error_bar=True")
        out = [s.to_dict() for s in self.advice(k=k)]
        self.summary["suggestions"] = out
        if out:
            self.summary["verdict"] = (f"click source vertex {out[0]['source_id']} next (provisional image "
                                       f"{out[0]['image_id']}): the bar is expected to go from "
                                       f"{self.summary['error_bar']['bar']:.3g} to {out[0]['bar_after']:.3g} "
                                       "sqrt(area)")
        return out

    def truth_errors(self, truth) -> dict:
        """The map's errors against a ground truth (``matching.problem.MatchProblem.truth_summary``): mean,
        median and worst geodesic error in sqrt(area) of the target and the mean in % of half its
        diameter, at up to 200 farthest-point samples of the source vertices whose true image is known.
        Recorded in ``summary["truth"]``.

        ``truth``: as ``to_html``'s (one target id per source id, -1: none; "same-ids" for one mesh
        deformed; a map file; ``"SOURCE.vts,TARGET.vts"``)."""
        if self.problem is None or self.drawing is None:
            raise InputError("errors against a ground truth need two surfaces, not distance matrices")
        from ..viz.truth import truth_map

        src, tgt = self.drawing[:2]
        self.summary["truth"] = self.problem.truth_summary(truth_map(truth, src, tgt))
        return self.summary["truth"]

    def to_dict(self) -> dict:
        """The summary of ``shapecond match --json`` plus the map itself."""
        return jsonable({**self.summary, "map": self.map})

    def picture_field(self):
        """The error bar's doubt field on the source (where the next landmark should go) for ``plot``."""
        from ..viz.scene import Colouring

        if self.doubt is None or self.drawing is None:
            raise InputError("the map has no doubt field to draw: match two surfaces with error_bar=True")
        src = self.drawing[0]
        return (src, self.doubt[src.ids], list(self.drawing[2]), Colouring("turbo", label="doubt, sqrt(area)"),
                f"{src.name}: the error bar's doubt (sqrt(area))")

    def __repr__(self) -> str:
        s = self.summary
        bar = s.get("error_bar")
        return (f"MatchResult({s.get('matcher')}, {self.map.size} source ids -> target ids, "
                f"{s.get('n_landmarks')} landmarks, N={s.get('n_points')}"
                + (f", error bar {bar['bar']:.3g} sqrt(area))" if bar else ")"))


__all__ = ["HeatMapResult", "KappaResult", "LandmarkResult", "LocalResult", "MatchResult", "ScoreResult", "promote"]

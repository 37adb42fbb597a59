"""The protocols of the evaluation: which samples a target has, and where errors are measured.

For each landmark method the null shape's landmarks (``landmark_sets``) are
sent to the target through the ground truth, the null shape is matched to the
target with the first 3 and with all of them (``MatchingSetup.counts``) by each
matcher, and the error of the map is measured on the target (``matching.metrics``).

``"corresponding"`` — the κ setting of the paper (Eq. 4 compares a shape with a
    perturbation of *the same points*): the null shape's N samples (landmarks
    first) are carried to the target by vertex id (``sampled.carry_samples``, in
    a shuffled order), the sample matchers map source samples to these target
    samples, and the error of sample ``x`` is the target's geodesic distance
    between ``T(x)`` and ``x``'s own vertex.  Also recorded: the fraction of
    samples mapped exactly, and for LH05 the recall of its candidates and its
    objective against the true map's.  Shared vertex order only.
``"independent"`` — each target gets its own farthest-point samples, so no target
    sample is the true image of a source sample; the map is made dense
    (``problem.MatchProblem``, with the dense stage) and its error is measured
    at the target's N samples (the source vertex with the same id goes to
    ``p``; ``d_t(p, g)`` is read from the target's distance rows).  Shared
    vertex order only.
``"remeshed"`` — where users live: every shape has its own triangulation and the
    ground truth is given at reference points by ``.vts`` files
    (``datasets``).  A null landmark goes to the target vertex of the reference
    point at it (or, when no reference point falls on it, of the reference point
    geodesically nearest to it).  Each matcher gives a dense map (``"zoomout"``
    from the landmarks alone), and the error is the field's: the mean over the
    reference points ``j`` of the target's geodesic distance between the image of
    ``vts_null[j]`` and ``vts_target[j]``, divided by ``sqrt(target area)``,
    beside the same in % of half the target's geodesic diameter.  Where the
    ground truth gives the mirror images (``.sym.vts``, ``reference.sym``) a
    matching is *flipped* when its mean error exceeds half the mean distance
    between mirror images.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..api import load as load_shape
from ..errors import InputError
from ..matching import consistency
from ..matching.candidates import recall
from ..matching.metrics import errors_from_rows, normalise
from ..matching.error_bar import ErrorBar
from ..matching.pipeline import SAMPLE_MATCHERS, MatchOptions
from ..matching.problem import MatchProblem
from ..matching.seeded import FAQOptions
from ..matching.sampled import CachedSolver, sample_surface, surface_at, surface_unit
from ..matching.spectral import fine_kernel
from ..shapes.geodesics import DistanceSolver
from ..shapes.vts import read_vts
from .datasets import ClassFolder, reference_symmetry
from .landmark_sets import ShapeSetup
from .records import MatchRecord, curve_points

PROTOCOLS = ("corresponding", "independent", "remeshed")
#: Target rows computed at a time when measuring errors at the reference points.
ROW_BLOCK = 512


@dataclass(frozen=True)
class MatchingSetup:
    """What every target task of an evaluation shares.

    Attributes
    ----------
    counts : landmark counts to match with (prefixes of each method's landmarks).
    matchers : matchers (``matching.pipeline.MATCHERS``); the corresponding protocol runs the
        sample matchers only.
    dense : how maps reach every vertex (``matching.pipeline.DENSE_STAGES``).
    shape : ShapeSetup (N, seed, backend, cache).
    error_bars : give every matching its error bar (``matching.error_bar``; a δ search each).
    faq_objective : FAQ's objective (``matching.seeded``).
    """

    counts: tuple
    matchers: tuple
    dense: str = "zoomout"
    shape: ShapeSetup = ShapeSetup()
    error_bars: bool = True
    faq_objective: str = "distance"

    def options(self, matcher: str, protocol: str = "independent") -> MatchOptions:
        """The ``MatchOptions`` of ``matcher`` in ``protocol`` (the corresponding protocol's target has the
        source's samples, ``samples="same-ids"``)."""
        s = self.shape
        faq = FAQOptions(objective=self.faq_objective, seed=s.seed) if matcher == "faq" else None
        return MatchOptions(matcher=matcher, n_points=s.n_points, backend=s.backend, seed=s.seed,
                            dense=self.dense, samples="same-ids" if protocol == "corresponding" else "fps",
                            cache=s.cache, matcher_options=faq)


def target_task(cls: ClassFolder, target_path, landmark_sets: dict, setup: MatchingSetup,
                protocol: str = "corresponding", load=None) -> list:
    """Match the null shape of ``cls`` to one target for every method, count and matcher.

    Parameters
    ----------
    landmark_sets : dict method -> internal vertex ids of the null shape, in order.
    protocol : one of ``PROTOCOLS``.
    load : optional callable path -> Geometry (tests); default ``sc.load``.
    """
    if protocol not in PROTOCOLS:
        raise InputError(f"unknown protocol {protocol!r} ({', '.join(PROTOCOLS)})")
    load = load or load_shape
    if protocol == "remeshed":
        return _remeshed(cls, target_path, landmark_sets, setup, load)
    return _shared_order(cls, target_path, landmark_sets, setup, protocol, load)


def _cells(landmark_sets: dict, setup: MatchingSetup, matchers):
    for method, lm in landmark_sets.items():
        for c in setup.counts:
            for matcher in matchers:
                yield method, min(c, len(lm)), matcher


def _shared_order(cls, target_path, landmark_sets, setup, protocol, load) -> list:
    """The corresponding and independent protocols (shapes with one vertex order)."""
    s = setup.shape
    source = sample_surface(load(cls.null), s.n_points, s.backend, s.seed, cache=s.cache)
    g = load(target_path)
    if not source.geometry.shares_vertex_order(g):  # the truth is the identity: one mesh deformed, not one count
        raise InputError(f"{g.name} and {source.geometry.name} do not share their vertex order (vertex ids and "
                         "triangles): shapes without .vts files need one mesh deformed (or a corres/ folder of "
                         ".vts files)")
    if protocol == "corresponding":
        tgt = surface_at(g, source.samples, s.backend, s.cache)
        solvers = (CachedSolver(source.geometry, s.backend, source), CachedSolver(g, s.backend, tgt))
    else:
        tgt = sample_surface(g, s.n_points, s.backend, s.seed, cache=s.cache)
        solvers = (CachedSolver(source.geometry, s.backend), CachedSolver(g, s.backend))
    half = 0.5 * tgt.diameter
    area = tgt.unit ** 2 if g.faces is not None else None
    matchers = [m for m in setup.matchers if m in SAMPLE_MATCHERS] if protocol == "corresponding" else setup.matchers
    out = []
    for method, c, matcher in _cells(landmark_sets, setup, matchers):
        lm = landmark_sets[method][:c]
        t0 = time.perf_counter()
        problem = MatchProblem(source.geometry, g, lm, lm, setup.options(matcher, protocol), surfaces=(source, tgt),
                               solvers=solvers)
        if protocol == "corresponding":
            raw, raw_s, extra = _corresponding_cell(problem, setup.error_bars)
        else:
            raw, raw_s, extra = _independent_cell(problem, tgt, setup.error_bars)
        err = normalise(raw, 2 * half)
        out.append(MatchRecord(
            cls.name, g.name, method, c, matcher, float(err.mean()),
            float(normalise(raw, 2 * half, area, "sqrt_area").mean()) if area else math.nan,
            float(normalise(raw_s, 2 * half).mean()) if raw_s is not None else math.nan,
            time.perf_counter() - t0, curve_points(err), protocol, **extra))
    return out


def _corresponding_cell(problem: MatchProblem, bars: bool = True):
    """Errors of the sample map at the samples carried to the target (``MatchProblem.sample_map_errors``),
    and the exact fraction, LH05's recall and objective ratio and the sample map's bar."""
    sm, truth, src, carried = problem.sample_map, problem.sample_truth, problem.source, problem.target
    raw = problem.sample_map_errors
    extra = {"exact": float(np.mean(sm.t == truth))}
    if bars:
        extra.update(_bar_columns(problem.sample_bar))
    if sm.candidates is not None:
        extra["recall"] = recall(sm.candidates, truth)
    if "h" in sm.info:
        extra["objective_ratio"] = sm.info["objective"] / consistency.objective(src.D, carried.D, truth,
                                                                             fine_kernel(sm.info["h"]))
    return raw, raw, extra


def _independent_cell(problem: MatchProblem, tgt, bars: bool = True):
    """Errors of the dense map at the target's own samples ``tgt`` (the source vertex with the same id
    goes to each), of the sample map at the source's samples, and the dense map's bar."""
    m = problem.dense_match
    raw_s = None if m.sample_map is None else errors_from_rows(m.target.rows[m.sample_map.t], m.source.samples)
    return (errors_from_rows(tgt.rows, m.vertex_map[tgt.samples]), raw_s,
            _bar_columns(problem.error_bar) if bars else {})


def _bar_columns(bar: ErrorBar) -> dict:
    """The record's ``epsilon_hat`` and ``bar`` of an error bar (sqrt(area) units)."""
    return {"epsilon_hat": bar.epsilon_hat, "bar": bar.bar}


# --- the remeshed protocol ------------------------------------------------------------------------

def landmark_images(landmarks, ref_source, ref_target, solver) -> np.ndarray:
    """Target vertex of each source landmark through the reference points (module docstring).

    ``ref_source[j]``, ``ref_target[j]``: internal vertex of reference point ``j`` on
    each shape; ``solver``: geodesic rows of the source.  A landmark's image is that of
    the reference point on it (or nearest to it).  Two landmarks closer than the
    target's vertex spacing can reach one target vertex that way; the later one then
    takes the image of the nearest reference point whose target vertex is still free,
    so that the landmark pairs stay a correspondence (off by at most about one vertex
    spacing, as the ground truth of a remeshed release is).
    """
    first = {}
    for j, v in enumerate(ref_source.tolist()):
        first.setdefault(v, j)
    out = []
    for v in np.asarray(landmarks, dtype=np.int64).tolist():
        j = first.get(v)
        if j is None or int(ref_target[j]) in out:
            d = solver.distances([v])[0][ref_source]
            j = next((int(i) for i in np.argsort(d, kind="stable") if int(ref_target[i]) not in out), None)
        if j is None:
            raise InputError(f"{len(out) + 1} landmarks need as many distinct target vertices among the "
                             "reference points")
        out.append(int(ref_target[j]))
    return np.asarray(out, dtype=np.int64)


def reference_errors(target, ref_target, predictions: dict, backend: str, mirror=None):
    """Raw geodesic errors at the reference points of every prediction, with the target's scale.

    Parameters
    ----------
    target : Geometry.
    ref_target : (R,) internal target vertex of each reference point (the truth).
    predictions : key -> (R,) predicted target vertex of each reference point.
    mirror : (R,) internal target vertex of each reference point's mirror image, or None.

    Returns
    -------
    (errors: key -> (R,) float64, diameter estimate, mean distance between mirror images or NaN)
    """
    solver = DistanceSolver(target, backend)
    sources, which = np.unique(ref_target, return_inverse=True)
    errors = {k: np.empty(ref_target.size) for k in predictions}
    mirror_d = np.full(ref_target.size, np.nan)
    diameter = 0.0
    for lo in range(0, sources.size, ROW_BLOCK):
        rows = solver.distances(sources[lo:lo + ROW_BLOCK])
        diameter = max(diameter, float(rows.max()))
        sel = np.flatnonzero((which >= lo) & (which < lo + ROW_BLOCK))
        r = which[sel] - lo
        for k, pred in predictions.items():
            errors[k][sel] = rows[r, pred[sel]]
        if mirror is not None:
            mirror_d[sel] = rows[r, mirror[sel]]
    return errors, diameter, float(np.mean(mirror_d)) if mirror is not None else math.nan


def _mirror_images(cls: ClassFolder, target_path, geometry, ref_target) -> np.ndarray | None:
    """Target vertex of each reference point's mirror image: ``.sym.vts`` of the target, else
    ``reference.sym`` (``datasets``), else None."""
    p = cls.mirror_path(target_path)
    if p is not None:
        ids = read_vts(p, int(geometry.ids.max()) + 1, f"{cls.name}/corres/{p.name}")
        if ids.size != ref_target.size:
            raise InputError(f"{cls.name}/corres/{p.name} has {ids.size} lines for {ref_target.size} reference points")
        return geometry.to_internal(ids)
    sym = reference_symmetry(cls, ref_target.size)
    return None if sym is None else ref_target[sym]


def _reference_ids(cls: ClassFolder, shape_path, geometry) -> np.ndarray:
    n_file = int(geometry.ids.max()) + 1
    ids = read_vts(cls.vts_path(shape_path), n_file, f"{cls.name}/corres/{shape_path.stem}.vts")
    return geometry.to_internal(ids)


def _remeshed(cls, target_path, landmark_sets, setup: MatchingSetup, load) -> list:
    """The remeshed protocol (module docstring): dense maps, errors at the reference points."""
    s = setup.shape
    null, g = load(cls.null), load(target_path)
    ref_s, ref_t = _reference_ids(cls, cls.null, null), _reference_ids(cls, target_path, g)
    if ref_s.size != ref_t.size:
        raise InputError(f"{cls.name}: {cls.null.stem} has {ref_s.size} reference points but {g.name} has "
                         f"{ref_t.size}")
    sampled = any(m in SAMPLE_MATCHERS for m in setup.matchers)
    # the sample matchers' samples, and those of the error bars
    src = sample_surface(null, s.n_points, s.backend, s.seed, cache=s.cache) if sampled or setup.error_bars else None
    tgt = sample_surface(g, s.n_points, s.backend, s.seed, cache=s.cache) if sampled else None
    solvers = (CachedSolver(null, s.backend, src), CachedSolver(g, s.backend, tgt))
    images = {m: landmark_images(lm, ref_s, ref_t, solvers[0]) for m, lm in landmark_sets.items()}
    maps, seconds, bars = {}, {}, {}
    for cell in _cells(landmark_sets, setup, setup.matchers):
        method, c, matcher = cell
        t0 = time.perf_counter()
        ls, lt = landmark_sets[method][:c], images[method][:c]
        problem = MatchProblem(null, g, ls, lt, setup.options(matcher), surfaces=(src, tgt), solvers=solvers)
        maps[cell], seconds[cell] = problem.vertex_map[ref_s], time.perf_counter() - t0
        bars[cell] = _bar_columns(problem.error_bar) if setup.error_bars else {}
    mirror_t = _mirror_images(cls, target_path, g, ref_t)
    raw, diameter, mirror = reference_errors(g, ref_t, maps, s.backend, mirror_t)
    unit = surface_unit(g, diameter)
    out = []
    for (method, c, matcher), e in raw.items():
        err = normalise(e, diameter)
        flipped = float(e.mean() > 0.5 * mirror) if mirror_t is not None else math.nan
        out.append(MatchRecord(cls.name, g.name, method, c, matcher, float(err.mean()), float(e.mean() / unit),
                               math.nan, seconds[(method, c, matcher)], curve_points(err), "remeshed",
                               flipped=flipped, **bars[(method, c, matcher)]))
    return out

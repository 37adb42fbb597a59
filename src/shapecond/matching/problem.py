"""One matched pair: both shapes, their samples and solvers, the landmark pairs, and what is read off them.

A match (``pipeline``'s module docstring) runs in stages that read each
other's results: the sampled surfaces (landmarks first), the sample map, the
dense map, the error bar read off the dense map (``error_bar``), the next
landmarks read off the bar (``suggest``), and, when a ground truth is known,
the map's errors.  ``MatchProblem`` owns one pair and each of these results:
the landmark pairs are checked once, when it is made, every stage is computed
on first use and kept, and a later stage reads the earlier ones instead of
computing them again (the bar reads the samples the matcher used; the
suggestions read the bar's samples and target distances).  ``sc.match``,
``sc.deformation_level`` and the evaluation's protocols all match through it,
and a match page draws what it computed.

Samples.  The sample matchers (``"lh05"``, ``"faq"``) sample both shapes with
N points, landmarks first; with ``samples="same-ids"`` the target is sampled
at the source's sample vertices (``sampled.carry_samples``, the paper's κ
setting).  The zoomout matcher samples only the source, once, on the samples
the bar will read: ``BAR_SAMPLES`` of them when it compares its two starts on
them (more than 3 landmarks, ``pipeline``'s docstring), else N.

Solvers.  Given ``solvers`` (the evaluation shares one per shape between all the
matchings of a target), every stage uses them.  Without, each stage solves with
its own, except that the bar reads the target with the factorisation the target
was sampled with (``solvers``: the same factor, the same rows, one heat-method
factorisation less); rows are not shared between stages otherwise, since one
shared solver would solve other blocks of sources, and the heat method's rows
differ with the block in the last bits.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cached_property

import numpy as np

from shapecond.errors import InputError
from shapecond.matching.candidates import check_landmarks
from shapecond.matching.dense import DENSE_METHODS, dense_map
from shapecond.matching.error_bar import ErrorBar, bar_and_samples, bar_surface, map_distortion, sample_map_bar
from shapecond.matching.metrics import errors_from_rows, normalise
from shapecond.matching.pipeline import (MIN_ZOOMOUT_LANDMARKS, DenseMatch, MatchOptions, anchors_of,
                                         comparison_samples, dense_stage, landmark_sides, match_landmarks_only,
                                         match_samples, sample_sides)
from shapecond.matching.sampled import (CachedSolver, SampledSurface, carry_samples, insert_landmarks, sample_surface,
                                        surface_unit)
from shapecond.matching.spectral import SampleMatch
from shapecond.matching.suggest import Suggestion, suggest_landmarks
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.sampling import farthest_point_sampling

#: Source samples the errors against a ground truth are measured at (``MatchProblem.truth_errors``).
TRUTH_SAMPLES = 200


def landmark_pair(source_geometry, target_geometry, landmarks_source, landmarks_target,
                  options: MatchOptions) -> tuple[np.ndarray, np.ndarray]:
    """The landmark pairs of a match as two int64 arrays of internal vertex ids, once they are fit for it.

    Refused (``InputError``): counts that differ, an id that is not a vertex, a repeated landmark
    (``candidates.check_landmarks``), fewer than ``MIN_ZOOMOUT_LANDMARKS`` pairs for the zoomout
    matcher, more samples than vertices or landmarks than samples, and for ``samples="same-ids"``
    target landmarks that are not the source's.
    """
    ls, lt = check_landmarks(source_geometry.n_vertices, target_geometry.n_vertices, landmarks_source,
                             landmarks_target)
    if options.matcher == "zoomout":
        if ls.size < MIN_ZOOMOUT_LANDMARKS:
            raise InputError(f"the zoomout matcher needs at least {MIN_ZOOMOUT_LANDMARKS} landmark pairs, "
                             f"got {ls.size}")
        return ls, lt
    n = min(source_geometry.n_vertices, target_geometry.n_vertices)
    if options.n_points > n:
        raise InputError(f"{options.n_points} samples requested but a shape has only {n} vertices")
    if ls.size > options.n_points:
        raise InputError(f"{ls.size} landmarks but only {options.n_points} samples")
    if options.samples == "same-ids" and not np.array_equal(ls, lt):
        raise InputError("with same-ids samples the target landmarks must be the source's vertex ids")
    return ls, lt


class MatchProblem:
    """One pair of shapes matched with landmark pairs fixed, and every result read off the match.

    Parameters
    ----------
    source, target : Geometry of the two shapes (the map goes source to target).
    landmarks_source, landmarks_target : internal vertex ids of corresponding landmarks, same order;
        checked here, once (``landmark_pair``).
    options : MatchOptions.
    surfaces : (source, target) SampledSurfaces to match on instead of sampling the shapes (the
        evaluation's shared samples; the landmarks are inserted, ``sampled.insert_landmarks``); None each
        to sample.  The target's is ignored by the zoomout matcher, and with ``samples="same-ids"``.
    solvers : (source, target) distance solvers (``sampled.CachedSolver``) every stage shares, or None
        (module docstring).

    Notes
    -----
    Every result is computed on first use and kept: ``source``/``target`` (the sampled surfaces),
    ``sample_map``, ``dense_match``, ``epsilon_hat``, ``error_bar``/``doubt``, ``sample_bar``,
    ``suggest(k)`` and ``truth_errors(truth)``.

    Examples
    --------
    >>> from shapecond.shapes.synthetic import animal
    >>> g = animal(resolution=0.08)   # a coarse animal (942 vertices)
    >>> p = MatchProblem(g, g, [0, 100, 200], [0, 100, 200], MatchOptions(n_points=40, dense="nearest", cache=False))
    >>> p.vertex_map.shape == (g.n_vertices,) and p.error_bar is p.error_bar   # computed once, kept
    True
    """

    def __init__(self, source, target, landmarks_source, landmarks_target, options: MatchOptions = MatchOptions(),
                 *, surfaces=(None, None), solvers=None):
        self.source_geometry, self.target_geometry, self.options = source, target, options
        self.landmarks_source, self.landmarks_target = landmark_pair(source, target, landmarks_source,
                                                                     landmarks_target, options)
        self._given, self._solvers = tuple(surfaces), solvers
        self._sampling_solver = None  # the target's, while the bar may still read with it (``solvers``)
        self._suggestions: dict = {}
        self._truth_errors: dict = {}

    @property
    def n_landmarks(self) -> int:
        """The number of landmark pairs."""
        return int(self.landmarks_source.size)

    def _stage_solvers(self) -> tuple:
        """The solvers the sampling and matching stages are given (module docstring): the shared ones, or
        none (each makes its own)."""
        return self._solvers if self._solvers is not None else (None, None)

    @cached_property
    def source(self) -> SampledSurface:
        """The source's samples with their distance rows, its landmarks first (``sampled.SampledSurface``).

        Sampled once (module docstring): N farthest points (``sampled.sample_surface``), or the given
        surface with the landmarks inserted; for the zoomout matcher with more than 3 landmarks, the
        ``BAR_SAMPLES`` on which it compares its starts and the bar reads the map.
        """
        o, given = self.options, self._given[0]
        if o.matcher == "zoomout" and self.n_landmarks > MIN_ZOOMOUT_LANDMARKS:
            return comparison_samples(self.source_geometry, self.landmarks_source, o)
        if given is not None:
            return insert_landmarks(given, self.landmarks_source, self._stage_solvers()[0])[0]
        return sample_surface(self.source_geometry, o.n_points, o.backend, o.seed, self.landmarks_source, o.cache)

    @cached_property
    def _carried(self) -> tuple[SampledSurface | None, np.ndarray | None]:
        """(target SampledSurface, the target sample holding each source sample's vertex, or None): with
        ``samples="same-ids"`` the source's samples carried over in a seeded order
        (``sampled.carry_samples``), else the target's own, landmarks first; (None, None) for the zoomout
        matcher."""
        o, given = self.options, self._given[1]
        if o.matcher == "zoomout":
            return None, None
        if o.samples == "same-ids":
            return carry_samples(self.source, self.target_geometry, self._stage_solvers()[1], o.seed)
        if given is not None:
            return insert_landmarks(given, self.landmarks_target, self._stage_solvers()[1])[0], None
        solver = self._stage_solvers()[1]
        if solver is None:  # kept until the bar has read the target with it (``solvers``)
            solver = self._sampling_solver = CachedSolver(self.target_geometry, o.backend)
        return sample_surface(self.target_geometry, o.n_points, o.backend, o.seed, self.landmarks_target,
                              o.cache, solver), None

    @property
    def _target_landmarks(self) -> np.ndarray:
        """The sample index on ``target`` of each target landmark."""
        truth = self._carried[1]
        return np.arange(self.n_landmarks, dtype=np.int64) if truth is None else truth[:self.n_landmarks]

    @property
    def target(self) -> SampledSurface | None:
        """The target's samples (``source``'s carried over with ``samples="same-ids"``); None for the
        zoomout matcher, which samples no target."""
        return self._carried[0]

    def solvers(self) -> tuple:
        """(source, target) distance solvers: the given ones, or ``sampled.CachedSolver``s that know the
        rows of ``source`` and ``target`` (what the bar reads the target's distances with).  The target's
        is the one it was sampled with while the bar has not been computed (no second heat-method
        factorisation: 1.4 s CPU at 52,565 vertices; the same factor, the same rows), else a new one;
        none is kept after the bar: a problem kept by a result (``MatchResult.problem``) holds no
        factorisation and no rows beyond its samples'."""
        if self._solvers is not None:
            return self._solvers
        o = self.options
        target = self.target
        sampling = self._sampling_solver
        if sampling is not None and target is not None:
            sampling.remember(target)
        return (CachedSolver(self.source_geometry, o.backend, self.source),
                sampling if sampling is not None else CachedSolver(self.target_geometry, o.backend, target))

    @cached_property
    def sample_map(self) -> SampleMatch | None:
        """The map between the samples, landmark pairs fixed and the landmarks' sides read
        (``pipeline.match_samples``, ``pipeline.sample_sides``): LH05 on the N samples is the matching of
        the paper's evaluation (Section 7), FAQ the seeded alternative; None for the zoomout matcher."""
        if self.target is None:
            return None
        source, target, lt = self.source, self.target, self._target_landmarks
        ls = np.arange(self.n_landmarks, dtype=np.int64)
        sides = sample_sides(source, ls, target, lt, self._sides)
        return match_samples(source.D, target.D, ls, lt, self.options.sample_options(sides))

    @cached_property
    def _sides(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The sides of the landmark pairs at every vertex of both shapes (``pipeline.landmark_sides``),
        read by the sample matcher at the samples and by the dense stage's anchors: computed once (0.3 s
        CPU less at 52,565 vertices); None for point clouds, fewer than 2 landmarks and the zoomout
        matcher."""
        if self.target is None:
            return None
        ls = np.arange(self.n_landmarks, dtype=np.int64)
        return landmark_sides(self.source, ls, self.target, self._target_landmarks)

    @cached_property
    def dense_match(self) -> DenseMatch:
        """The map of every source vertex (``pipeline.DenseMatch``): the sample map extended
        (``dense.dense_map``) and refined by the dense stage (``pipeline.dense_stage``), or the zoomout
        matcher's (``pipeline.match_landmarks_only``); the landmarks go exactly onto their images."""
        o, ls, lt = self.options, self.landmarks_source, self.landmarks_target
        if o.matcher == "zoomout":
            compared = self.source if self.n_landmarks > MIN_ZOOMOUT_LANDMARKS else None
            return match_landmarks_only(self.source_geometry, self.target_geometry, ls, lt, o, self._stage_solvers(),
                                        compared)
        source, target, sm = self.source, self.target, self.sample_map
        if o.dense in DENSE_METHODS:
            vmap = dense_map(source, target, sm.t, method=o.dense)
        else:
            carried = self._carried[1] is not None  # same-ids: the target's landmarks are shuffled among its samples
            anchors = anchors_of(source, target, self.n_landmarks, self._target_landmarks if carried else None)
            if self._sides is not None:  # the sides the sample matcher read: ``Anchors.oriented`` keeps them
                anchors = replace(anchors, source_sides=self._sides[0], target_sides=self._sides[1])
            vmap = dense_stage(source.geometry, target.geometry, dense_map(source, target, sm.t), anchors, o)
        vmap[ls] = lt
        info = dict(matcher=o.matcher, dense=o.dense, n_landmarks=self.n_landmarks)
        if o.samples == "same-ids":
            info.update(samples="same-ids", **self._sample_errors())
        return DenseMatch(vmap, sm, source, target, info)

    def _sample_errors(self) -> dict:
        """``sample_error`` (% of half the target's diameter) and ``exact`` (the fraction of samples mapped
        exactly) of the sample map with ``samples="same-ids"``, whose truth is known."""
        return dict(sample_error=float(normalise(self.sample_map_errors, self.target.diameter).mean()),
                    exact=float(np.mean(self.sample_map.t == self.sample_truth)))

    @property
    def sample_truth(self) -> np.ndarray | None:
        """With ``samples="same-ids"``: the target sample holding each source sample's vertex (the true
        sample map, ``sampled.carry_samples``); else None."""
        return self._carried[1]

    @cached_property
    def sample_map_errors(self) -> np.ndarray:
        """With ``samples="same-ids"``: the target's geodesic distance (raw units) between the image of each
        source sample and its true image (``metrics.errors_from_rows``)."""
        if self.sample_truth is None:
            raise InputError("the sample map's errors need the true sample map: samples 'same-ids'")
        return errors_from_rows(self.target.rows[self.sample_truth], self.target.samples[self.sample_map.t])

    @property
    def vertex_map(self) -> np.ndarray:
        """(n_source,) internal target vertex of every source vertex (``dense_match.vertex_map``)."""
        return self.dense_match.vertex_map

    @cached_property
    def epsilon_hat(self) -> float:
        """ε̂, the map's RMS distortion on the bar's samples (``error_bar.map_distortion``; sqrt(area) units):
        the level a deformation is read at (``api.level``); the error bar's when it is computed."""
        if "_bar" in self.__dict__:
            return self._bar[0].epsilon_hat
        coarse = bar_surface(self.source, self.n_landmarks)
        return map_distortion(coarse, self.target_geometry, self.vertex_map[coarse.samples], self.solvers()[1])

    @cached_property
    def _bar(self) -> tuple[ErrorBar, SampledSurface, np.ndarray]:
        """(ErrorBar, the bar's samples, the target's distances between their images): the dense map's bar
        on the first ``BAR_SAMPLES`` samples of ``source`` (``error_bar.bar_and_samples``), no new samples."""
        bar = bar_and_samples(self.source, self.target_geometry, self.vertex_map, self.n_landmarks,
                              self.options.seed, self.solvers()[1])
        self._sampling_solver = None  # its factorisation is not needed any more (``solvers``)
        return bar

    @property
    def error_bar(self) -> ErrorBar:
        """The dense map's error bar, δ(ε̂) without ground truth (``matching.error_bar``)."""
        return self._bar[0]

    @cached_property
    def doubt(self) -> np.ndarray:
        """(n_source,) the bar's doubt at every source vertex, from its nearest bar sample (sqrt(area))."""
        bar, coarse, _ = self._bar
        return bar.doubt[coarse.nearest]

    @cached_property
    def sample_bar(self) -> ErrorBar:
        """The error bar of the sample map, on the bar's samples (``error_bar.sample_map_bar``; the
        evaluation's corresponding protocol, which has no dense map)."""
        return sample_map_bar(self.source, self.target, self.sample_map.t, self.n_landmarks, self.options.seed)

    def suggest(self, k: int = 1) -> list[Suggestion]:
        """The ``k`` next landmarks of this match, in order (``matching.suggest``: CNBS's greedy step run
        on the pair, paper Section 5), read off the error bar's samples; kept per ``k``."""
        if k not in self._suggestions:
            bar, coarse, images = self._bar
            self._suggestions[k] = suggest_landmarks(coarse, images, bar, self.n_landmarks, self.vertex_map,
                                                     self.target_geometry.ids, k=k, seed=self.options.seed)
        return self._suggestions[k]

    def truth_errors(self, truth, n_points: int = TRUTH_SAMPLES) -> tuple[np.ndarray, np.ndarray]:
        """The map's errors against a ground truth (``truth_errors``, module function), kept per truth."""
        raw, samples, diameter = self._truth(truth, n_points)
        return normalise(raw, diameter), samples

    def truth_summary(self, truth, n_points: int = TRUTH_SAMPLES) -> dict:
        """The map's errors against a ground truth in the field's two units (``truth_errors``): mean,
        median and worst in sqrt(area) of the target and in % of half its diameter, the share of the
        measured points within 0.05 sqrt(area), and the number of points measured.  A point cloud has no
        area: its errors are then in units of its diameter (``unit`` says which)."""
        raw, samples, diameter = self._truth(truth, n_points)
        area = normalise(raw, diameter, surface_unit(self.target_geometry, diameter) ** 2, "sqrt_area")
        half = normalise(raw, diameter)
        return {"mean": float(area.mean()), "median": float(np.median(area)), "worst": float(area.max()),
                "within_0.05": float(np.mean(area <= 0.05)),
                "unit": "sqrt(area)" if self.target_geometry.faces is not None else "diameter",
                "mean_percent_half_diameter": float(half.mean()), "n_points": int(samples.size)}

    def _truth(self, truth, n_points):
        truth = np.asarray(truth, dtype=np.int64)
        key = (truth.tobytes(), int(n_points))
        if key not in self._truth_errors:
            self._truth_errors[key] = _truth_raw(self.source_geometry, self.target_geometry, self.vertex_map,
                                                 truth, n_points)
        return self._truth_errors[key]


def truth_errors(source_geometry, target_geometry, vertex_map, truth, n_points: int = TRUTH_SAMPLES,
                 backend: str = "heat") -> tuple[np.ndarray, np.ndarray]:
    """Errors of a dense map (internal ids) against a ground truth, % of half the target's diameter.

    The geodesic distance on the target between the matched and the true vertex is measured at
    ``n_points`` farthest-point samples (Euclidean FPS) of the source vertices that have both a match
    and a true image (all of them for a complete ground truth; the reference vertices for a truth of
    ``.vts`` files).

    Parameters
    ----------
    source_geometry, target_geometry : Geometry.
    vertex_map : (n_source,) target internal vertex of every source vertex (-1: none).
    truth : (n_source,) the true target internal vertex of every source vertex (-1: unknown).

    Returns
    -------
    (errors at the samples, their source internal vertices)
    """
    raw, samples, diameter = _truth_raw(source_geometry, target_geometry, vertex_map, truth, n_points, backend)
    return normalise(raw, diameter), samples


def _truth_raw(source_geometry, target_geometry, vertex_map, truth, n_points, backend="heat"):
    """(raw geodesic errors, their source samples, the target's diameter as the rows read it) of
    ``truth_errors``."""
    known = np.flatnonzero((vertex_map >= 0) & (truth >= 0))
    if not known.size:
        raise InputError("no source vertex has both a match and a ground-truth image")
    solver = DistanceSolver(source_geometry, "euclidean")
    if known.size < source_geometry.n_vertices:
        solver = _Among(solver, known)
    k = min(int(n_points), solver.n)
    picked = np.asarray(farthest_point_sampling(solver, k, seed=0).samples, np.int64) if k >= 3 else np.arange(k)
    samples = known[picked] if known.size < source_geometry.n_vertices else picked
    rows = DistanceSolver(target_geometry, backend).distances(truth[samples])
    return errors_from_rows(rows, vertex_map[samples]), samples, float(rows.max()) or 1.0


class _Among:
    """A distance solver restricted to the vertices ``keep`` (rows and columns), for sampling among them."""

    block = 1

    def __init__(self, solver, keep):
        self.solver, self.keep, self.n = solver, np.asarray(keep), len(keep)

    def distances(self, sources):
        return self.solver.distances(self.keep[np.atleast_1d(sources)])[:, self.keep]


def match_shapes(source_geometry, target_geometry, landmarks_source, landmarks_target,
                 options: MatchOptions = MatchOptions()) -> DenseMatch:
    """Sample both shapes (landmarks first) and match them, source to target (``MatchProblem.dense_match``).

    With ``options.samples == "same-ids"`` the two shapes share their vertex
    order (a class of TOSCA, say) and the target is sampled at the source's
    sample vertices (``sampled.carry_samples``, the evaluation's *corresponding*
    protocol): the true sample map is known, and ``info`` reports its error
    (``sample_error``, % of half the target's geodesic diameter) and the fraction
    of samples matched exactly (``exact``).  The target landmarks must then be
    the source's.

    Parameters
    ----------
    source_geometry, target_geometry : Geometry
    landmarks_source, landmarks_target : sequences of int
        Internal vertex indices of corresponding landmarks (same count).
    options : MatchOptions
    """
    return MatchProblem(source_geometry, target_geometry, landmarks_source, landmarks_target, options).dense_match


def match_surfaces(source: SampledSurface, target: SampledSurface, landmarks_source, landmarks_target,
                   options: MatchOptions = MatchOptions(), solvers=(None, None)) -> DenseMatch:
    """Match two sampled surfaces whose landmark vertices (internal ids) are given
    (``MatchProblem.dense_match`` on these surfaces).

    Landmarks that are not samples yet are inserted (``sampled.insert_landmarks``,
    with the optional ``solvers``, e.g. ``sampled.CachedSolver``, for their rows).
    """
    return MatchProblem(source.geometry, target.geometry, landmarks_source, landmarks_target, options,
                        surfaces=(source, target), solvers=tuple(solvers)).dense_match

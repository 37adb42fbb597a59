"""Landmark-guided matching of two shapes, end to end, source to target.

    geometry -> sampled surface (FPS, landmarks first) -> sample map (LH05 or FAQ)
             -> dense map (one target vertex per source vertex)
             -> dense stage (landmark-anchored ZoomOut on the Laplace–Beltrami bases)

Both shapes are sampled with ``N`` points, their sample distances expressed in
units of ``sqrt(area)`` (``sampled.py``), the samples matched with the landmark
pairs fixed (``spectral.lh05_match`` or ``seeded.faq_match``), the sample map
extended to every source vertex (``dense.dense_map``) and, by default, that
vertex map refined by ``zoomout.zoomout`` with the landmark pairs as anchors.
The paper matches samples only; the dense stage is what makes the map usable
between differently meshed shapes: on independently remeshed TOSCA pairs it
takes LH05's extended maps from 0.03–0.13 sqrt(area) to 0.01–0.03.

Off isometry (two bodies, two species) distances alone leave a map and its composition with a
reflection that keeps the landmarks apart by nothing: every stage also reads on which side of each
pair of landmarks a point lies (``orientation``): the sample matchers' descriptors (``sample_sides``;
the nested runs with the first 3 landmarks keep the sides of every pair, a start, not a constraint),
the zoomout matcher's start and the dense stage's anchors (SMAL_r, cow to 8 other species, 6
landmarks: FAQ 0.060 → 0.040 sqrt(area), LH05 0.093 → 0.048, zoomout 0.096 → 0.050).  And the dense
stage, whose fixed point was the limit (started from the *true* map it ended at 0.042), also compares the
landmarks' harmonic coordinates (``harmonic``), which a change of proportions keeps (same pairs: FAQ
0.040 → 0.037, LH05 0.048 → 0.038, zoomout 0.050 → 0.040).

The third matcher, ``"zoomout"``, needs no samples: each vertex is described by
its geodesic distances to the landmarks, the initial map sends every source
vertex to the target vertex with the nearest description, and the dense stage
refines it.  It needs at least 3 landmarks (fewer cannot exclude the isometries
of a surface, so its start would be ambiguous).  More landmarks must never cost
it accuracy, but a description by more geodesic distances is not always a
better start: where a pose changes some landmark distances a lot (limbs that
touch the body, TOSCA gorilla), the nearest description goes wrong, and ZoomOut
does not recover (remeshed gorilla0 → gorilla8, CNBS-scale landmarks: 0.056
sqrt(area) with 3, 0.131 with 6).  So with more than 3 landmarks it also starts
from the first 3 landmarks' descriptions, anchors both runs with every
landmark, and keeps the map that distorts the source's sample distances less
(``error_bar.map_distortion``): the matcher's own criterion, no ground truth,
and never a more distorted map than the first 3 landmarks lead to (same pair:
0.036 with 6).  Less distortion is not always less error: on the paper's 8
remeshed classes the rule changed one of 40 all-landmark results, for the worse
(cat, PLS landmarks: 0.027 → 0.030).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from shapecond.errors import InputError
from shapecond.matching.dense import DENSE_METHODS, dense_map
from shapecond.matching.error_bar import BAR_SAMPLES, map_distortion
from shapecond.matching.orientation import orientation_features
from shapecond.matching.metrics import errors_from_rows, normalise
from shapecond.matching.sampled import (CachedSolver, SampledSurface, carry_samples, insert_landmarks,
                                        sample_surface, surface_unit)
from shapecond.matching.seeded import FAQOptions, faq_match
from shapecond.matching.spectral import LH05Options, SampleMatch, lh05_match
from shapecond.matching.zoomout import Anchors, ZoomOutOptions, anchor_width, nearest_rows, zoomout
from shapecond.shapes.laplace import laplace_basis

#: Matchers: two on samples (then extended and refined), one from the landmarks alone.
MATCHERS = ("lh05", "faq", "zoomout")
SAMPLE_MATCHERS = ("lh05", "faq")
#: Which samples the target gets (``match_shapes``): its own FPS samples, or the source's vertex ids.
SAMPLINGS = ("fps", "same-ids")
#: How the map reaches every vertex: the dense stage (default) or one of the plain extensions.
DENSE_STAGES = ("zoomout",) + DENSE_METHODS
#: Landmarks the zoomout matcher needs (module docstring).
MIN_ZOOMOUT_LANDMARKS = 3


@dataclass(frozen=True)
class MatchOptions:
    """How two shapes are matched (``match_shapes``).

    Attributes
    ----------
    matcher : one of ``MATCHERS``.
    n_points : N, samples per shape (the sample matchers).
    backend : geodesic backend (``shapecond.shapes.geodesics``).
    seed : seed of FPS's start, FAQ and the sample shuffle.
    dense : one of ``DENSE_STAGES``.
    samples : one of ``SAMPLINGS``.
    cache : read and write the on-disk cache.
    zoomout : options of the dense stage.
    matcher_options : the sample matcher's options, ``LH05Options`` or ``FAQOptions`` (its ``seed`` is
        the sample matcher's); None: ``sample_matcher_options(matcher, seed)``.
    """

    matcher: str = "lh05"
    n_points: int = 400
    backend: str = "heat"
    seed: int = 0
    dense: str = "zoomout"
    samples: str = "fps"
    cache: bool = True
    zoomout: ZoomOutOptions = ZoomOutOptions()
    matcher_options: LH05Options | FAQOptions | None = None

    def __post_init__(self):
        for name, value, allowed in (("matcher", self.matcher, MATCHERS), ("dense", self.dense, DENSE_STAGES),
                                     ("samples", self.samples, SAMPLINGS)):
            if value not in allowed:
                raise InputError(f"unknown {name} {value!r} (choose from {', '.join(allowed)})")
        if self.matcher == "zoomout" and self.samples != "fps":
            raise InputError("the zoomout matcher uses no samples: samples 'same-ids' does not apply")
        if self.matcher_options is None and self.matcher in SAMPLE_MATCHERS:
            object.__setattr__(self, "matcher_options", sample_matcher_options(self.matcher, self.seed))

    def sample_options(self, sides):
        """The sample matcher's options with the side features ``sides`` of the samples (``sample_sides``)
        unless they have their own."""
        o = self.matcher_options
        return o if o.sides is not None else replace(o, sides=sides)


@dataclass(frozen=True, eq=False)
class DenseMatch:
    """Result of ``match_shapes`` / ``match_surfaces``.

    Attributes
    ----------
    vertex_map : (n_source,) int64 internal target vertex of every source vertex.
    sample_map : SampleMatch between ``source.samples`` and ``target.samples`` (None: zoomout matcher).
    source, target : SampledSurface used (landmarks are their first samples).  Zoomout matcher: no
        target, and as source the samples its two starts were compared on (None with 3 landmarks),
        which the error bar reads the map's distortion on without sampling the source again.
    info : dict of diagnostics.
    target_solver : the target's distance solver the target was sampled with (``match_shapes``), or
        None: the error bar's rows of the target without a second factorisation (1.4 s CPU at 52k
        vertices).
    """

    vertex_map: np.ndarray
    sample_map: SampleMatch | None
    source: SampledSurface | None
    target: SampledSurface | None
    info: dict = field(default_factory=dict)
    target_solver: CachedSolver | None = None


def sample_matcher_options(matcher: str, seed: int = 0) -> LH05Options | FAQOptions:
    """The default options of the sample matcher ``matcher`` ("lh05" or "faq"; FAQ's with ``seed``)."""
    return LH05Options() if matcher == "lh05" else FAQOptions(seed=seed)


def match_samples(D_source, D_target, landmarks_source, landmarks_target,
                  options: LH05Options | FAQOptions = LH05Options()) -> SampleMatch:
    """``lh05_match`` or ``faq_match``, as the type of ``options`` says."""
    matcher = faq_match if isinstance(options, FAQOptions) else lh05_match
    return matcher(D_source, D_target, landmarks_source, landmarks_target, options)


def anchors_of(source: SampledSurface, target: SampledSurface, n_landmarks: int) -> Anchors:
    """The first ``n_landmarks`` samples of two sampled surfaces (their landmark pairs) as anchors."""
    L = int(n_landmarks)
    return Anchors(source.samples[:L], target.samples[:L], source.rows[:L] / source.unit,
                   target.rows[:L] / target.unit)


def dense_stage(source_geometry, target_geometry, initial, anchors: Anchors | None,
                options: MatchOptions = MatchOptions()) -> np.ndarray:
    """The vertex map ``initial`` refined by landmark-anchored ZoomOut on both shapes' bases."""
    bs = laplace_basis(source_geometry, cache=options.cache)
    bt = laplace_basis(target_geometry, cache=options.cache)
    if anchors is not None:
        anchors = anchors.oriented(source_geometry, target_geometry).harmonic(
            source_geometry, target_geometry, anchor_width(bs, bt, options.zoomout))
    return zoomout(bs, bt, (source_geometry.vertices, target_geometry.vertices), initial, anchors, options.zoomout)


def match_surfaces(source: SampledSurface, target: SampledSurface, landmarks_source, landmarks_target,
                   options: MatchOptions = MatchOptions(), solvers=(None, None)) -> DenseMatch:
    """Match two sampled surfaces whose landmark vertices (internal ids) are given.

    Landmarks that are not samples yet are inserted (``sampled.insert_landmarks``,
    with the optional ``solvers``, e.g. ``sampled.CachedSolver``, for their rows).
    """
    ls, lt = _landmark_pair(landmarks_source, landmarks_target)
    source, ils = insert_landmarks(source, ls, solvers[0])
    target, ilt = insert_landmarks(target, lt, solvers[1])
    sm = match_samples(source.D, target.D, ils, ilt, options.sample_options(sample_sides(source, ils, target, ilt)))
    vmap = _extend(source, target, sm.t, ls.size, options)
    vmap[ls] = lt  # landmarks map exactly onto their images
    return DenseMatch(vmap, sm, source, target, dict(matcher=options.matcher, dense=options.dense,
                                                     n_landmarks=int(ls.size)))


def sample_sides(source: SampledSurface, landmarks_source, target: SampledSurface, landmarks_target):
    """(source, target) sides of the landmark pairs at the samples (``orientation``; landmarks given as
    sample indices), or None for point clouds and fewer than 2 landmarks."""
    fs = orientation_features(source.geometry, source.rows[np.asarray(landmarks_source)])
    ft = orientation_features(target.geometry, target.rows[np.asarray(landmarks_target)])
    return None if fs is None or ft is None else (fs[source.samples], ft[target.samples])


def _extend(source: SampledSurface, target: SampledSurface, t, n_landmarks: int, options: MatchOptions):
    if options.dense in DENSE_METHODS:
        return dense_map(source, target, t, method=options.dense)
    initial = dense_map(source, target, t, method="distances")
    return dense_stage(source.geometry, target.geometry, initial, anchors_of(source, target, n_landmarks), options)


def _landmark_pair(landmarks_source, landmarks_target) -> tuple[np.ndarray, np.ndarray]:
    ls = np.asarray(landmarks_source, dtype=np.int64).reshape(-1)
    lt = np.asarray(landmarks_target, dtype=np.int64).reshape(-1)
    if ls.size != lt.size:
        raise InputError(f"landmark counts differ: {ls.size} on the source, {lt.size} on the target")
    return ls, lt


def match_landmarks_only(source_geometry, target_geometry, landmarks_source, landmarks_target,
                         options: MatchOptions = MatchOptions(matcher="zoomout"), solvers=(None, None)) -> DenseMatch:
    """The zoomout matcher (module docstring): from the landmark pairs alone to a dense map.

    ``solvers``: optional distance solvers of the two shapes (e.g. ``sampled.CachedSolver``)
    for the landmarks' geodesic rows.
    """
    ls, lt = _landmark_pair(landmarks_source, landmarks_target)
    if ls.size < MIN_ZOOMOUT_LANDMARKS:
        raise InputError(f"the zoomout matcher needs at least {MIN_ZOOMOUT_LANDMARKS} landmark pairs, got {ls.size}")
    anchors = []
    for g, lm, solver in ((source_geometry, ls, solvers[0]), (target_geometry, lt, solvers[1])):
        if lm.min() < 0 or lm.max() >= g.n_vertices or np.unique(lm).size != lm.size:
            raise InputError(f"landmarks on {g.name} must be distinct vertices 0..{g.n_vertices - 1}")
        rows = (solver if solver is not None else CachedSolver(g, options.backend)).distances(lm)
        anchors.append(rows / surface_unit(g, float(rows.max())))
    anchor = Anchors(ls, lt, anchors[0], anchors[1])
    maps = [dense_stage(source_geometry, target_geometry, _nearest_description(source_geometry, target_geometry,
                                                                              anchor, k), anchor, options)
            for k in sorted({ls.size, MIN_ZOOMOUT_LANDMARKS})[::-1]]
    best, compared = _least_distorted(source_geometry, target_geometry, maps, ls, options, solvers[1])
    return DenseMatch(maps[best], None, compared, None,
                      dict(matcher="zoomout", dense="zoomout", n_landmarks=int(ls.size),
                           start="every landmark" if best == 0 else f"the first {MIN_ZOOMOUT_LANDMARKS} landmarks"))


def _nearest_description(source_geometry, target_geometry, anchor: Anchors, k: int) -> np.ndarray:
    """The zoomout matcher's start: every source vertex to the target vertex whose description by the
    first ``k`` landmarks is nearest: its geodesic distances to them (sqrt(area) units) and, on meshes,
    the side of every pair of them it lies on (``orientation``), which distances alone leave open."""
    first = Anchors(anchor.source[:k], anchor.target[:k], anchor.source_rows[:k], anchor.target_rows[:k])
    first = first.oriented(source_geometry, target_geometry)
    xs, xt = first.source_rows.T, first.target_rows.T
    if first.source_sides is not None:
        xs, xt = np.hstack([xs, first.source_sides]), np.hstack([xt, first.target_sides])
    return nearest_rows(xs, xt)


def _least_distorted(source_geometry, target_geometry, maps: list, landmarks, options: MatchOptions,
                     solver) -> tuple[int, SampledSurface | None]:
    """Index of the map that distorts the source's sample distances least (``error_bar.map_distortion`` on
    as many samples as the error bar's, landmarks first; the first of equals), and those samples (None:
    one map, nothing to compare)."""
    if len(maps) == 1:
        return 0, None
    src = sample_surface(source_geometry, min(options.n_points, BAR_SAMPLES), options.backend, options.seed,
                         landmarks, options.cache)
    solver = solver if solver is not None else CachedSolver(target_geometry, options.backend)
    costs = [map_distortion(src, target_geometry, m[src.samples], solver) for m in maps]
    return int(np.argmin(costs)), src


def match_shapes(source_geometry, target_geometry, landmarks_source, landmarks_target,
                 options: MatchOptions = MatchOptions()) -> DenseMatch:
    """Sample both shapes (landmarks first) and match them, source to target.

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
    ls, lt = _landmark_pair(landmarks_source, landmarks_target)
    if options.matcher == "zoomout":
        return match_landmarks_only(source_geometry, target_geometry, ls, lt, options)
    n = min(source_geometry.n_vertices, target_geometry.n_vertices)
    if options.n_points > n:
        raise InputError(f"{options.n_points} samples requested but a shape has only {n} vertices")
    src = sample_surface(source_geometry, options.n_points, options.backend, options.seed, ls, options.cache)
    if options.samples == "same-ids":
        return _match_same_ids(src, target_geometry, ls, lt, options)
    solver = CachedSolver(target_geometry, options.backend)
    tgt = sample_surface(target_geometry, options.n_points, options.backend, options.seed, lt, options.cache, solver)
    return replace(match_surfaces(src, tgt, ls, lt, options), target_solver=solver)


def _match_same_ids(src: SampledSurface, target_geometry, ls, lt, options: MatchOptions) -> DenseMatch:
    """``match_shapes`` with the target sampled at the source's sample vertices."""
    src, ils = insert_landmarks(src, ls)
    tgt, truth = carry_samples(src, target_geometry, seed=options.seed)  # refuses different vertex ids
    if not np.array_equal(ls, lt):
        raise InputError("with same-ids samples the target landmarks must be the source's vertex ids")
    sm = match_samples(src.D, tgt.D, ils, truth[ils], options.sample_options(sample_sides(src, ils, tgt, truth[ils])))
    if options.dense in DENSE_METHODS:
        vmap = dense_map(src, tgt, sm.t, method=options.dense)
    else:  # the carried samples are shuffled: the landmark pairs are (src.samples[i], tgt.samples[truth[i]])
        anchors = Anchors(src.samples[ils], tgt.samples[truth[ils]], src.rows[ils] / src.unit,
                          tgt.rows[truth[ils]] / tgt.unit)
        vmap = dense_stage(src.geometry, tgt.geometry, dense_map(src, tgt, sm.t), anchors, options)
    vmap[ls] = lt
    raw = errors_from_rows(tgt.rows[truth], tgt.samples[sm.t])
    info = dict(matcher=options.matcher, dense=options.dense, n_landmarks=int(ls.size), samples="same-ids",
                sample_error=float(normalise(raw, tgt.diameter).mean()),
                exact=float(np.mean(sm.t == truth)))
    return DenseMatch(vmap, sm, src, tgt, info)

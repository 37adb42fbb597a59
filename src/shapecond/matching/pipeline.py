"""The stages of landmark-guided matching, source to target (``problem.MatchProblem`` runs them for a pair).

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
(cat, PLS landmarks: 0.027 → 0.030).  Tried and not adopted: the landmarks' harmonic coordinates
(``harmonic``) in the start's description too.  Between species it kept the cow's head off a horse's
legs with PLS's landmarks (SMAL_r muybridge_097_01: 142 → 78 ×10⁻³ sqrt(area); the other 31 rows of 8
animals × 4 methods within ±5), but between poses it lost (TOSCA_r, one test pair per class, CNBS's
6 landmarks 32.2 → 36.0, cat2 → cat3 75 → 93; FPS's, PLS's and HKS's within ±0.8).

Between species the sample map, not the dense stage, is where the error is made: on the cow to 8
SMAL_r animals (FPS, PLS and CNBS landmarks, 6 exact: 24 rows) the true sample map snapped to the
target's samples and extended by ``dense.dense_map`` errs 21.3 ×10⁻³ sqrt(area), FAQ's sample map
extended the same way 84.5, and the dense stage takes FAQ's to 45.7.  Tried and not adopted: the dense
stage's map read back at the samples (a linear assignment to the target's samples) as the start of FAQ
on the distance or the local objective, then extended, then one whole-basis ZoomOut level: 52.8–80.6 on
the same rows (the sample objectives move the start away from the truth).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from shapecond.errors import InputError
from shapecond.matching.dense import DENSE_METHODS
from shapecond.matching.error_bar import BAR_SAMPLES, map_distortion
from shapecond.matching.orientation import orientation_features
from shapecond.matching.sampled import CachedSolver, SampledSurface, sample_surface, surface_unit
from shapecond.matching.seeded import FAQOptions, faq_match
from shapecond.matching.spectral import LH05Options, SampleMatch, lh05_match
from shapecond.matching.zoomout import Anchors, ZoomOutOptions, anchor_width, nearest_rows, zoomout
from shapecond.shapes.laplace import laplace_basis

#: Matchers: two on samples (then extended and refined), one from the landmarks alone.
MATCHERS = ("lh05", "faq", "zoomout")
SAMPLE_MATCHERS = ("lh05", "faq")
#: Which samples the target gets (``problem.MatchProblem``): its own FPS samples, or the source's vertex ids.
SAMPLINGS = ("fps", "same-ids")
#: How the map reaches every vertex: the dense stage (default) or one of the plain extensions.
DENSE_STAGES = ("zoomout",) + DENSE_METHODS
#: Landmarks the zoomout matcher needs (module docstring).
MIN_ZOOMOUT_LANDMARKS = 3


@dataclass(frozen=True)
class MatchOptions:
    """How two shapes are matched (``problem.MatchProblem``).

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
    """A dense map and what it was made from (``problem.MatchProblem.dense_match``).

    Attributes
    ----------
    vertex_map : (n_source,) int64 internal target vertex of every source vertex.
    sample_map : SampleMatch between ``source.samples`` and ``target.samples`` (None: zoomout matcher).
    source, target : SampledSurface used (landmarks are their first samples).  Zoomout matcher: no
        target, and as source the samples its two starts were compared on (None with 3 landmarks),
        which the error bar reads the map's distortion on without sampling the source again.
    info : dict of diagnostics.
    """

    vertex_map: np.ndarray
    sample_map: SampleMatch | None
    source: SampledSurface | None
    target: SampledSurface | None
    info: dict = field(default_factory=dict)


def sample_matcher_options(matcher: str, seed: int = 0) -> LH05Options | FAQOptions:
    """The default options of the sample matcher ``matcher`` ("lh05" or "faq"; FAQ's with ``seed``)."""
    return LH05Options() if matcher == "lh05" else FAQOptions(seed=seed)


def match_samples(D_source, D_target, landmarks_source, landmarks_target,
                  options: LH05Options | FAQOptions = LH05Options()) -> SampleMatch:
    """``lh05_match`` or ``faq_match``, as the type of ``options`` says."""
    matcher = faq_match if isinstance(options, FAQOptions) else lh05_match
    return matcher(D_source, D_target, landmarks_source, landmarks_target, options)


def anchors_of(source: SampledSurface, target: SampledSurface, n_landmarks: int, target_samples=None) -> Anchors:
    """The landmark pairs of two sampled surfaces as anchors: the first ``n_landmarks`` samples of
    ``source`` and, on ``target``, the samples ``target_samples`` (default: its first ``n_landmarks``;
    the carried samples of ``samples="same-ids"`` are shuffled)."""
    L = int(n_landmarks)
    t = slice(0, L) if target_samples is None else np.asarray(target_samples, dtype=np.int64)
    return Anchors(source.samples[:L], target.samples[t], source.rows[:L] / source.unit,
                   target.rows[t] / target.unit)


def dense_stage(source_geometry, target_geometry, initial, anchors: Anchors | None,
                options: MatchOptions = MatchOptions()) -> np.ndarray:
    """The vertex map ``initial`` refined by landmark-anchored ZoomOut on both shapes' bases."""
    bs = laplace_basis(source_geometry, cache=options.cache)
    bt = laplace_basis(target_geometry, cache=options.cache)
    if anchors is not None:
        anchors = anchors.oriented(source_geometry, target_geometry).harmonic(
            source_geometry, target_geometry, anchor_width(bs, bt, options.zoomout))
    return zoomout(bs, bt, (source_geometry.vertices, target_geometry.vertices), initial, anchors, options.zoomout)


def landmark_sides(source: SampledSurface, landmarks_source, target: SampledSurface, landmarks_target):
    """(source, target) sides of the landmark pairs at every vertex (``orientation``; landmarks given as
    sample indices), or None for point clouds and fewer than 2 landmarks: what the sample matcher reads
    at the samples (``sample_sides``) and the dense stage's anchors at every vertex (``Anchors.oriented``,
    ``problem.MatchProblem``: computed once for both)."""
    fs = orientation_features(source.geometry, source.rows[np.asarray(landmarks_source)])
    ft = orientation_features(target.geometry, target.rows[np.asarray(landmarks_target)])
    return None if fs is None or ft is None else (fs, ft)


def sample_sides(source: SampledSurface, landmarks_source, target: SampledSurface, landmarks_target, sides=None):
    """(source, target) sides of the landmark pairs at the samples: ``landmark_sides``, given or computed
    here, read at the samples; None for point clouds and fewer than 2 landmarks."""
    sides = sides if sides is not None else landmark_sides(source, landmarks_source, target, landmarks_target)
    return None if sides is None else (sides[0][source.samples], sides[1][target.samples])


def match_landmarks_only(source_geometry, target_geometry, landmarks_source, landmarks_target,
                         options: MatchOptions = MatchOptions(matcher="zoomout"), solvers=(None, None),
                         compared: SampledSurface | None = None) -> DenseMatch:
    """The zoomout matcher (module docstring): from the landmark pairs alone to a dense map.

    The landmark pairs (internal ids, at least ``MIN_ZOOMOUT_LANDMARKS``, distinct) are checked by
    ``problem.MatchProblem``, which runs this matcher.  ``solvers``: optional distance solvers of the
    two shapes (e.g. ``sampled.CachedSolver``) for the landmarks' geodesic rows; ``compared``: the
    source's samples the starts are compared on (``comparison_samples``; sampled here when None).
    """
    ls = np.asarray(landmarks_source, dtype=np.int64).reshape(-1)
    lt = np.asarray(landmarks_target, dtype=np.int64).reshape(-1)
    anchors = []
    for g, lm, solver in ((source_geometry, ls, solvers[0]), (target_geometry, lt, solvers[1])):
        rows = (solver if solver is not None else CachedSolver(g, options.backend)).distances(lm)
        anchors.append(rows / surface_unit(g, float(rows.max())))
    anchor = Anchors(ls, lt, anchors[0], anchors[1])
    maps = [dense_stage(source_geometry, target_geometry, _nearest_description(source_geometry, target_geometry,
                                                                              anchor, k), anchor, options)
            for k in sorted({ls.size, MIN_ZOOMOUT_LANDMARKS})[::-1]]
    best, compared = _least_distorted(source_geometry, target_geometry, maps, ls, options, solvers[1], compared)
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


def comparison_samples(source_geometry, landmarks, options: MatchOptions) -> SampledSurface:
    """The source's samples the zoomout matcher compares its starts on: as many as the error bar's
    (``error_bar.BAR_SAMPLES``, or N if fewer), landmarks first; the bar reads the map on them."""
    return sample_surface(source_geometry, min(options.n_points, BAR_SAMPLES), options.backend, options.seed,
                          landmarks, options.cache)


def _least_distorted(source_geometry, target_geometry, maps: list, landmarks, options: MatchOptions,
                     solver, compared: SampledSurface | None = None) -> tuple[int, SampledSurface | None]:
    """Index of the map that distorts the source's sample distances least (``error_bar.map_distortion`` on
    ``compared``, by default ``comparison_samples``; the first of equals), and those samples (None: one
    map, nothing to compare)."""
    if len(maps) == 1:
        return 0, None
    src = compared if compared is not None else comparison_samples(source_geometry, landmarks, options)
    solver = solver if solver is not None else CachedSolver(target_geometry, options.backend)
    costs = [map_distortion(src, target_geometry, m[src.samples], solver) for m in maps]
    return int(np.argmin(costs)), src

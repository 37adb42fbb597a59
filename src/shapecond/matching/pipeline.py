"""Landmark-guided matching of two shapes, end to end, source to target.

    geometry -> sampled surface (FPS, landmarks first) -> sample map (LH05 or FAQ)
             -> dense map (one target vertex per source vertex)

Both shapes are sampled with ``N`` points, their sample distances expressed in
units of ``sqrt(area)`` (``sampled.py``), the samples matched with the
landmark pairs fixed (``spectral.lh05_match`` or ``seeded.faq_match``), and the
sample map extended to every source vertex (``dense.dense_map``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from shapecond.errors import InputError
from shapecond.matching.dense import dense_map
from shapecond.matching.metrics import errors_from_rows, normalise
from shapecond.matching.sampled import SampledSurface, carry_samples, insert_landmarks, sample_surface
from shapecond.matching.seeded import faq_match
from shapecond.matching.spectral import SampleMatch, lh05_match

MATCHERS = ("lh05", "faq")
#: Which samples the target gets (``match_shapes``): its own FPS samples, or the source's vertex ids.
SAMPLINGS = ("fps", "same-ids")


@dataclass(frozen=True, eq=False)
class DenseMatch:
    """Result of ``match_shapes`` / ``match_surfaces``.

    Attributes
    ----------
    vertex_map : (n_source,) int64 internal target vertex of every source vertex.
    sample_map : SampleMatch between ``source.samples`` and ``target.samples``.
    source, target : SampledSurface used (landmarks are their first samples).
    info : dict of diagnostics.
    """

    vertex_map: np.ndarray
    sample_map: SampleMatch
    source: SampledSurface
    target: SampledSurface
    info: dict = field(default_factory=dict)

    @property
    def sample_vertex_map(self) -> np.ndarray:
        """(N,) internal target vertex of each source sample (the sample map in vertex ids)."""
        return self.target.samples[self.sample_map.t]


def match_samples(D_source, D_target, landmarks_source, landmarks_target, matcher: str = "lh05",
                  seed: int = 0, **options) -> SampleMatch:
    """Dispatch to ``lh05_match`` or ``faq_match`` (options passed through)."""
    if matcher == "lh05":
        return lh05_match(D_source, D_target, landmarks_source, landmarks_target, **options)
    if matcher == "faq":
        return faq_match(D_source, D_target, landmarks_source, landmarks_target, seed=seed, **options)
    raise InputError(f"unknown matcher {matcher!r} ({' or '.join(MATCHERS)})")


def match_surfaces(source: SampledSurface, target: SampledSurface, landmarks_source,
                   landmarks_target, matcher: str = "lh05", dense: str = "distances",
                   seed: int = 0, source_solver=None, target_solver=None, **options) -> DenseMatch:
    """Match two sampled surfaces whose landmark vertices (internal ids) are given.

    Landmarks that are not samples yet are inserted (``sampled.insert_landmarks``,
    with the optional solvers, e.g. ``sampled.CachedSolver``, for their rows).
    """
    ls = np.asarray(landmarks_source, dtype=np.int64).reshape(-1)
    lt = np.asarray(landmarks_target, dtype=np.int64).reshape(-1)
    if ls.size != lt.size:
        raise InputError(f"landmark counts differ: {ls.size} on the source, {lt.size} on the target")
    source, ils = insert_landmarks(source, ls, source_solver)
    target, ilt = insert_landmarks(target, lt, target_solver)
    sm = match_samples(source.D, target.D, ils, ilt, matcher, seed=seed, **options)
    vmap = dense_map(source, target, sm.t, method=dense)
    # landmarks map exactly onto their images
    vmap[ls] = lt
    return DenseMatch(vmap, sm, source, target, dict(matcher=matcher, dense=dense,
                                                     n_landmarks=int(ls.size)))


def match_shapes(source_geometry, target_geometry, landmarks_source, landmarks_target,
                 matcher: str = "lh05", n_points: int = 400, backend: str = "heat", seed: int = 0,
                 dense: str = "distances", cache: bool = True, samples: str = "fps",
                 **options) -> DenseMatch:
    """Sample both shapes (landmarks first) and match them, source to target.

    With ``samples="same-ids"`` the two shapes share their vertex order (a class
    of TOSCA, say) and the target is sampled at the source's sample vertices
    (``sampled.carry_samples``, the evaluation's *corresponding* protocol): the
    true sample map is known, and ``info`` reports its error (``sample_error``,
    % of half the target's geodesic diameter) and the fraction of samples
    matched exactly (``exact``).  The target landmarks must then be the source's.

    Parameters
    ----------
    source_geometry, target_geometry : Geometry
    landmarks_source, landmarks_target : sequences of int
        Internal vertex indices of corresponding landmarks (same count).
    matcher : {"lh05", "faq"}
    n_points : int
        Samples per shape.
    backend : str
        Geodesic backend.
    dense : {"distances", "nearest"}
        Dense extension method (``dense.py``).
    options
        Passed to the matcher (``k``, ``rounding``, ``objective``...).
    """
    ls = np.asarray(landmarks_source, dtype=np.int64).reshape(-1)
    lt = np.asarray(landmarks_target, dtype=np.int64).reshape(-1)
    if ls.size != lt.size:
        raise InputError(f"landmark counts differ: {ls.size} on the source, {lt.size} on the target")
    if matcher not in MATCHERS:
        raise InputError(f"unknown matcher {matcher!r} ({' or '.join(MATCHERS)})")
    if samples not in SAMPLINGS:
        raise InputError(f"unknown sampling {samples!r} ({' or '.join(SAMPLINGS)})")
    n = min(source_geometry.n_vertices, target_geometry.n_vertices)
    if n_points > n:
        raise InputError(f"{n_points} samples requested but a shape has only {n} vertices")
    src = sample_surface(source_geometry, n_points, backend, seed, ls, cache)
    if samples == "same-ids":
        return _match_same_ids(src, target_geometry, ls, lt, matcher, dense, seed, **options)
    tgt = sample_surface(target_geometry, n_points, backend, seed, lt, cache)
    return match_surfaces(src, tgt, ls, lt, matcher, dense, seed, **options)


def _match_same_ids(src: SampledSurface, target_geometry, ls, lt, matcher, dense, seed, **options):
    """``match_shapes`` with the target sampled at the source's sample vertices."""
    src, ils = insert_landmarks(src, ls)
    tgt, truth = carry_samples(src, target_geometry, seed=seed)  # refuses different vertex ids
    if not np.array_equal(ls, lt):
        raise InputError("with same-ids samples the target landmarks must be the source's vertex ids")
    sm = match_samples(src.D, tgt.D, ils, truth[ils], matcher, seed=seed, **options)
    vmap = dense_map(src, tgt, sm.t, method=dense)
    vmap[ls] = lt
    raw = errors_from_rows(tgt.rows[truth], tgt.samples[sm.t])
    info = dict(matcher=matcher, dense=dense, n_landmarks=int(ls.size), samples="same-ids",
                sample_error=float(normalise(raw, tgt.diameter).mean()),
                exact=float(np.mean(sm.t == truth)))
    return DenseMatch(vmap, sm, src, tgt, info)

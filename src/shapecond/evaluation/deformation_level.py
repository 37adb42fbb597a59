"""A class's own deformation level ε, read from its ground truth or from its matched maps, and δ(ε) at it.

The scale-aware score δ(ε) (``symmetry.scale``) predicts how badly a class's
poses will be matched when ε is the distortion those poses actually cause.  An
evaluation knows it from the ground truth: the RMS distortion of the true map
between the null shape's samples and the same vertices of each target (shared
vertex order only).  A user does not; what any collection has is its matched
maps, and the distortion ε̂ of a map a distortion-minimising matcher found
reads ε from below (``matching.error_bar``).  The class level read without
ground truth is the median ε̂ over the class's matchings (every target,
landmark set and matcher), and δ is computed at it too, so that the two
levels can be compared on the same landmark sets.  A user who knows their
data's non-isometry passes it as ``--epsilon``.
"""

from __future__ import annotations

import numpy as np

from ..api import load
from ..api.level import collection_level
from ..matching.sampled import sample_surface, surface_at
from ..selection import monotone
from ..symmetry.scale import scale_score
from .landmark_sets import ShapeSetup


def class_epsilon(null_path, targets, setup: ShapeSetup) -> float:
    """The median over the targets of the RMS distortion of the ground-truth map on the null
    shape's samples, in units of the null shape's metric shape (diameter 1)."""
    g = load(null_path)
    null = sample_surface(g, setup.n_points, setup.backend, setup.seed, cache=setup.cache)
    scale = setup.metric_shape(g).scale
    iu = np.triu_indices(null.n_samples, 1)
    rms = [float(np.sqrt(np.mean((null.D - surface_at(load(p), null.samples, setup.backend,
                                                      setup.cache).D)[iu] ** 2)))
           for p in targets]
    return float(np.median(rms)) * null.unit / scale


def matched_level_task(cls: str, null_path, targets, setup: ShapeSetup) -> dict:
    """The class's level read off its matched maps before any landmark (``api.level.collection_level``:
    the null shape against its first targets, no ground truth), in units of its metric shape."""
    level = collection_level([null_path, *targets], n_points=setup.n_points, seed=setup.seed, backend=setup.backend,
                             cache=setup.cache, force=True)
    return dict(cls=cls, epsilon=in_diameters(null_path, setup, level.epsilon_area))


def class_scale_task(cls: str, null_path, targets, sets: dict, setup: ShapeSetup) -> dict:
    """A class's deformation level ε (``class_epsilon``) and, at it, δ(ε) of each landmark set
    (``scale_at``)."""
    epsilon = class_epsilon(null_path, targets, setup)
    return dict(cls=cls, epsilon=epsilon, scale_class=scale_at(null_path, sets, setup, epsilon))


def hat_scale_task(cls: str, null_path, sets: dict, setup: ShapeSetup, epsilon_hat: float) -> dict:
    """δ at the class level read off its matched maps: ``epsilon_hat`` (the median ε̂ of the class's
    matchings, units of the null shape's sqrt(area)) in units of its metric shape (diameter 1)."""
    epsilon = in_diameters(null_path, setup, epsilon_hat)
    return dict(cls=cls, epsilon_hat=epsilon, scale_hat=scale_at(null_path, sets, setup, epsilon))


def in_diameters(null_path, setup: ShapeSetup, epsilon_area: float) -> float:
    """A level in units of the null shape's sqrt(area) (``matching.error_bar``) in units of its metric
    shape (diameter 1), the unit of δ's ε."""
    g = load(null_path)
    unit = sample_surface(g, setup.n_points, setup.backend, setup.seed, cache=setup.cache).unit
    return float(epsilon_area) * unit / setup.metric_shape(g).scale


def scale_at(null_path, sets: dict, setup: ShapeSetup, epsilon: float) -> dict:
    """δ(ε) (quick search) of each landmark set ``sets[method] = (vertices, counts)`` after each count,
    non-increasing in the count, on the null shape's metric shape (ε in its units)."""
    shape = setup.metric_shape(null_path)
    where = {int(v): i for i, v in enumerate(shape.samples[:shape.n_samples])}
    out = {}
    for method, (vertices, counts) in sets.items():
        idx = [where[int(v)] for v in vertices]
        vals = [scale_score(shape.D, shape.n_samples, idx[:c], epsilon, seed=setup.seed,
                            effort="quick").displacement for c in counts]
        out[method] = dict(zip(counts, monotone(vals)))
    return out

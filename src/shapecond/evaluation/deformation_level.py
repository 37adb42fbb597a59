"""A class's own deformation level ε, read from its ground truth, and δ(ε) at it.

The scale-aware score δ(ε) (``symmetry.scale``) predicts how badly a class's
poses will be matched when ε is the distortion those poses actually cause.  An
evaluation knows it from the ground truth: the RMS distortion of the true map
between the null shape's samples and the same vertices of each target (shared
vertex order only).  A user who knows their data's non-isometry passes it as
``--epsilon``.
"""

from __future__ import annotations

import numpy as np

from .landmark_sets import ShapeSetup


def class_epsilon(null_path, targets, setup: ShapeSetup) -> float:
    """The median over the targets of the RMS distortion of the ground-truth map on the null
    shape's samples, in units of the null shape's metric shape (diameter 1)."""
    from ..api import load
    from ..matching.sampled import sample_surface, surface_at

    g = load(null_path)
    null = sample_surface(g, setup.n_points, setup.backend, setup.seed, cache=setup.cache)
    scale = setup.metric_shape(g).scale
    iu = np.triu_indices(null.n_samples, 1)
    rms = [float(np.sqrt(np.mean((null.D - surface_at(load(p), null.samples, setup.backend,
                                                      setup.cache).D)[iu] ** 2)))
           for p in targets]
    return float(np.median(rms)) * null.unit / scale


def class_scale_task(cls: str, null_path, targets, sets: dict, setup: ShapeSetup) -> dict:
    """A class's deformation level ε (``class_epsilon``) and, at it, δ(ε) (quick search) of each
    landmark set ``sets[method] = (vertices, counts)`` after each count, non-increasing in the count."""
    from ..selection import monotone
    from ..symmetry.scale import scale_score

    epsilon = class_epsilon(null_path, targets, setup)
    shape = setup.metric_shape(null_path)
    where = {int(v): i for i, v in enumerate(shape.samples[:shape.n_samples])}
    out = {}
    for method, (vertices, counts) in sets.items():
        idx = [where[int(v)] for v in vertices]
        vals = [scale_score(shape.D, shape.n_samples, idx[:c], epsilon, seed=setup.seed,
                            effort="quick").displacement for c in counts]
        out[method] = dict(zip(counts, monotone(vals)))
    return dict(cls=cls, epsilon=epsilon, scale_class=out)

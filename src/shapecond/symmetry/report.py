"""The global score of one metric shape as the JSON-ready report of ``shapecond score``.

``score_report`` runs ``symmetry_score`` (the σ bracket of Eq. 5 with its
witness, σ̂ = σ√N and the κ bracket of Theorem 4.1), for dense targets on a
mesh or point cloud the resolution report (is the witness a symmetry within
sampling resolution?), and the scale-aware score δ(ε) with its own witness
(``symmetry.scale``), and returns them as one dict with the keys that
``shapecond score --json`` prints.  The command line and batch scoring both
call it, so that their numbers cannot drift apart.
"""

from __future__ import annotations

import numpy as np

from shapecond.symmetry.resolution import resolution_for_shape
from shapecond.symmetry.scale import scale_score
from shapecond.symmetry.score import symmetry_score


def score_report(shape, landmark_ids=(), exact="auto", upper=False, time_limit=10.0, seed=0,
                 effort="default", epsilon=None) -> tuple[dict, object]:
    """JSON-ready report of one ``MetricShape`` and the ``SymmetryScore`` behind it.

    Parameters
    ----------
    shape : MetricShape
    landmark_ids : the input's ids (file vertex ids, matrix rows) fixed by every map;
        each must be a sample.
    exact, upper, time_limit, seed, effort : passed to ``symmetry_score``.
    epsilon : distortion level of δ(ε) (default ``symmetry.scale.default_epsilon``).

    Returns
    -------
    (dict, SymmetryScore)
        The dict holds ``SymmetryScore.to_dict()`` plus ``landmarks``, ``samples``
        (input ids of the samples), ``target``, ``resolution`` (a
        ``ResolutionReport`` dict, or None for bijections and matrices) and
        ``witness_vertices`` (input ids of the witness's images, None for a matrix)
        and ``scale`` (``ScaleScore.to_dict()`` plus its ``witness_vertices``).
    """
    lm = shape.landmark_indices(landmark_ids) if len(landmark_ids) else np.zeros(0, dtype=np.int64)
    sc = symmetry_score(shape.D, shape.n_points, lm, exact=exact, upper=upper, time_limit=time_limit,
                        seed=seed, effort=effort)
    out = sc.to_dict()
    out["landmarks"] = [int(v) for v in landmark_ids]
    out["samples"] = [int(v) for v in shape.sample_ids]
    out["target"] = shape.target
    res = resolution_for_shape(shape, lm, seed=seed, effort=effort, score=sc)
    out["resolution"] = None if res is None else res.to_dict()
    if shape.geometry is None:
        out["witness_vertices"] = None
    else:
        out["witness_vertices"] = [int(v) for v in shape.target_ids[sc.witness]]
    scale = scale_score(shape.D, shape.n_points, lm, epsilon, seed=seed, effort=effort,
                        starts=[sc.witness, *sc.maps])
    out["scale"] = scale.to_dict()
    out["scale"]["witness_vertices"] = (None if shape.geometry is None
                                        else [int(v) for v in shape.target_ids[scale.witness]])
    return out, sc

"""Landmark selection (paper Sections 6 and 7).

``select_landmarks(shape, k, method)`` chooses ``k`` landmarks among the samples of a
``MetricShape`` and reports them in order with the global symmetry score after each:

* ``"cnbs"``: Condition Number Based Sampling on the global score (``cnbs``);
* ``"cnbs-local"``: CNBS on the local score of deformation-based matching
  (``shapecond.deformation.heatmap``; its scores are local scores σ_∞, landmarks are
  mesh vertices, not necessarily samples);
* ``"fps"``: farthest point sampling with the paper's seeded start (``fps``);
* ``"pls"``: Planned Landmark Sampling, reimplemented from Tevs et al. 2011 (``pls``);
* ``"hks"``: extremal points of the heat kernel signature (``hks``);
* ``"user"``: the user's vertex ids or landmark file (``user``).
"""

from __future__ import annotations

import time

from ..errors import InputError
from .result import LandmarkResult, make_result, sample_of_vertex

METHODS = ("cnbs", "cnbs-local", "fps", "pls", "hks", "user")


def prefix_scores(shape, sample_indices, fixed=(), seed: int = 0, effort: str = "default") -> list[float]:
    """σ (lower bound with witness, Eq. 5) with the first 1, 2, ... landmarks fixed."""
    from ..symmetry.search import witness_search

    out, L = [], [int(v) for v in fixed]
    for s in sample_indices:
        L.append(int(s))
        out.append(float(witness_search(shape.D, n_samples=shape.n_samples, landmarks=L, seed=seed,
                                        effort=effort).sigma))
    return out


def _local_landmarks(shape, k, fixed, alpha=None, energy=None, refine=None):
    """CNBS on the local score via ``shapecond.deformation``.

    Landmarks are mesh vertices chosen by ``deformation.heatmap.select_local_landmarks``
    (greedy on the local score σ_∞ of paper Section 5); the scores reported are local
    scores, not the global σ.  ``sample_indices`` are the samples standing for them.
    """
    from ..deformation.heatmap import select_local_landmarks
    from ..deformation.local_score import LocalProblem

    g = shape.geometry
    if g is None or g.faces is None:
        raise InputError("cnbs-local needs a triangle mesh (the local score deforms a surface)")
    kw = {key: v for key, v in (("alpha", alpha), ("energy", energy)) if v is not None}
    problem = LocalProblem(g.vertices, g.faces, **kw)
    start = [int(shape.samples[i]) for i in fixed]
    res = select_local_landmarks(problem, k, start=start, **({"refine": refine} if refine is not None else {}))
    verts = [int(v) for v in res.landmarks]
    return verts, list(res.scores), float(res.initial)


def select_landmarks(shape, k: int, method: str = "cnbs", seed: int = 0, *, scores: bool | None = None,
                     effort: str = "default", fixed=(), **kw) -> LandmarkResult:
    """Choose ``k`` landmarks on ``shape`` with ``method``.

    Parameters
    ----------
    shape : MetricShape
    k : int, number of landmarks (for ``"user"``: at most the number given; 0 = all).
    method : one of ``METHODS``.
    seed : int, for every random choice (FPS start, search starts).
    scores : compute σ after each landmark for the baselines (k witness searches);
        default True for "cnbs" (free: the heat map gives them), False otherwise.
    effort : effort of the witness searches ("quick", "default", "thorough").
    fixed : sample indices fixed before selection (they are not reported again).
    **kw : method options: cnbs (``resolve_fraction``, ``resolve``, ``n_maps``,
        ``progress``, ``keep_heat_maps``), cnbs-local (``alpha``, ``energy``, ``refine``),
        hks (``time_fraction``, ``n_eigs``),
        user (``ids`` or ``path``).

    Returns
    -------
    LandmarkResult
    """
    if method not in METHODS:
        raise InputError(f"unknown landmark method {method!r}; choose one of {', '.join(METHODS)}")
    n = int(shape.n_samples)
    if method != "user" and not 1 <= k <= n - len(fixed) - 1:
        raise InputError(f"k must lie between 1 and {n - len(fixed) - 1} for {n} samples, got {k}")
    t0 = time.perf_counter()
    initial, heat_maps, sc = None, (), None
    if method == "cnbs":
        from .cnbs import cnbs_landmarks

        out = cnbs_landmarks(shape.D, n, k, fixed=fixed, seed=seed, effort=effort, **kw)
        chosen, sc, initial = out["landmarks"], out["scores"], out["initial_score"]
        heat_maps = tuple(out["heat_maps"])
    elif method == "cnbs-local":
        verts, sc, initial = _local_landmarks(shape, k, fixed, **kw)
        samples = [sample_of_vertex(shape, v) for v in verts]
        ids = [int(shape.geometry.ids[v]) for v in verts]
        return LandmarkResult(tuple(ids), tuple(samples), tuple(verts), tuple(float(v) for v in sc), method,
                              time.perf_counter() - t0, initial)
    elif method == "fps":
        from .fps import fps_landmarks

        chosen = fps_landmarks(shape.D, n, k, seed=seed, fixed=fixed)
    elif method == "pls":
        from .pls import pls_landmarks

        chosen, _ = pls_landmarks(shape.D, n, k, fixed=fixed)
    elif method == "hks":
        from .hks import hks_landmarks

        chosen, _ = hks_landmarks(shape, k, seed=seed, **kw)
    else:
        from .user import user_landmarks

        chosen = user_landmarks(shape, **kw)
        if k:
            chosen = chosen[:k]
    if sc is None:
        want = scores if scores is not None else False
        sc = prefix_scores(shape, chosen, fixed, seed, effort) if want else [None] * len(chosen)
    return make_result(shape, chosen, sc, method, time.perf_counter() - t0, initial, heat_maps)


__all__ = ["LandmarkResult", "METHODS", "prefix_scores", "select_landmarks"]

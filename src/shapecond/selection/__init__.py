"""Landmark selection (paper Sections 6 and 7).

``select_landmarks(shape, k, method)`` chooses ``k`` landmarks among the samples of a
``MetricShape`` and reports them in order with the global symmetry score after each:

* ``"cnbs"``: Condition Number Based Sampling on the global score (``cnbs``);
* ``"cnbs-scale"``: CNBS on the scale-aware score δ(ε) (``shapecond.symmetry.scale``):
  each landmark lowers most the displacement of the widest self-map whose distortion
  stays within ε; its scores are δ after each landmark;
* ``"cnbs-local"``: CNBS on the local score of deformation-based matching
  (``shapecond.deformation.heatmap``; its scores are local scores σ_∞, landmarks are
  mesh vertices, not necessarily samples);
* ``"fps"``: farthest point sampling with the paper's seeded start (``fps``);
* ``"pls"``: Planned Landmark Sampling, reimplemented from Tevs et al. 2011 (``pls``);
* ``"hks"``: extremal points of the heat kernel signature (``hks``);
* ``"user"``: the user's vertex ids or landmark file (``user``).
"""

from __future__ import annotations

import math
import time

from ..errors import InputError
from ..limits import single_blas_thread
from .result import LandmarkSelection, make_result, sample_of_vertex

METHODS = ("cnbs", "cnbs-scale", "cnbs-local", "fps", "pls", "hks", "user")
#: Which score follows each landmark: σ (Eq. 5) or δ(ε) (``shapecond.symmetry.scale``).
SCORES = ("sigma", "scale")


#: Keyword options of ``select_landmarks`` itself, which every method takes.
COMMON_OPTIONS = ("scores", "effort", "fixed", "score", "epsilon")


def method_options(method: str) -> frozenset:
    """The keyword options ``select_landmarks`` takes with ``method``, read from the signatures of
    the methods (``COMMON_OPTIONS`` and the method's own, e.g. ``resolve_fraction`` for cnbs)."""
    import inspect

    def own(f, *taken):
        return set(inspect.signature(f).parameters) - set(taken)

    if method in ("cnbs", "cnbs-scale"):
        from .cnbs import cnbs_landmarks

        extra = own(cnbs_landmarks, "D", "n_samples", "k", "fixed", "seed", "effort", "budget")
    elif method == "cnbs-local":
        extra = own(_local_landmarks, "shape", "k", "fixed")
    elif method == "hks":
        from .hks import hks_landmarks

        extra = own(hks_landmarks, "shape", "k", "seed")
    elif method == "user":
        from .user import user_landmarks

        extra = own(user_landmarks, "shape")
    else:
        extra = set()
    return frozenset(extra | set(COMMON_OPTIONS))


def check_method_options(method: str, options) -> None:
    """``InputError`` for an unknown method or an option it does not take (cheap: call it before
    computing anything, e.g. the geodesics of the shape)."""
    if method not in METHODS:
        raise InputError(f"unknown landmark method {method!r}; choose one of {', '.join(METHODS)}")
    unknown = sorted(set(options) - method_options(method))
    if unknown:
        raise InputError(f"landmark method {method!r} has no option {unknown[0]!r} "
                         f"(its options: {', '.join(sorted(method_options(method)))})")


def monotone(values) -> list:
    """Lower bounds after 1, 2, ... landmarks made non-increasing: a map fixing more
    landmarks also fixes fewer, so a later bound is a bound of every earlier score too."""
    out, hi = list(values), -math.inf
    for i in range(len(out) - 1, -1, -1):
        if out[i] is not None:
            hi = max(hi, out[i])
            out[i] = hi
    return out


def prefix_scores(shape, sample_indices, fixed=(), seed: int = 0, effort: str = "default",
                  score: str = "sigma", epsilon=None) -> list[float]:
    """σ (Eq. 5) or δ(ε) (lower bounds with witness) with the first 1, 2, ... landmarks fixed."""
    from ..symmetry.scale import scale_score
    from ..symmetry.search import witness_search

    out, L = [], [int(v) for v in fixed]
    for s in sample_indices:
        L.append(int(s))
        if score == "scale":
            out.append(scale_score(shape.D, shape.n_samples, L, epsilon, seed=seed, effort=effort).displacement)
        else:
            out.append(float(witness_search(shape.D, n_samples=shape.n_samples, landmarks=L, seed=seed,
                                            effort=effort).sigma))
    return monotone(out)


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


@single_blas_thread
def select_landmarks(shape, k: int, method: str = "cnbs", seed: int = 0, *, scores: bool | None = None,
                     effort: str = "default", fixed=(), score: str | None = None, epsilon=None,
                     **kw) -> LandmarkSelection:
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
    score : "sigma" or "scale", the score reported after each landmark; default
        "scale" for "cnbs-scale", "sigma" otherwise (cnbs always reports σ).
    epsilon : distortion level of the scale-aware score (default:
        ``symmetry.scale.default_epsilon``).
    **kw : method options: cnbs (``resolve_fraction``, ``resolve``, ``n_maps``,
        ``progress``, ``keep_heat_maps``), cnbs-local (``alpha``, ``energy``, ``refine``),
        hks (``time_fraction``, ``n_eigs``),
        user (``ids`` or ``path``).

    Returns
    -------
    LandmarkSelection
    """
    check_method_options(method, kw)
    score = score or ("scale" if method == "cnbs-scale" else "sigma")
    if score not in SCORES:
        raise InputError(f"unknown score {score!r}; choose sigma or scale")
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
        score = "sigma"
    elif method == "cnbs-scale":
        from ..symmetry.scale import budget_of, default_epsilon
        from .cnbs import cnbs_landmarks

        eps = default_epsilon(shape.D, n) if epsilon is None else float(epsilon)
        out = cnbs_landmarks(shape.D, n, k, fixed=fixed, seed=seed, effort=effort,
                             budget=budget_of(eps, n, shape.D), **kw)
        # heat-map values are sqrt(d²): RMS displacement δ = value / sqrt(N)
        chosen = out["landmarks"]
        sc = monotone([v / math.sqrt(n) for v in out["scores"]])
        initial = max(out["initial_score"] / math.sqrt(n), sc[0] if sc else 0.0)
        heat_maps = tuple(out["heat_maps"])
        if score == "sigma":  # σ after each landmark (computed below when asked for)
            sc, initial = None, None
    elif method == "cnbs-local":
        verts, sc, initial = _local_landmarks(shape, k, fixed, **kw)
        samples = [sample_of_vertex(shape, v) for v in verts]
        ids = [int(shape.geometry.ids[v]) for v in verts]
        return LandmarkSelection(tuple(ids), tuple(samples), tuple(verts), tuple(float(v) for v in sc), method,
                              time.perf_counter() - t0, initial, shape=shape)
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
        sc = prefix_scores(shape, chosen, fixed, seed, effort, score, epsilon) if want else [None] * len(chosen)
    return make_result(shape, chosen, sc, method, time.perf_counter() - t0, initial, heat_maps, score)


__all__ = ["LandmarkSelection", "METHODS", "SCORES", "check_method_options", "method_options", "monotone",
           "prefix_scores", "select_landmarks"]

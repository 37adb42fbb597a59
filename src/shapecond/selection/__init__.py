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
from dataclasses import dataclass, fields, replace

from ..errors import InputError
from ..threads import single_blas_thread
from .fps import fps_landmarks
from .pls import pls_landmarks
from .result import LandmarkSelection, make_result, sample_of_vertex
from .user import UserLandmarks, user_landmarks

# The score-based methods (cnbs, cnbs-scale, the scores after each landmark) need the compiled
# witness search (numba), hks a Laplace-Beltrami basis and cnbs-local the deformation energy:
# they are imported when used, so that importing this package (the command line does) stays light.

METHODS = ("cnbs", "cnbs-scale", "cnbs-local", "fps", "pls", "hks", "user")
#: Which score follows each landmark: σ (Eq. 5) or δ(ε) (``shapecond.symmetry.scale``).
SCORES = ("sigma", "scale")


@dataclass(frozen=True)
class LandmarkOptions:
    """The options of ``select_landmarks``: those every method takes and the method's own.

    Attributes
    ----------
    seed : seed of every random choice (FPS start, search starts).
    scores : compute the score after each landmark for the baselines (k witness searches);
        default True for "cnbs" (free: the heat map gives them), False otherwise.
    effort : effort of the witness searches ("quick", "default", "thorough").
    fixed : sample indices fixed before selection (they are not reported again).
    score : "sigma" or "scale", the score reported after each landmark; default "scale"
        for "cnbs-scale", "sigma" otherwise (cnbs always reports σ).
    epsilon : distortion level of the scale-aware score (default:
        ``symmetry.scale.default_epsilon``).
    own : the method's own options, an instance of ``own_options_class(method)`` (None: its
        defaults): ``cnbs.CNBSOptions`` for cnbs and cnbs-scale (their ``seed`` and ``effort``
        are this object's), ``LocalLandmarkOptions``, ``hks.HKSOptions`` or ``user.UserLandmarks``.
    """

    seed: int = 0
    scores: bool | None = None
    effort: str = "default"
    fixed: tuple = ()
    score: str | None = None
    epsilon: float | None = None
    own: object = None


@dataclass(frozen=True)
class LocalLandmarkOptions:
    """The options of cnbs-local (``_local_landmarks``); None: the default of ``deformation``.

    Attributes
    ----------
    alpha, energy : of the local score's energy (``deformation.local_score.LocalProblem``).
    refine : of ``deformation.heatmap.select_local_landmarks``.
    """

    alpha: float | None = None
    energy: str | None = None
    refine: bool | None = None


#: Keyword options of ``select_landmarks`` that every method takes (``seed`` is the shape's, ``own`` the method's).
COMMON_OPTIONS = tuple(f.name for f in fields(LandmarkOptions) if f.name not in ("seed", "own"))
#: Keywords CNBS takes besides its options' fields: the witness search it starts from, a progress callback and
#: a ``CNBSOptions`` whose fields the other keywords replace.
CNBS_EXTRAS = ("base", "progress", "options")


def own_options_class(method: str):
    """The dataclass of ``method``'s own options (``LandmarkOptions.own``), or None (fps, pls)."""
    if method in ("cnbs", "cnbs-scale"):
        from .cnbs import CNBSOptions  # numba: see the note on imports above

        return CNBSOptions
    if method == "hks":
        from .hks import HKSOptions  # a Laplace-Beltrami basis: see the note on imports above

        return HKSOptions
    return {"cnbs-local": LocalLandmarkOptions, "user": UserLandmarks}.get(method)


def method_options(method: str) -> frozenset:
    """The keyword options the interface takes with ``method``: ``COMMON_OPTIONS`` and the fields of
    the method's own options (for cnbs less ``seed`` and ``effort``, plus ``CNBS_EXTRAS``)."""
    cls = own_options_class(method)
    extra = set() if cls is None else {f.name for f in fields(cls)}
    if method in ("cnbs", "cnbs-scale"):
        extra = extra - {"seed", "effort"} | set(CNBS_EXTRAS)
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
    from ..symmetry.scale import scale_score  # numba: see the note on imports above
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


def _local_landmarks(shape, k, fixed, own: LocalLandmarkOptions):
    """CNBS on the local score via ``shapecond.deformation``.

    Landmarks are mesh vertices chosen by ``deformation.heatmap.select_local_landmarks``
    (greedy on the local score σ_∞ of paper Section 5); the scores reported are local
    scores, not the global σ.  ``sample_indices`` are the samples standing for them.
    """
    from ..deformation.heatmap import select_local_landmarks  # see the note on imports above
    from ..deformation.local_score import LocalProblem

    g = shape.geometry
    if g is None or g.faces is None:
        raise InputError("cnbs-local needs a triangle mesh (the local score deforms a surface)")
    kw = {key: v for key, v in (("alpha", own.alpha), ("energy", own.energy)) if v is not None}
    problem = LocalProblem(g.vertices, g.faces, **kw)
    start = [int(shape.samples[i]) for i in fixed]
    res = select_local_landmarks(problem, k, start=start, **({"refine": own.refine} if own.refine is not None else {}))
    verts = [int(v) for v in res.landmarks]
    return verts, list(res.scores), float(res.initial)


def _cnbs(shape, k, method, opts: LandmarkOptions, score, runtime):
    """CNBS on σ ("cnbs") or on δ(ε) ("cnbs-scale"): (samples, scores, initial score, heat maps,
    what the scores are); scores None when σ is asked for after cnbs-scale.  ``runtime``: (base, progress)."""
    from ..symmetry.scale import budget_of, default_epsilon  # numba: see the note on imports above
    from .cnbs import CNBSOptions, cnbs_landmarks

    n, D = int(shape.n_samples), shape.D
    own = replace(opts.own or CNBSOptions(), seed=opts.seed, effort=opts.effort)
    base, progress = runtime
    if method == "cnbs":
        out = cnbs_landmarks(D, n, k, opts.fixed, base, None, progress, own)
        return out["landmarks"], out["scores"], out["initial_score"], tuple(out["heat_maps"]), "sigma"
    eps = default_epsilon(D, n) if opts.epsilon is None else float(opts.epsilon)
    out = cnbs_landmarks(D, n, k, opts.fixed, base, budget_of(eps, n, D), progress, own)
    if score == "sigma":  # σ after each landmark (computed by the caller when asked for)
        return out["landmarks"], None, None, tuple(out["heat_maps"]), score
    # heat-map values are sqrt(d²): RMS displacement δ = value / sqrt(N)
    sc = monotone([v / math.sqrt(n) for v in out["scores"]])
    initial = max(out["initial_score"] / math.sqrt(n), sc[0] if sc else 0.0)
    return out["landmarks"], sc, initial, tuple(out["heat_maps"]), score


def _baseline(shape, k, method, opts: LandmarkOptions) -> list:
    """The samples chosen by fps, pls, hks or user."""
    n, seed, fixed = int(shape.n_samples), opts.seed, opts.fixed
    if method == "fps":
        return fps_landmarks(shape.D, n, k, seed=seed, fixed=fixed)
    if method == "pls":
        return pls_landmarks(shape.D, n, k, fixed=fixed)[0]
    if method == "hks":
        from .hks import HKSOptions, hks_landmarks  # a Laplace-Beltrami basis: see the note on imports above

        return hks_landmarks(shape, k, seed, opts.own or HKSOptions())[0]
    own = opts.own or UserLandmarks()
    chosen = user_landmarks(shape, own.ids, own.path)
    return chosen[:k] if k else chosen


@single_blas_thread
def select_landmarks(shape, k: int, method: str = "cnbs", options: LandmarkOptions = LandmarkOptions(), *,
                     base=None, progress=None) -> LandmarkSelection:
    """Choose ``k`` landmarks on ``shape`` with ``method``.

    Parameters
    ----------
    shape : MetricShape
    k : int, number of landmarks (for ``"user"``: at most the number given; 0 = all).
    method : one of ``METHODS``.
    options : LandmarkOptions (the seed, the options every method takes and the method's own),
        taken as checked (the interface checks a user's: ``check_method_options``).
    base : cnbs and cnbs-scale: the witness search with ``options.fixed`` fixed, when already known.
    progress : cnbs and cnbs-scale: callable(step, done, total) or None.

    Returns
    -------
    LandmarkSelection
    """
    opts = options
    score = opts.score or ("scale" if method == "cnbs-scale" else "sigma")
    n = int(shape.n_samples)
    if method != "user" and not 1 <= k <= n - len(opts.fixed) - 1:
        raise InputError(f"k must lie between 1 and {n - len(opts.fixed) - 1} for {n} samples, got {k}")
    t0 = time.perf_counter()
    if method == "cnbs-local":
        verts, sc, initial = _local_landmarks(shape, k, opts.fixed, opts.own or LocalLandmarkOptions())
        samples = [sample_of_vertex(shape, v) for v in verts]
        ids = [int(shape.geometry.ids[v]) for v in verts]
        return LandmarkSelection(tuple(ids), tuple(samples), tuple(verts), tuple(float(v) for v in sc), method,
                                 time.perf_counter() - t0, initial, shape=shape)
    initial, heat_maps, sc = None, (), None
    if method in ("cnbs", "cnbs-scale"):
        chosen, sc, initial, heat_maps, score = _cnbs(shape, k, method, opts, score, (base, progress))
    else:
        chosen = _baseline(shape, k, method, opts)
    if sc is None:
        want = opts.scores if opts.scores is not None else False
        sc = (prefix_scores(shape, chosen, opts.fixed, opts.seed, opts.effort, score, opts.epsilon) if want
              else [None] * len(chosen))
    return make_result(shape, chosen, sc, method, time.perf_counter() - t0, initial, heat_maps, score)


__all__ = ["CNBS_EXTRAS", "COMMON_OPTIONS", "LandmarkOptions", "LandmarkSelection", "LocalLandmarkOptions", "METHODS",
           "SCORES", "check_method_options", "method_options", "monotone", "own_options_class", "prefix_scores",
           "select_landmarks"]

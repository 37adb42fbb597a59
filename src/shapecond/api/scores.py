"""How hard a shape is to match: the scores of the Python interface, guarded and validated.

``score`` (σ bracket, Eq. 5; κ bracket, Theorem 4.1; δ(ε); verdict),
``local_score`` (σ_∞, Section 5), ``landmarks`` (CNBS and the baselines,
Section 6), ``heatmap`` (Figures 1 and 4) and ``kappa`` (probes of Eq. 4).
Each takes any input of ``load`` (or a ``MetricShape``), refuses an unknown
keyword and work beyond ``shapecond.limits`` before starting (``force=True``
runs it), and returns a result with pictures (``api.results``).
"""

from __future__ import annotations

from dataclasses import replace
import sys
import time

import numpy as np

from ..checks import parse_ids
from ..deformation.local_score import ZERO_TOL, LocalProblem
from ..errors import InputError
from ..selection import method_options, select_landmarks
from ..symmetry.condition import MAX_PROBE_POINTS, kappa_probes
from ..symmetry.report import score_report
from .guards import guard_landmarks, guard_local
from .inputs import load, require_mesh, shape_of
from .options import K, LANDMARK_SCORE, METHOD, SCORES_AFTER, ShapeOptions, landmark_options
from .params import (EFFORT, EPSILON, FIXED_LANDMARKS, IDS_HELP, POINTS, PROGRESS, SHAPE_OPTIONS, FloatRange, Ids, IntRange,
                     Param, check_keywords)
from .problem import HEATMAP_SCORE, RESOLVE, SymmetryProblem
from .results import HeatMapResult, KappaResult, LandmarkResult, LocalResult, ScoreResult, promote
from .settings import EXACT, TIME_LIMIT, UPPER, score_settings

#: Largest N of κ probes beyond the landmarks (exact matching enumerates every map).
DEFAULT_KAPPA_POINTS = 8

#: The options of ``score``, each declared once (``params``): ``shapecond score``'s options and ``score``'s
#: keywords are made from it (``progress``: Python only; the command line shows bars on a terminal).
SCORE_PARAMS = (*SHAPE_OPTIONS, FIXED_LANDMARKS, EXACT, UPPER, TIME_LIMIT, EFFORT, EPSILON, PROGRESS)
#: The options of ``landmarks`` that every method takes, each declared once (``params``): ``shapecond
#: landmarks``'s options and ``landmarks``'s keywords are made from it.  A method's own options
#: (``selection.method_options``: CNBS's ``resolve_fraction``, HKS's ``n_eigs``, ...) are Python only and
#: checked by the method's options class.
LANDMARK_PARAMS = (*SHAPE_OPTIONS, K, METHOD,
                   Param("user_landmarks", Ids(), None, "For --method user: vertex ids, " + IDS_HELP + ".",
                         cli=("--user-landmarks",)),
                   SCORES_AFTER, EFFORT, LANDMARK_SCORE, EPSILON.in_context("--method cnbs-scale or --score scale: "),
                   PROGRESS)
#: The options of ``heatmap``, each declared once (``params``): the shape options, the landmarks fixed already
#: and those of the heat map itself (``SymmetryProblem.heatmap``).
HEATMAP_PARAMS = (*SHAPE_OPTIONS, Param("landmarks", Ids(), (), "Vertex ids already fixed: " + IDS_HELP + ".",
                                        cli=("--landmarks",)),
                  EFFORT, RESOLVE, HEATMAP_SCORE, EPSILON.in_context("--score scale: "), PROGRESS)
#: kappa's N: ``DEFAULT_KAPPA_POINTS`` free samples of a mesh by default (its probes enumerate every map).
KAPPA_POINTS = replace(POINTS, cli_default=f"{DEFAULT_KAPPA_POINTS} + the landmarks for a mesh, every point of a matrix")
#: The options of ``kappa``, each declared once (``params``).
KAPPA_PARAMS = (KAPPA_POINTS, *(p for p in SHAPE_OPTIONS if p is not POINTS), FIXED_LANDMARKS,
                Param("trials", IntRange(1), 20, "Number of perturbed copies probed.", cli=("--trials",)),
                Param("scale", FloatRange(0, 10, lo_open=True), 0.05,
                      "Random perturbation size, relative to the RMS distance.", cli=("--scale",)),
                Param("time_limit", FloatRange(0, lo_open=True, none=True), None,
                      "Stop probing after this many seconds (the probes so far are reported).", cli=("--time-limit",)),
                PROGRESS)


def score(x, n_points: int | None = None, *, landmarks=(), exact="auto", upper: bool = False,
          time_limit: float | None = None, effort: str = "default", **options) -> ScoreResult:
    """How hard ``x`` is to match: the σ bracket (paper Eq. 5), κ bracket, witness, δ(ε) and verdict.

    Parameters
    ----------
    x : any input of ``load``, or a ``MetricShape``.
    n_points, landmarks : samples N and fixed landmarks (input ids); see ``metric_shape``.
    exact : "auto" (exact σ when enumeration is quick), True or False.
    upper : LP upper bound when σ is not exact (N <= 16 free samples).
    time_limit : seconds for the whole score once the distances are known (computing them, or the
        kernels the first time, is not bounded): the witness search, the exact and LP solves, the
        resolution report and δ(ε).  When it is reached the searches keep the best maps found (valid
        bounds that then depend on the machine's speed) and the solves stop unproven;
        ``to_dict()["time_limited"]`` and a note say so.  None: the searches run in full
        (deterministic) and each solve gets 10 s.
    effort : "quick", "default" or "thorough" work of the witness search.
    **options : ``epsilon``, the distortion level of the scale-aware score δ(ε) (default: the median
        sample spacing), and the options of ``metric_shape`` (``seed``, ``force``, ``backend``, ...).
        Every keyword, its constraint and default: ``SCORE_PARAMS``; a bad value or an unknown keyword is
        refused before any work.

    Returns
    -------
    ScoreResult: ``.sigma``, ``.kappa``, ``.verdict``, ``.score`` (SymmetryScore),
    ``.scale`` (ScaleScore, δ(ε)), ``.witness_ids``, ``.to_dict()`` (the JSON of
    ``shapecond score --json``), ``.plot()``, ``.to_html()``.

    Examples
    --------
    >>> import shapecond as sc
    >>> result = sc.score("demo:sphere:subdivisions=2", n_points=20, cache=False)
    >>> result.sigma
    (inf, inf)
    >>> result.verdict.startswith("exact symmetry")
    True
    """
    v = check_keywords(SCORE_PARAMS, dict(options, n_points=n_points, landmarks=landmarks, exact=exact, upper=upper,
                                          time_limit=time_limit, effort=effort), "score")
    opts = ShapeOptions.of(v)
    settings = score_settings(exact=v["exact"], upper=v["upper"], time_limit=v["time_limit"], effort=v["effort"],
                              epsilon=v["epsilon"], seed=opts.seed, force=opts.force)
    shape = shape_of(x, v["n_points"], v["landmarks"], opts)
    report = score_report(shape, v["landmarks"], settings)
    return promote(report, ScoreResult)


def local_score(x, landmarks=(), *, alpha: float = 1.0, energy: str = "springs", zero_tol: float | None = None,
                force: bool = False) -> LocalResult:
    """Local symmetry score σ_∞ = sqrt(2/λ_min) of deformation-based matching (paper Section 5).

    ``x`` must be a triangle mesh; ``landmarks`` are vertex ids of the input.
    Returns a ``LocalResult`` (``.score``, ``.lambda_min``, ``.zero_modes``, ``.doubt()``, ``.plot()``).

    Examples
    --------
    >>> import shapecond as sc
    >>> sc.local_score("demo:sphere:subdivisions=2").score   # the sphere's rotations are zero modes
    inf
    """
    t0 = time.perf_counter()
    g = require_mesh(load(x, force=force))
    guard_local(g.n_vertices, force)
    zero_tol = ZERO_TOL if zero_tol is None else zero_tol
    problem = LocalProblem(g.vertices, g.faces, alpha=alpha, energy=energy)
    result = problem.score(g.to_internal(parse_ids(landmarks)), zero_tol=zero_tol, ids=g.ids)
    result = replace(result, seconds=time.perf_counter() - t0)  # building and factorising the Hessian included
    return promote(result, LocalResult, {"drawing": (g, problem, zero_tol)})


def landmarks(x, k: int, method: str = "cnbs", n_points: int | None = None, *, user_landmarks=None,
              scores: bool | None = None, effort: str = "default", **options) -> LandmarkResult:
    """``k`` landmarks chosen by ``method``, with the score after each (paper Section 6).

    Parameters
    ----------
    x : any input of ``load``, or a ``MetricShape``.
    k : how many landmarks (``method="user"``: 0 takes all of ``user_landmarks``).
    method : "cnbs" (the paper's condition-number-based sampling on σ), "cnbs-scale" (CNBS on
        δ(ε)), "cnbs-local", "fps", "pls", "hks" or "user".
    user_landmarks : input ids placed first among the samples; for ``method="user"``, the landmarks.
    scores : also compute the score after each landmark (always for CNBS; one search each otherwise).
    effort : work of the witness searches.
    **options : ``score`` and ``epsilon`` (which score follows each landmark, and the level of δ(ε)), the
        options of ``metric_shape`` (``seed``, ``force``, ``progress``...) and the method's own
        (``selection.method_options``: ``resolve_fraction``, ``n_eigs``...).  Every keyword every method
        takes, its constraint and default: ``LANDMARK_PARAMS``; a bad value or an unknown keyword is refused
        before any work.

    Returns
    -------
    LandmarkResult whose ``landmarks`` are input ids, with ``.scores``, ``.plot()``, ``.to_html()``.

    Examples
    --------
    >>> import shapecond as sc
    >>> result = sc.landmarks("demo:animal", 3, "fps", n_points=30, cache=False)
    >>> len(result.landmarks), result.method
    (3, 'fps')
    """
    method = METHOD.check(method)
    # a misspelt option is refused, naming the nearest option, before any work
    v = check_keywords(LANDMARK_PARAMS, dict(options, k=k, method=method, n_points=n_points,
                                             user_landmarks=user_landmarks, scores=scores, effort=effort),
                       "landmarks", context=f" for method {method!r}", others=method_options(method))
    opts, ids = ShapeOptions.of(v), v["user_landmarks"]
    method_kw = {key: value for key, value in options.items() if key not in v}
    if method == "user":
        if not ids:
            raise InputError("method 'user' needs user_landmarks")
        method_kw["ids"] = ids
    common = {"scores": v["scores"], "effort": v["effort"], "score": v["score"], "epsilon": v["epsilon"]}
    chosen, runtime = landmark_options(method, opts.seed, {**method_kw, **common})
    k, shape = v["k"], shape_of(x, v["n_points"], ids, opts)
    guard_landmarks(shape, k, method, v["scores"], opts.force)
    if opts.progress and method in ("cnbs", "cnbs-scale"):
        runtime.setdefault("progress", _cnbs_progress(k))
    return promote(select_landmarks(shape, k, method, chosen, **runtime), LandmarkResult)


def _cnbs_progress(k: int):
    """CNBS's progress callback: "landmark i/k: heat map done/total" on stderr."""
    def show(step, done, total):
        print(f"\rlandmark {step + 1}/{k}: heat map {done}/{total}", end="\n" if done == total else "",
              file=sys.stderr, flush=True)

    return show


def heatmap(x, landmarks=(), n_points: int | None = None, *, effort: str = "default",
            resolve_fraction: float | None = None, score: str = "sigma", epsilon: float | None = None,
            **options) -> HeatMapResult:
    """σ (or δ(ε), ``score="scale"``) with each sample fixed: where the next landmark helps most
    (paper Figures 1 and 4).

    ``landmarks`` (input ids) are fixed already; ``resolve_fraction``, ``score`` and ``epsilon`` as
    ``SymmetryProblem.heatmap``; ``**options`` are those of ``metric_shape`` (``seed``, ``cache``,
    ``force``...).  Every keyword, its constraint and default: ``HEATMAP_PARAMS``; a bad value or an
    unknown keyword is refused before any work.

    Examples
    --------
    >>> import shapecond as sc
    >>> hm = sc.heatmap("demo:animal:delta=0.1", n_points=30, target="samples", cache=False)
    >>> hm.best in hm.samples
    True
    """
    v = check_keywords(HEATMAP_PARAMS, dict(options, landmarks=landmarks, n_points=n_points, effort=effort,
                                            resolve_fraction=resolve_fraction, score=score, epsilon=epsilon), "heatmap")
    opts = ShapeOptions.of(v)
    problem = SymmetryProblem.of_shape(shape_of(x, v["n_points"], v["landmarks"], opts), opts, v["effort"])
    return problem.heatmap(v["landmarks"], resolve_fraction=v["resolve_fraction"], score=v["score"],
                           epsilon=v["epsilon"])


def kappa(x, n_points: int | None = None, *, landmarks=(), trials: int = 20, scale: float = 0.05,
          time_limit: float | None = None, **options) -> KappaResult:
    """Empirical condition number (paper Eq. 4): perturbed copies matched exactly, σ <= κ <= 2σ + 1.

    The samples are matched to samples and every map is enumerated, so at most
    ``symmetry.condition.MAX_PROBE_POINTS`` samples may be free of landmarks; a mesh
    is sampled with 8 points beside the landmarks unless ``n_points`` says otherwise.
    ``**options`` are those of ``metric_shape`` (but ``target="dense"``).  Every keyword, its
    constraint and default: ``KAPPA_PARAMS``; a bad value or an unknown keyword is refused before any work.

    Examples
    --------
    >>> import shapecond as sc
    >>> r = sc.kappa("demo:animal:delta=0.1", trials=3, cache=False)
    >>> r.kappa[0] <= r.kappa_probe_max <= r.kappa[1]
    True
    """
    v = check_keywords(KAPPA_PARAMS, dict(options, n_points=n_points, landmarks=landmarks, trials=trials, scale=scale,
                                          time_limit=time_limit), "kappa")
    opts, ids, n_points = ShapeOptions.of(v), v["landmarks"], v["n_points"]
    if opts.target == "dense":
        raise InputError("kappa probes match samples to samples: target='dense' does not apply")
    limit = MAX_PROBE_POINTS + len(ids)
    if n_points is not None and n_points > limit:
        raise InputError(f"kappa probes enumerate every map: at most {limit} points with {len(ids)} landmarks, "
                         f"got n_points={n_points}")
    loaded = load(x, largest_component=opts.largest_component, symmetry_map=opts.symmetry_map, force=opts.force)
    if n_points is None and not isinstance(loaded, np.ndarray):
        n_points = min(DEFAULT_KAPPA_POINTS + len(ids), limit)
    shape = shape_of(loaded, n_points, ids, replace(opts, target="samples"))
    if shape.n_points > limit:
        raise InputError(f"kappa probes enumerate every map: at most {limit} points with {len(ids)} landmarks, "
                         f"the input has {shape.n_points}")
    bar = _bar(v["trials"], "probes") if opts.progress else None
    try:
        res = kappa_probes(shape.D, trials=v["trials"], seed=opts.seed, landmarks=list(range(len(ids))),
                           scale=v["scale"], time_limit=v["time_limit"], force=opts.force,
                           progress=None if bar is None else lambda done, total: bar.update(1))
    finally:
        if bar is not None:
            bar.close()
    return promote(res, KappaResult, {"shape": shape, "landmark_ids": tuple(ids), "trials": v["trials"]})


def _bar(total: int, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=desc[:-1], leave=False)


__all__ = ["HEATMAP_PARAMS", "KAPPA_PARAMS", "LANDMARK_PARAMS", "SCORE_PARAMS", "heatmap", "kappa", "landmarks", "local_score", "score"]

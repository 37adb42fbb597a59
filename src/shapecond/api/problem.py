"""One shape's metric space with the searches already run on it, for repeated queries."""

from __future__ import annotations

import math
import time

import numpy as np

from ..checks import parse_ids
from ..selection import method_options, select_landmarks
from ..selection.cnbs import RESOLVE_FRACTION, HeatMapOptions, heat_map
from ..symmetry.report import score_report
from ..symmetry.scale import budget_of, default_epsilon
from ..symmetry.search import witness_search
from .guards import guard_heat_map, guard_landmarks
from .inputs import METRIC_SHAPE_PARAMS, shape_of
from .options import K, LANDMARK_SCORE, METHOD, SCORES_AFTER, ShapeOptions, landmark_options
from .params import EFFORT, EPSILON, Choice, FloatRange, Ids, Param, check_keywords
from .results import HeatMapResult, LandmarkResult, ScoreResult, promote
from .settings import score_settings

#: The options of ``SymmetryProblem``, each declared once (``params``): those of ``metric_shape`` and the
#: effort of every search.
PROBLEM_PARAMS = (*METRIC_SHAPE_PARAMS, EFFORT)
#: The options of a heat map itself (``SymmetryProblem.heatmap``; rows of ``scores.HEATMAP_PARAMS``).
RESOLVE = Param("resolve_fraction", FloatRange(0, 1, none=True), None,
                "Share of candidates (those the witness maps move farthest) searched again.",
                cli=("--resolve-fraction",), cli_default=str(RESOLVE_FRACTION))
HEATMAP_SCORE = Param("score", Choice(("sigma", "scale")), "sigma",
                      "sigma: the paper's σ with each point fixed; scale: the scale-aware δ(ε) (the CNBS heat map of "
                      "--method cnbs-scale).", cli=("--score",))
#: The options of ``SymmetryProblem.landmarks`` that every method takes (a method's own, as for
#: ``scores.landmarks``, are checked by its options class, ``selection.method_options``).
PROBLEM_LANDMARK_PARAMS = (K, METHOD, Param("fixed", Ids(), (), "Input ids of samples fixed already."),
                           SCORES_AFTER, LANDMARK_SCORE, EPSILON)


class SymmetryProblem:
    """One shape's metric space with the searches already run on it, for repeated queries.

    The metric shape is built once; the witness search with each landmark set is
    run once and kept, and its best maps warm-start the CNBS heat map and landmark
    selection (the landmark-independent starts are shared), as potpourri3d's
    solvers keep their factorisations.

    Parameters
    ----------
    x : any input of ``load``, or a ``MetricShape``.
    n_points, landmarks : see ``metric_shape``; ``landmarks`` (input ids) are made
        samples so that they can be fixed later.
    seed, effort : for every search.
    **options : the other options of ``metric_shape`` (metric, backend, target, cache, force...).
        Every keyword, its constraint and default: ``PROBLEM_PARAMS``; a bad value or an unknown
        keyword is refused before any work.

    Examples
    --------
    >>> import shapecond as sc
    >>> problem = sc.SymmetryProblem("demo:animal:delta=0.1", n_points=40, target="samples", cache=False)
    >>> first = problem.heatmap().best
    >>> problem.score(landmarks=[first]).sigma[0] <= problem.score().sigma[0]
    True
    """

    def __init__(self, x, n_points: int | None = None, *, landmarks=(), seed: int = 0, effort: str = "default",
                 **options):
        v = check_keywords(PROBLEM_PARAMS, dict(options, n_points=n_points, landmarks=landmarks, seed=seed,
                                                effort=effort), "SymmetryProblem")
        opts = ShapeOptions.of(v)
        self._start(shape_of(x, v["n_points"], v["landmarks"], opts), opts, v["effort"])

    @classmethod
    def of_shape(cls, shape, opts: ShapeOptions, effort: str) -> SymmetryProblem:
        """The problem of a ``MetricShape`` already built with the checked ``opts`` (``scores.heatmap``)."""
        problem = cls.__new__(cls)
        problem._start(shape, opts, effort)
        return problem

    def _start(self, shape, opts: ShapeOptions, effort: str) -> None:
        self.seed, self.effort, self.force = opts.seed, effort, opts.force
        self.shape = shape
        self._searches: dict = {}

    def __repr__(self) -> str:
        s = self.shape
        name = s.geometry.name if s.geometry is not None else "matrix"
        return (f"SymmetryProblem({name}, N={s.n_samples}, M={s.n_targets}, {s.metric}, "
                f"{len(self._searches)} searches kept)")

    @property
    def sample_ids(self) -> np.ndarray:
        """Input ids of the samples (the candidates for landmarks)."""
        return self.shape.sample_ids

    def _indices(self, landmarks) -> tuple:
        return tuple(int(i) for i in self.shape.landmark_indices(parse_ids(landmarks)))

    def search(self, landmarks=()):
        """The witness search (lower bound of σ with its maps) with ``landmarks`` fixed, kept."""
        key = tuple(sorted(self._indices(landmarks)))
        if key not in self._searches:
            self._searches[key] = witness_search(self.shape.D, self.shape.n_samples, list(key), seed=self.seed,
                                                 effort=self.effort)
        return self._searches[key]

    def score(self, landmarks=(), *, exact="auto", upper: bool = False, time_limit: float | None = None,
              epsilon: float | None = None) -> ScoreResult:
        """``ScoreResult`` with ``landmarks`` (input ids of samples) fixed; reuses a kept search.  The
        options are ``score``'s (``scores.SCORE_PARAMS``), checked by the same rows (``score_settings``)."""
        ids = parse_ids(landmarks)
        settings = score_settings(exact=exact, upper=upper, time_limit=time_limit, effort=self.effort,
                                  epsilon=epsilon, seed=self.seed, force=self.force)
        report = score_report(self.shape, ids, settings, search=self.search(ids))
        return promote(report, ScoreResult)

    def heatmap(self, landmarks=(), *, resolve_fraction: float | None = None, score: str = "sigma",
                epsilon: float | None = None) -> HeatMapResult:
        """σ (``score="sigma"``, warm-started from the kept search) or δ(ε) (``score="scale"``)
        with each sample fixed, ``landmarks`` fixed already (paper Figures 1 and 4).

        ``resolve_fraction``: share of candidates searched again (``RESOLVE``; None: CNBS's default);
        ``epsilon``: the level of δ(ε) (None: the median sample spacing)."""
        t0 = time.perf_counter()
        ids = parse_ids(landmarks)
        L = list(self._indices(ids))
        frac = RESOLVE.check(resolve_fraction)
        frac = RESOLVE_FRACTION if frac is None else frac
        n = self.shape.n_samples
        score = HEATMAP_SCORE.check(score)
        epsilon = EPSILON.check(epsilon)  # checked for either score
        guard_heat_map(self.shape, self.force)
        budget, base, unit, eps = None, None, 1.0, None
        if score == "scale":
            eps = default_epsilon(self.shape.D, n) if epsilon is None else epsilon
            budget, unit = budget_of(eps, n, self.shape.D), 1.0 / math.sqrt(n)
        else:
            base = self.search(ids)
        hm = heat_map(self.shape.D, n, L, base, budget,
                      options=HeatMapOptions(seed=self.seed, effort=self.effort, resolve_fraction=frac))
        best = hm.argmin()  # values in the score's units: δ = sqrt(d²) / sqrt(N)
        return HeatMapResult(np.asarray(self.shape.sample_ids), hm.values * unit, float(hm.sigma_before) * unit,
                             int(self.shape.sample_ids[best]), float(hm.values[best]) * unit, tuple(ids),
                             time.perf_counter() - t0, self.shape, score, eps)

    def landmarks(self, k: int, method: str = "cnbs", *, fixed=(), scores: bool | None = None,
                  **options) -> LandmarkResult:
        """``k`` new landmarks after ``fixed`` (input ids of samples); CNBS starts from the kept search.

        ``**options``: ``score`` and ``epsilon`` (which score follows each landmark, and the level of δ(ε))
        and the method's own (``selection.method_options``: ``resolve_fraction``, ``n_eigs``...), as for
        ``landmarks``; the searches' effort and seed are the problem's.  Every keyword every method takes:
        ``PROBLEM_LANDMARK_PARAMS``; a bad value or an unknown keyword is refused before any work."""
        method = METHOD.check(method)
        v = check_keywords(PROBLEM_LANDMARK_PARAMS, dict(options, k=k, method=method, fixed=fixed, scores=scores),
                           "SymmetryProblem.landmarks", context=f" for method {method!r}",
                           others=method_options(method) - {"effort"})
        own = {key: value for key, value in options.items() if key not in v}
        common = {"scores": v["scores"], "effort": self.effort, "score": v["score"], "epsilon": v["epsilon"],
                  "fixed": self._indices(v["fixed"])}
        chosen, runtime = landmark_options(method, self.seed, {**own, **common})
        guard_landmarks(self.shape, v["k"], method, v["scores"], self.force)
        if method == "cnbs":
            runtime.setdefault("base", self.search(v["fixed"]))
        sel = select_landmarks(self.shape, v["k"], method, chosen, **runtime)
        return promote(sel, LandmarkResult)


__all__ = ["HEATMAP_SCORE", "PROBLEM_LANDMARK_PARAMS", "PROBLEM_PARAMS", "RESOLVE", "SymmetryProblem"]

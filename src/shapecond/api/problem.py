"""One shape's metric space with the searches already run on it, for repeated queries."""

from __future__ import annotations

import math
import time

import numpy as np

from ..checks import check_choice, check_float, check_int, check_seed, parse_ids
from ..selection import select_landmarks
from ..selection.cnbs import RESOLVE_FRACTION, HeatMapOptions, heat_map
from ..symmetry.report import score_report
from ..symmetry.scale import budget_of, default_epsilon
from ..symmetry.search import witness_search
from .guards import guard_heat_map, guard_landmarks
from .inputs import shape_of
from .options import ShapeOptions, landmark_options, refuse_unknown
from .params import EFFORT
from .results import HeatMapResult, LandmarkResult, ScoreResult, promote
from .settings import score_settings


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
        opts, _ = ShapeOptions.take({**options, "seed": seed}, "SymmetryProblem")
        self.seed = check_seed(seed)
        self.effort = EFFORT.check(effort)
        self.force = opts.force
        self.shape = shape_of(x, n_points, landmarks, opts)
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
              epsilon: float | None = None, **unknown) -> ScoreResult:
        """``ScoreResult`` with ``landmarks`` (input ids of samples) fixed; reuses a kept search."""
        refuse_unknown(unknown, "SymmetryProblem.score")
        ids = parse_ids(landmarks)
        settings = score_settings(exact=exact, upper=upper, time_limit=time_limit, effort=self.effort,
                                  epsilon=epsilon, seed=self.seed, force=self.force)
        report = score_report(self.shape, ids, settings, search=self.search(ids))
        return promote(report, ScoreResult)

    def heatmap(self, landmarks=(), *, resolve_fraction: float | None = None, score: str = "sigma",
                epsilon: float | None = None, **unknown) -> HeatMapResult:
        """σ (``score="sigma"``, warm-started from the kept search) or δ(ε) (``score="scale"``)
        with each sample fixed, ``landmarks`` fixed already (paper Figures 1 and 4)."""
        refuse_unknown(unknown, "SymmetryProblem.heatmap")
        t0 = time.perf_counter()
        ids = parse_ids(landmarks)
        L = list(self._indices(ids))
        frac = check_float(RESOLVE_FRACTION if resolve_fraction is None else resolve_fraction, "resolve_fraction",
                           lo=0.0, hi=1.0)
        n = self.shape.n_samples
        score = check_choice(score, "score", ("sigma", "scale"))
        epsilon = None if epsilon is None else check_float(epsilon, "epsilon", lo=0.0)  # checked for either score
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
        """``k`` new landmarks after ``fixed`` (input ids of samples); CNBS starts from the kept search."""
        k = check_int(k, "k", lo=0)
        chosen, runtime = landmark_options(method, self.seed, {**options, "scores": scores, "effort": self.effort,
                                                               "fixed": self._indices(fixed)})
        guard_landmarks(self.shape, k, method, scores, self.force)
        if method == "cnbs":
            runtime.setdefault("base", self.search(fixed))
        sel = select_landmarks(self.shape, k, method, chosen, **runtime)
        return promote(sel, LandmarkResult)


__all__ = ["SymmetryProblem"]

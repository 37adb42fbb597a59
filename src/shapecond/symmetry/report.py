"""The full answer to "how hard is this shape to match": the result of ``shapecond score``.

``score_report(shape, landmark_ids)`` runs the symmetry score of a
``MetricShape`` (the σ bracket of paper Eq. 5, σ̂ = σ√N and the κ bracket of
Theorem 4.1, ``score.symmetry_score``), the resolution report for dense targets
(``resolution``), the scale-aware score δ(ε) with its own witness (``scale``)
and the verdict in words (``verdict``), and returns a ``ScoreReport`` whose
``to_dict()`` is the JSON object of ``shapecond score --json``; the Python
interface (``shapecond.score``, which the command line and batch scoring
call) adds its pictures, so their numbers cannot drift apart.
Landmarks and the witnesses are given in the input's own ids.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from shapecond.jsonable import fmt, jsonable
from shapecond.limits import Deadline, search_seconds
from shapecond.symmetry.resolution import ResolutionReport, coarse_level, refine, resolution_for_shape
from shapecond.symmetry.scale import ScaleScore, budget_of, describe, scale_score
from shapecond.symmetry.score import LIMITED, ScoreOptions, SymmetryScore, symmetry_score
from shapecond.symmetry.verdict import verdict


@dataclass(frozen=True, eq=False)
class ScoreReport:
    """σ bracket, κ bracket, witness (input ids), resolution report and verdict of one shape.

    Attributes
    ----------
    score : SymmetryScore (sample indices; ``score.witness[i]`` is a point of Y).
    shape : MetricShape the score was computed on.
    resolution : ResolutionReport or None (only for dense targets on a mesh).
    verdict : one line saying what the numbers mean for matching.
    landmarks : the fixed landmarks, in the input's ids.
    scale : ScaleScore, δ(ε) with its witness (``symmetry.scale``), or None.
    """

    score: SymmetryScore
    shape: object = field(repr=False)
    resolution: ResolutionReport | None
    verdict: str
    landmarks: tuple = ()
    scale: ScaleScore | None = None

    @property
    def sigma(self) -> tuple:
        """(lower, upper) bracket of σ; ``math.inf`` for an exact symmetry."""
        return self.score.sigma_lower, self.score.sigma_upper

    @property
    def kappa(self) -> tuple:
        """(lower, upper) bracket of the condition number (Theorem 4.1)."""
        return self.score.kappa_lower, self.score.kappa_upper

    @property
    def witness_ids(self) -> np.ndarray:
        """Input id of the image of each sample under the witness (a row for a distance matrix)."""
        return self.shape.target_ids[self.score.witness]

    def to_dict(self) -> dict:
        """The JSON object of ``shapecond score --json`` (``inf`` as "inf")."""
        out = self.score.to_dict()
        out["landmarks"] = [int(v) for v in self.landmarks]
        out["samples"] = [int(v) for v in self.shape.sample_ids]
        out["target"] = self.shape.target
        out["resolution"] = None if self.resolution is None else self.resolution.to_dict()
        out["verdict"] = self.verdict
        out["witness_vertices"] = None if self.shape.geometry is None else [int(v) for v in self.witness_ids]
        if self.scale is not None:
            out["scale"] = self.scale.to_dict()
            out["scale"]["witness_vertices"] = (None if self.shape.geometry is None else
                                                [int(v) for v in self.shape.target_ids[self.scale.witness]])
        return jsonable(out)

    def __repr__(self) -> str:
        lo, hi = self.sigma
        return (f"{type(self).__name__}(sigma=[{fmt(lo)}, {fmt(hi)}], kappa=[{fmt(self.kappa[0])}, {fmt(self.kappa[1])}], "
                f"N={self.score.n_points}, M={self.score.n_targets}, verdict={self.verdict!r})")


def _scale(D, n, lm, s, sc, clock) -> ScaleScore:
    """δ(ε) at the settings ``s`` started from the σ search's maps, within the ``Deadline``
    ``clock``; with dense targets searched over the first M/2 targets and refined over all M, as σ
    is (``resolution.coarse_to_fine``)."""
    starts = [sc.witness, *sc.maps]
    if sc.coarse is None:
        return scale_score(D, n, lm, s.epsilon, seed=s.seed, effort=s.effort, starts=starts, time_limit=clock.left())
    t0 = time.perf_counter()
    m_lo = coarse_level(D.shape[0], n)
    lo_starts = [sc.coarse.witness, *sc.coarse.maps] + [t for t in starts if t.max() < m_lo]
    lo = scale_score(D[:m_lo, :m_lo], n, lm, s.epsilon, seed=s.seed, effort=s.effort, starts=lo_starts,
                     time_limit=clock.left())
    # ε and its budget depend on the samples only: the same at both levels
    fine = refine(D, n, lm, [lo.witness, *lo.maps, *starts], budget=budget_of(lo.epsilon, n, D),
                  time_limit=clock.left())
    return describe(D, n, fine.witness, lo.epsilon, lm, time.perf_counter() - t0, fine.maps)


def delta_reserve(time_limit, n, m) -> float:
    """Seconds of a time limit kept for δ(ε): about one witness search (``limits.search_seconds``),
    at most a third of the limit (0 without a limit)."""
    return 0.0 if time_limit is None else min(time_limit / 3.0, search_seconds(n, m))


def _limited(sc: SymmetryScore, what: str) -> SymmetryScore:
    """``sc`` marked ``time_limited`` with a note saying what the limit cut."""
    return replace(sc, notes=(*sc.notes, f"{LIMITED} {what}"), time_limited=True)


@dataclass(frozen=True)
class ScoreSettings(ScoreOptions):
    """How ``score_report`` scores a shape: ``score.ScoreOptions`` (how σ is bracketed: exact,
    upper, time_limit, seed, effort, force) and the level of δ(ε).

    Attributes
    ----------
    epsilon : distortion level of δ(ε) (None: ``scale.default_epsilon``, the median sample spacing).
    """

    epsilon: float | None = None


def score_report(shape, landmark_ids=(), settings: ScoreSettings = ScoreSettings(), search=None) -> ScoreReport:
    """Score a ``MetricShape`` whose samples include the landmarks ``landmark_ids`` (input ids).

    ``search``: a witness search already run with these landmarks (reused).  ``settings.time_limit``
    bounds all of it (the distances are computed already): σ's bracket and the resolution report
    get it less a reserve for δ(ε) (``delta_reserve``), δ(ε) what is left; a note for each part it
    cut, and the JSON's ``time_limited``.
    """
    s = settings
    clock = Deadline(s.time_limit)
    reserve = delta_reserve(s.time_limit, shape.n_points, shape.n_targets)
    lm = shape.landmark_indices(landmark_ids) if len(landmark_ids) else np.zeros(0, dtype=np.int64)
    sc = symmetry_score(shape.D, shape.n_points, lm, search=search, options=replace(s, time_limit=clock.left(reserve)))
    res = resolution_for_shape(shape, lm, seed=s.seed, effort=s.effort, score=sc, time_limit=clock.left(reserve))
    if res is not None and sc.coarse is None and clock.passed(reserve):  # its own search at M/2 was cut
        sc = _limited(sc, "the resolution report's search stopped early")
    delta = _scale(shape.D, shape.n_points, lm, s, sc, clock)
    if clock.passed():
        sc = _limited(sc, "δ(ε)'s search stopped early; δ is the widest map found in time")
    return ScoreReport(sc, shape, res, verdict(sc, shape.D, res, shape.covering_radius, delta, shape.sample_ids),
                       tuple(int(v) for v in landmark_ids), delta)

"""Is the witness an isometry within sampling resolution?

With dense targets (a set Y of M points containing the N samples X as its
FPS prefix) the score of an exact symmetry keeps growing as M grows: the
mirror image of every sample gets a closer target, so Dist² of the witness
shrinks with the covering radius of Y and σ → ∞.  An asymmetric shape instead
converges to a finite value.  The report compares the dense score at two
target counts M_lo < M_hi (M_hi = 2 M_lo) and classifies:

* ``"symmetric"``: σ = ∞ already (an exact isometry among the targets);
* ``"converged"``: |σ(M_hi) − σ(M_lo)| < ``CONVERGED_RTOL`` · σ(M_lo);
* ``"symmetric within resolution"``: σ grows by at least ``CONVERGED_RTOL``
  *and* the witness at M_hi distorts distances by no more than the sampling
  resolution: its RMS distortion sqrt(Dist²/N²) is at most
  ``RESOLUTION_FACTOR`` × the covering radius r of Y (an isometry rounded to
  the nearest target moves each distance by at most 2r; typical errors are
  below r) *and* the witness is a global map, not a local one: its RMS
  displacement sqrt(d²/N) is at least ``DISPLACEMENT_FACTOR`` × r.  A map
  that moves the samples by less than a few covering radii is within sampling
  noise of the identity: on TOSCA dog5 (N = 100, M = 800) the witness moves
  one sample across the tip of a thin part (RMS displacement 0.19 r, RMS
  distortion 0.01 r), which says nothing about a symmetry of the surface,
  whereas the mirror witnesses of cat0, dog0, horse5 and wolf0 move the
  samples by 10-14 r on average;
* ``"undecided"``: anything else (σ grows while the distortion is well above
  the resolution, or σ falls); reported honestly rather than forced.

Measured on TOSCA (the project's witness-search benchmark): the mirror
witnesses of the exactly symmetric null shapes have RMS distortion about
0.3-0.6 r, deformed poses several r.

The two levels are also how a large dense σ is searched (``coarse_to_fine``):
the full witness search over Y_lo, then each of its maps polished once over Y.
A local-search move costs O(N·M), and a map found over Y_lo is already most of
the way to its optimum over Y, so this costs a fraction of a full search over
Y, and the report then judges the score's own two levels with no search of
its own.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from shapecond.jsonable import jsonable
from shapecond.limits import Deadline, search_seconds
from shapecond.threads import one_blas_thread
from shapecond.symmetry import _kernels as K
from shapecond.symmetry import objective as obj
from shapecond.symmetry.search import (DENSE_K, EFFORTS, MapPool, SearchResult, SearchStage, prepare_instance,
                                      best_reassignment, witness_search)
from shapecond.symmetry.starts import reflection_starts

CONVERGED_RTOL = 0.10
#: ``two_levels``: dense searches estimated to take at least this long run in two levels.
TWO_LEVEL_SECONDS = 2.0
RESOLUTION_FACTOR = 1.0
DISPLACEMENT_FACTOR = 3.0


@dataclass(frozen=True)
class ResolutionReport:
    """Dense score at two target counts and the resulting flag (see module docstring)."""

    flag: str
    covering_radius: float | None
    sigma_lo: float
    sigma_hi: float
    n_targets_lo: int
    n_targets_hi: int
    relative_change: float
    distortion_rms: float
    displacement_rms: float

    def to_dict(self) -> dict:
        return jsonable({"flag": self.flag, "covering_radius": self.covering_radius, "sigma_lo": self.sigma_lo,
                "sigma_hi": self.sigma_hi, "n_targets_lo": self.n_targets_lo,
                "n_targets_hi": self.n_targets_hi, "relative_change": self.relative_change,
                "distortion_rms": self.distortion_rms, "displacement_rms": self.displacement_rms})


def classify(sigma_lo: float, sigma_hi: float, distortion_rms: float, covering_radius: float | None,
             displacement_rms: float = math.inf) -> str:
    """The flag of the module docstring from the two scores and the witness's distortion and displacement."""
    if sigma_lo == math.inf or sigma_hi == math.inf:
        return "symmetric"
    change = (sigma_hi - sigma_lo) / sigma_lo if sigma_lo > 0 else math.inf
    if abs(change) < CONVERGED_RTOL:
        return "converged"
    if change >= CONVERGED_RTOL and covering_radius is not None \
            and distortion_rms <= RESOLUTION_FACTOR * covering_radius \
            and displacement_rms >= DISPLACEMENT_FACTOR * covering_radius:
        return "symmetric within resolution"
    return "undecided"


def coarse_level(m: int, n: int) -> int:
    """M_lo, the target count of the lower level: the first half of the M targets, at least the N samples."""
    return max(n, m // 2)


def two_levels(n: int, m: int) -> bool:
    """Whether σ over M dense targets is searched by ``coarse_to_fine`` rather than by one full search.

    Only where the full search is slow (estimated at least ``TWO_LEVEL_SECONDS``,
    ``limits.search_seconds``) and the lower level is itself dense: below that the
    full search is affordable and explores more starts over Y (on small random
    instances, N = 4-20 and M = 8N, it finds a higher σ about half the time).
    """
    return coarse_level(m, n) > n and search_seconds(n, m) >= TWO_LEVEL_SECONDS


def refine(D, n_samples, landmarks, maps, budget=None, time_limit=None) -> SearchResult:
    """Polish each of ``maps`` over all M targets of ``D`` (the witness search's dense local search).

    A map over the first M_lo targets is a map over all M (FPS prefix), so the
    maps a search found over Y_lo, each polished once over Y, are the maps of a
    search over Y that starts where Y_lo left off.  ``budget``: the scale-aware
    objective (``witness_search(budget=...)``).  Returns the ``search.KEEP`` best
    distinct maps, the given ones included, as a ``SearchResult``.  ``time_limit``
    (seconds): once it is reached the maps left are dropped (none is polished when
    it is reached already).
    """
    t0 = time.perf_counter()
    deadline = Deadline(time_limit)
    D, n, lm, free = prepare_instance(D, n_samples, landmarks)
    stage = SearchStage(D, n, free, DENSE_K)
    pool = MapPool(D, n, budget, lm)
    mode, s = (K.MODE_RATIO, 0.0) if budget is None else (K.MODE_BUDGET, float(budget))
    first = {}  # each distinct map once, in order of first appearance
    for t in maps:
        t = np.asarray(t, dtype=np.int64)
        first.setdefault(t.tobytes(), t)
    maps = list(first.values())
    if deadline.passed():  # no time to polish: the maps as they are
        for t in maps:
            pool.add(t)
        return pool.result(time.perf_counter() - t0)
    with one_blas_thread():
        for t, u in stage.polished(maps, mode, s, lm):  # parallel threads, taken in order
            if t.tobytes() in pool.items:  # polished already (the witness is also the first map)
                continue
            pool.add(t)
            if pool.best_value() < math.inf:
                pool.add(u)
            if deadline.passed():
                break
    return pool.result(time.perf_counter() - t0)


def coarse_to_fine(D, n_samples, landmarks=(), seed=0, effort="default", starts=(),
                   budget=None, time_limit=None) -> tuple[SearchResult, SearchResult]:
    """The witness search over the first M_lo targets, then its maps refined over all M.

    Returns ``(fine, coarse)``: the search over Y and the one over Y_lo, the two
    levels the report compares.  Cheaper than a search at each level: the local
    search's moves cost O(N·M) each, and at M_lo most of them are already made.
    On the eight TOSCA null shapes (N = 400, M = 3,200) σ is as high as a full
    search over Y, or higher, in less time.  ``time_limit`` (seconds) bounds both levels together.
    """
    clock = Deadline(time_limit)
    D, n, lm, free = prepare_instance(D, n_samples, landmarks)
    m_lo = coarse_level(D.shape[0], n)
    lo_starts = [t for t in starts if np.max(t) < m_lo]
    coarse = witness_search(D[:m_lo, :m_lo], n, lm, seed=seed, effort=effort, starts=lo_starts, budget=budget,
                            time_limit=clock.left())
    # two starts of the full search that the coarse maps do not replace: one sample sent to a
    # target of the second half right beside it (a thin tip's sample, the witness of horse0), and
    # the reflections of the MDS embedding onto all of Y, which land each mirror image on its
    # nearest target over Y (polished from the coarse mirror instead, σ ended 0.1-1.2 % lower
    # on wolf0, david0 and michael0)
    extra = [best_reassignment(D, n, free)] if free.size and not clock.passed() else []
    if free.size >= 3 and not clock.passed():
        extra += reflection_starts(D, n, free, lm, *EFFORTS[effort]["reflect"])
    fine = refine(D, n, lm, [coarse.witness, *coarse.maps, *starts, *extra], budget=budget, time_limit=clock.left())
    return fine, coarse


def _best_global(D, n, maps, covering_radius):
    """The highest-scoring map among ``maps`` that moves the samples by >= DISPLACEMENT_FACTOR r (RMS).

    Returns (score, map) or (score, map) of the best map overall when none is global.
    """
    scored = [(obj.map_score(D, t), np.asarray(t)) for t in maps]
    if covering_radius is not None:
        global_maps = [(v, t) for v, t in scored
                       if math.sqrt(obj.d2(D, t) / n) >= DISPLACEMENT_FACTOR * covering_radius]
        if global_maps:
            return max(global_maps, key=lambda vt: vt[0])
    return max(scored, key=lambda vt: vt[0])


def resolution_report(D_hi, n_samples: int, covering_radius: float | None, landmarks=(), seed=0,
                      effort="default", score_hi=None, time_limit=None) -> ResolutionReport:
    """Compare the dense score over the first M/2 targets with the one over all M.

    The question is whether the *surface* has a symmetry, so the report judges
    the best global map among the search's distinct local optima (RMS
    displacement >= ``DISPLACEMENT_FACTOR`` r) at both target counts: on TOSCA
    horse0 (N = 400, M = 3200) the overall witness moves one sample across the
    tip of a thin part and outscores the mirror map (3.97 against 2.62), yet the
    mirror is what makes the horse symmetric.  ``sigma_lo``/``sigma_hi`` are the
    scores of the maps judged; without a global map they are the overall scores.

    Parameters
    ----------
    D_hi : (M, M) distances over Y (samples first, FPS order, so its leading
        (M/2) block is the same construction with half the targets).
    covering_radius : covering radius of the full Y (units of D_hi).
    score_hi : an already computed ``SearchResult`` (or ``SymmetryScore``) for D_hi,
        whose witness and maps are reused (its maps also warm-start the M/2 search); its coarse
        level (``coarse_to_fine``'s, ``SymmetryScore.coarse``), when it has one, is reused as is.
        Without a score, both levels come from one ``coarse_to_fine`` search.
    time_limit : seconds for the searches run here (None: no limit).
    """
    m = D_hi.shape[0]
    m_lo = coarse_level(m, n_samples)
    score_lo = getattr(score_hi, "coarse", None)
    if score_hi is None and score_lo is None and two_levels(n_samples, m):
        score_hi, score_lo = coarse_to_fine(D_hi, n_samples, landmarks, seed=seed, effort=effort,
                                            time_limit=time_limit)
    elif score_hi is None:
        score_hi = witness_search(D_hi, n_samples, landmarks, seed=seed, effort=effort, time_limit=time_limit)
    maps_hi = [score_hi.witness] + list(getattr(score_hi, "maps", ()))
    D_lo = D_hi[:m_lo, :m_lo]
    if score_lo is None:
        warm = [t for t in maps_hi if t.max() < m_lo]
        score_lo = witness_search(D_lo, n_samples, landmarks, seed=seed, effort=effort, starts=warm,
                                  time_limit=time_limit)
    maps_lo = [score_lo.witness] + list(score_lo.maps)
    sig_lo, _ = _best_global(D_lo, n_samples, maps_lo, covering_radius)
    # a map over Y_lo is a map over Y: the maps found at M/2 count at M too
    sig_hi, w = _best_global(D_hi, n_samples, maps_hi + maps_lo, covering_radius)
    rms = math.sqrt(obj.dist2(D_hi, w)) / n_samples
    disp = math.sqrt(obj.d2(D_hi, w) / n_samples)
    change = (sig_hi - sig_lo) / sig_lo if 0 < sig_lo < math.inf and sig_hi < math.inf else \
        (0.0 if sig_hi == sig_lo else math.inf)
    return ResolutionReport(classify(sig_lo, sig_hi, rms, covering_radius, disp), covering_radius, sig_lo,
                            sig_hi, m_lo, m, change, rms, disp)


def resolution_for_shape(shape, landmarks=(), seed=0, effort="default", score=None,
                         time_limit=None) -> ResolutionReport | None:
    """Resolution report of a dense ``MetricShape`` (None for bijections or a matrix input)."""
    if shape.geometry is None or shape.n_targets <= shape.n_points:
        return None
    return resolution_report(shape.D, shape.n_points, shape.covering_radius, landmarks, seed, effort, score,
                             time_limit=time_limit)

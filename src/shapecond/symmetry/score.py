"""The global symmetry score as a bracket, with its witness and the κ bracket.

Assembles the three estimators of σ(X) (paper Eq. 5, L² case):

* **lower**: ``search.witness_search``, always run; a certified lower bound
  attained by the returned witness map, never below the best single swap;
* **exact**: ``exact.exact_sigma`` (enumeration, or branch and bound within
  ``time_limit``); when it finishes, lower = upper = exact and the witness is
  the exact maximiser;
* **upper**: the exact value if known, else the LP relaxation
  (``relax.lp_upper_bound``) when asked for and within its size limit, else
  ``inf`` (no cheap valid upper bound exists: see ``paper_bound``).

Also reported: the size-free score σ̂ = σ·√N and the bracket of
the condition number σ_lower ≤ κ ≤ 2·σ_upper + 1 (Theorem 4.1).
``time_limit`` bounds each of the exact and LP solves; the search always runs
its full ``effort`` so that the lower bound is deterministic given ``seed``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from shapecond.jsonable import jsonable
from shapecond.errors import InputError, TooLargeError
from shapecond.limits import check_cost, search_seconds
from shapecond.symmetry.resolution import coarse_to_fine, two_levels
from shapecond.symmetry.search import prepare_instance, best_single_swap, witness_search

#: ``exact="auto"`` computes σ exactly when enumeration is quick (<= this many maps).
AUTO_EXACT_MAPS = 362_880  # 9!: about half a second


@dataclass(frozen=True)
class SymmetryScore:
    """Bracket of σ(X) (Eq. 5) with its witness, σ̂ = σ√N and the κ bracket (Thm 4.1).

    Attributes
    ----------
    sigma_lower, sigma_upper : bracket of σ (``math.inf`` allowed, never NaN).
    sigma_exact : σ when computed and finished, else None.
    witness : (N,) int64 map attaining ``sigma_lower`` (witness[i] = j: T(sample i) = target j).
    swap_floor : σ of the best single swap (``sigma_lower`` is never below it).
    n_points, n_targets : N and M.
    landmarks : sample indices fixed by every map.
    upper_method : "exact", "isometry" (the witness is one: σ = inf), "lp" or "none".
    maps, sigmas : distinct local optima of the search, best first (warm starts).
    notes : human-readable remarks (LP refused, exact not finished, ...).
    coarse : with dense targets, the search over the first M/2 targets that the
        search over Y was refined from (``resolution.coarse_to_fine``; the
        resolution report's lower level), else None.
    """

    sigma_lower: float
    sigma_upper: float
    sigma_exact: float | None
    witness: np.ndarray
    swap_floor: float
    n_points: int
    n_targets: int
    landmarks: tuple
    seconds: float
    upper_method: str = "none"
    maps: tuple = field(default=(), repr=False)
    sigmas: tuple = ()
    notes: tuple = ()
    coarse: object = field(default=None, repr=False)

    @property
    def sigma_hat_lower(self) -> float:
        return self.sigma_lower * math.sqrt(self.n_points)

    @property
    def sigma_hat_upper(self) -> float:
        return self.sigma_upper * math.sqrt(self.n_points)

    @property
    def kappa_lower(self) -> float:
        return self.sigma_lower

    @property
    def kappa_upper(self) -> float:
        return 2.0 * self.sigma_upper + 1.0

    def to_dict(self) -> dict:
        return jsonable({
            "n_points": self.n_points,
            "n_targets": self.n_targets,
            "landmarks": [int(v) for v in self.landmarks],
            "sigma": {"lower": self.sigma_lower, "upper": self.sigma_upper, "exact": self.sigma_exact},
            "sigma_hat": {"lower": self.sigma_hat_lower, "upper": self.sigma_hat_upper},
            "kappa": {"lower": self.kappa_lower, "upper": self.kappa_upper},
            "witness": [int(v) for v in self.witness],
            "swap_floor": self.swap_floor,
            "upper_method": self.upper_method,
            "notes": list(self.notes),
            "seconds": self.seconds,
        })


def check_exact(exact):
    """``exact`` if it is "auto", True or False (a numpy bool too); ``InputError`` otherwise."""
    if isinstance(exact, (bool, np.bool_)) or (isinstance(exact, str) and exact == "auto"):
        return exact
    raise InputError(f"exact must be 'auto', True or False, got {exact!r}")


def _exact_wanted(exact, n, m, n_landmarks) -> bool:
    if check_exact(exact) == "auto":
        from shapecond.symmetry.exact import map_count

        return map_count(n, m, n_landmarks) <= AUTO_EXACT_MAPS
    return bool(exact)


def symmetry_score(D, n_samples=None, landmarks=(), exact="auto", upper=False, time_limit=10.0, seed=0,
                   effort="default", force=False, search=None) -> SymmetryScore:
    """Bracket of the global symmetry score σ(X) (Eq. 5) and of κ (Theorem 4.1).

    Parameters
    ----------
    D : (M, M) distance matrix; the samples are the first ``n_samples`` points
        (default M: bijections, the paper's score; M > N: dense targets).
    landmarks : sample indices fixed by every map.
    exact : "auto" (only when enumeration is quick: at most ``AUTO_EXACT_MAPS``
        maps), True (enumeration or branch and bound within ``time_limit``) or False.
    upper : compute the LP upper bound when σ is not known exactly; refused
        above the LP's size limit (then ``sigma_upper = inf`` and a note).
    time_limit : seconds for each of the exact and LP solves (None: no limit).
    seed, effort : passed to ``witness_search``.
    force : run the exact and LP solves even beyond their memory and size limits
        (otherwise they are skipped with a note and the bracket keeps its bounds).
    search : a ``witness_search`` result for the same D, N, landmarks and seed, to
        reuse instead of searching again (``api.SymmetryProblem`` keeps them).

    With many dense targets (``resolution.two_levels``: N = 400, M = 3,200) the
    search runs over the first M/2 targets and its maps are then refined over
    all M (``resolution.coarse_to_fine``): the same σ or higher on the TOSCA null
    shapes for a fraction of the time, and the lower level is kept (``coarse``)
    for the resolution report.
    """
    t0 = time.perf_counter()
    D, n, lm, _ = prepare_instance(D, n_samples, landmarks)
    m = D.shape[0]
    notes = []
    coarse = None
    if search is None:
        check_cost(f"the witness search at N = {n}, M = {m}", search_seconds(n, m), force=force)
        if two_levels(n, m):
            res, coarse = coarse_to_fine(D, n, lm, seed=seed, effort=effort)
        else:
            res = witness_search(D, n, lm, seed=seed, effort=effort)
    else:
        res = search
    floor = best_single_swap(D, n, lm)[0]
    lower, witness = res.sigma, res.witness
    sigma_exact, hi, method = None, math.inf, "none"
    if lower == math.inf:  # a non-identity isometry: σ = inf exactly, nothing to bound
        sigma_exact, hi, method = math.inf, math.inf, "isometry"
    elif _exact_wanted(exact, n, m, lm.size):
        from shapecond.symmetry.exact import exact_sigma

        try:
            ex = exact_sigma(D, n, lm, time_limit=time_limit, warm=res, force=force)
        except TooLargeError as err:
            ex = None
            notes.append(f"exact σ not attempted: {err}")
        if ex is None:
            pass
        elif ex.finished and ex.sigma is not None:
            if ex.sigma >= lower * (1 - 1e-9):
                sigma_exact = ex.sigma
                lower = hi = ex.sigma
                method = "exact"
                if ex.witness is not None:
                    witness = np.asarray(ex.witness, dtype=np.int64)
            else:  # a map beats the "exact" value: trust the map, report it
                notes.append(f"exact solver returned {ex.sigma:.6g} below the witness {lower:.6g}; ignored")
        else:
            notes.append(f"exact solver did not finish within {time_limit} s")
    if method == "none" and upper and lower != math.inf:
        from shapecond.symmetry.relax import lp_upper_bound

        try:
            lp = lp_upper_bound(D, n, lm, time_limit=time_limit, force=force)
            hi, method = max(lp.upper, lower), "lp"
            if lp.upper == math.inf and lp.status.startswith("time"):
                notes.append(f"LP upper bound did not finish within {time_limit} s")
        except TooLargeError as err:
            notes.append(f"no upper bound: {err}")
    return SymmetryScore(
        sigma_lower=lower, sigma_upper=hi, sigma_exact=sigma_exact, witness=witness, swap_floor=floor,
        n_points=n, n_targets=m, landmarks=tuple(int(v) for v in lm), seconds=time.perf_counter() - t0,
        upper_method=method, maps=res.maps, sigmas=res.sigmas, notes=tuple(notes), coarse=coarse)

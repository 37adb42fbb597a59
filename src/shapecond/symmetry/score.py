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
``time_limit`` (seconds) bounds the whole bracket: the search stops at the best
map found when it is reached (a certified lower bound still, but one that
depends on the machine's speed) and the exact and LP solves get what is left;
``time_limited`` and a note say when it cut any of them.  Without it the
search runs its full ``effort``, so that the lower bound is deterministic
given ``seed``, and each solve gets ``limits.SOLVE_SECONDS``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from shapecond.jsonable import jsonable
from shapecond.errors import TooLargeError
from shapecond.limits import SOLVE_SECONDS, Deadline, check_cost, search_seconds
from shapecond.symmetry.exact import exact_sigma, map_count
from shapecond.symmetry.resolution import coarse_to_fine, two_levels
from shapecond.symmetry.search import best_single_swap, prepare_instance, witness_search

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
    time_limited : whether a time limit stopped the search or a solve early (a note says which).
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
    time_limited: bool = False

    def __repr__(self) -> str:
        moved = int(np.sum(np.asarray(self.witness) != np.arange(len(self.witness))))
        return (f"SymmetryScore(sigma in [{self.sigma_lower:.4g}, {self.sigma_upper:.4g}] ({self.upper_method}), "
                f"swap floor {self.swap_floor:.4g}, N={self.n_points}, M={self.n_targets}, "
                f"{len(self.landmarks)} landmarks, witness moves {moved} of {self.n_points} samples, "
                f"{len(self.notes)} notes, {self.seconds:.2f} s)")

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
            "time_limited": self.time_limited,
            "seconds": self.seconds,
        })


def _exact_wanted(exact, n, m, n_landmarks) -> bool:
    if isinstance(exact, str) and exact == "auto":
        return map_count(n, m, n_landmarks) <= AUTO_EXACT_MAPS
    return bool(exact)


@dataclass(frozen=True)
class ScoreOptions:
    """How ``symmetry_score`` brackets σ.

    Attributes
    ----------
    exact : "auto" (only when enumeration is quick: at most ``AUTO_EXACT_MAPS``
        maps), True (enumeration or branch and bound within ``time_limit``) or False.
    upper : compute the LP upper bound when σ is not known exactly; refused
        above the LP's size limit (then ``sigma_upper = inf`` and a note).
    time_limit : seconds for the whole bracket: the search, then the exact and LP
        solves in what is left (None: the search runs in full, each solve gets
        ``limits.SOLVE_SECONDS``).
    seed, effort : passed to ``witness_search``.
    force : run the exact and LP solves even beyond their memory and size limits
        (otherwise they are skipped with a note and the bracket keeps its bounds).
    """

    exact: object = "auto"
    upper: bool = False
    time_limit: float | None = None
    seed: int = 0
    effort: str = "default"
    force: bool = False


def symmetry_score(D, n_samples=None, landmarks=(), search=None, options: ScoreOptions = ScoreOptions()) -> SymmetryScore:
    """Bracket of the global symmetry score σ(X) (Eq. 5) and of κ (Theorem 4.1).

    Parameters
    ----------
    D : (M, M) distance matrix; the samples are the first ``n_samples`` points
        (default M: bijections, the paper's score; M > N: dense targets).
    landmarks : sample indices fixed by every map.
    search : a ``witness_search`` result for the same D, N, landmarks and seed, to
        reuse instead of searching again (``api.SymmetryProblem`` keeps them).
    options : ScoreOptions (``exact``, ``upper``, ``time_limit``, ``seed``, ``effort``,
        ``force``), taken as checked (``api.settings.score_settings`` checks a user's).

    With many dense targets (``resolution.two_levels``: N = 400, M = 3,200) the
    search runs over the first M/2 targets and its maps are then refined over
    all M (``resolution.coarse_to_fine``): the same σ or higher on the TOSCA null
    shapes for a fraction of the time, and the lower level is kept (``coarse``)
    for the resolution report.
    """
    opts = options
    t0 = time.perf_counter()
    clock = Deadline(opts.time_limit)
    D, n, lm, _ = prepare_instance(D, n_samples, landmarks)
    m = D.shape[0]
    notes = []
    res, coarse = (search, None) if search is not None else _search(D, n, lm, opts, clock.left())
    if clock.passed() and res.sigma < math.inf:  # σ = inf is exact: nothing was lost
        notes.append(f"{LIMITED} the witness search stopped at {opts.time_limit:g} s; its lower bound is "
                     "the best map found in time")
    floor = best_single_swap(D, n, lm)[0]
    lower, witness = res.sigma, res.witness
    sigma_exact, hi, method = None, math.inf, "none"
    if lower == math.inf:  # a non-identity isometry: σ = inf exactly, nothing to bound
        sigma_exact, hi, method = math.inf, math.inf, "isometry"
    elif _exact_wanted(opts.exact, n, m, lm.size):
        exact = _exact(D, n, lm, res, opts, notes, clock)
        if exact is not None:
            sigma_exact, witness = exact
            lower = hi = sigma_exact
            method = "exact"
    if method == "none" and opts.upper and lower != math.inf:
        hi, method = _lp_upper(D, n, lm, lower, opts, notes, clock)
    return SymmetryScore(
        sigma_lower=lower, sigma_upper=hi, sigma_exact=sigma_exact, witness=witness, swap_floor=floor,
        n_points=n, n_targets=m, landmarks=tuple(int(v) for v in lm), seconds=time.perf_counter() - t0,
        upper_method=method, maps=res.maps, sigmas=res.sigmas, notes=tuple(notes), coarse=coarse,
        time_limited=any(note.startswith(LIMITED) for note in notes))


#: How every note saying that a time limit cut the work short begins.
LIMITED = "time limit reached:"


def _search(D, n, lm, opts, time_limit):
    """The witness search (over two levels of targets when ``resolution.two_levels``) within
    ``time_limit`` seconds (None: its full effort): (the search result, its coarse level or None)."""
    m = D.shape[0]
    estimate = search_seconds(n, m)
    check_cost(f"the witness search at N = {n}, M = {m}",
               estimate if time_limit is None else min(estimate, time_limit), force=opts.force)
    if two_levels(n, m):
        return coarse_to_fine(D, n, lm, seed=opts.seed, effort=opts.effort, time_limit=time_limit)
    return witness_search(D, n, lm, seed=opts.seed, effort=opts.effort, time_limit=time_limit), None


def _solve_seconds(clock):
    """Seconds for the exact or the LP solve: what is left of the limit, or ``SOLVE_SECONDS``."""
    left = clock.left()
    return SOLVE_SECONDS if left is None else left


def _exact(D, n, lm, res, opts, notes, clock):
    """``(σ, witness)`` from ``exact.exact_sigma`` warm-started from the search ``res``, or None
    (with a note) when it was refused, did not finish, or came out below the search's witness
    (a map beats the "exact" value: the map is trusted)."""
    seconds = _solve_seconds(clock)
    try:
        ex = exact_sigma(D, n, lm, time_limit=seconds, warm=res, force=opts.force)
    except TooLargeError as err:
        notes.append(f"exact σ not attempted: {err}")
        return None
    if not (ex.finished and ex.sigma is not None):
        notes.append(f"{LIMITED} the exact solver stopped after {seconds:.3g} s before proving σ")
        return None
    if ex.sigma >= res.sigma * (1 - 1e-9):
        return ex.sigma, (res.witness if ex.witness is None else np.asarray(ex.witness, dtype=np.int64))
    notes.append(f"exact solver returned {ex.sigma:.6g} below the witness {res.sigma:.6g}; ignored")
    return None


def _lp_upper(D, n, lm, lower, opts, notes, clock):
    """``(upper, method)`` from the LP relaxation (at least ``lower``), or ``(inf, "none")`` with a
    note when it is refused."""
    from shapecond.symmetry.relax import lp_upper_bound  # highspy: loaded only when an LP bound is asked for

    seconds = _solve_seconds(clock)
    try:
        lp = lp_upper_bound(D, n, lm, time_limit=seconds, force=opts.force)
    except TooLargeError as err:
        notes.append(f"no upper bound: {err}")
        return math.inf, "none"
    if lp.upper == math.inf and lp.status.startswith("time"):
        notes.append(f"{LIMITED} the LP upper bound stopped after {seconds:.3g} s")
    return max(lp.upper, lower), "lp"

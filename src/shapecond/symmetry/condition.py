"""Condition number κ of a shape (paper Section 4, Eq. 4 and Theorem 4.1).

Definitions used here (paper Eq. 4, L² case; the paper is terse, so we state them):

- a perturbed copy ``X̃`` is the same sample set with distances ``D̃``
  (symmetric, zero diagonal, non-negative);
- ``d(X, X̃) = ‖D − D̃‖_F``: the L² distortion (Eq. 3) of the identity
  correspondence between X and X̃, i.e. how far X̃ is from X;
- ``T_opt = argmin_T Σ_{x,x'} (D[x,x'] − D̃[Tx,Tx'])²`` over bijections fixing the
  landmarks: the map a perfect L² matcher returns between X and X̃;
- ``d(T_opt, Id) = sqrt(Σ_x D[x, T_opt x]²)`` (Eq. 2 measured on X);
- a *probe* is the ratio ``d(T_opt, Id) / d(X, X̃)``; κ is their supremum.

Theorem 4.1: σ <= κ <= 2σ + 1.  With the definitions above every probe obeys
the sharper ``ratio <= 2σ``: ``Dist_X(T) = ‖D − P D Pᵀ‖ <= ‖D − P D̃ Pᵀ‖ +
‖D̃ − D‖ <= 2 d(X, X̃)`` because ``T_opt`` is at least as good as the identity,
and ``d(T, Id) <= σ Dist_X(T)`` for every non-identity map.  The ``+1`` is what
measuring the displacement on X̃ instead of X costs (at most ``d(X, X̃)``).
The lower end is reached by the construction of the proof: with ``T*`` the
witness of σ, ``D̃[T* x, T* x'] = D[x, x']`` makes ``T*`` an isometry X → X̃, so
``T_opt = T*`` and the probe equals ``sqrt(d²(T*)) / sqrt(Dist²(T*)) = σ``.
Blends ``D̃ = (1 − λ) D + λ D*`` with ``λ ∈ (1/2, 1]`` give probes ``σ/λ`` when
``T_opt = T*``.

Probes need the exact ``T_opt``, found by enumeration, so they are limited to
``MAX_PROBE_POINTS`` free samples.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..jsonable import jsonable
from ..checks import check_float, check_int, check_seed
from ..errors import TooLargeError
from ..limits import check_cost
from .exact import enumerate_maps, exact_sigma, map_count
from .objective import check_instance

#: Largest number of free samples for which probes enumerate all maps (9! maps).
MAX_PROBE_POINTS = 9
_BLOCK = 16_384


def kappa_bracket(sigma_lower, sigma_upper):
    """Theorem 4.1: ``(σ_lower, 2 σ_upper + 1)``; upper ``inf`` when unknown.

    ``None`` for either end means "unknown": the lower end becomes 0 and the
    upper end ``inf``.
    """
    lo = 0.0 if sigma_lower is None else float(sigma_lower)
    if sigma_upper is None or math.isinf(sigma_upper):
        return lo, math.inf
    return lo, 2.0 * float(sigma_upper) + 1.0


@dataclass(frozen=True)
class ProbeResult:
    """Empirical probes of κ (Eq. 4).

    Attributes
    ----------
    ratios : tuple of float
        ``d(T_opt, Id) / d(X, X̃)`` per probe.
    kinds : tuple of str
        ``"witness"`` (Theorem 4.1 construction, λ = 1), ``"witness-blend"``,
        ``"blend"`` (towards a random relabelling) or ``"noise"``.
    sigma : float
        Exact σ (``inf`` for an isometry).
    witness : ndarray or None
        The map attaining σ.
    seconds : float
    notes : tuple of str
        E.g. that ``time_limit`` stopped the probes early.
    """

    ratios: tuple
    kinds: tuple
    sigma: float
    witness: np.ndarray | None
    seconds: float
    notes: tuple = ()

    @property
    def kappa_probe_max(self) -> float:
        return max(self.ratios) if self.ratios else 0.0

    @property
    def kappa(self) -> tuple:
        return kappa_bracket(self.sigma, self.sigma)

    def to_dict(self) -> dict:
        lo, hi = self.kappa
        return jsonable({
            "probes": list(self.ratios),
            "probe_kinds": list(self.kinds),
            "kappa_probe_max": self.kappa_probe_max,
            "sigma": self.sigma,
            "kappa": {"lower": lo, "upper": hi},
            "witness": None if self.witness is None else [int(v) for v in self.witness],
            "notes": list(self.notes),
            "seconds": self.seconds,
        })


#: Seconds per (enumerated map x N²) of one probe, measured at N = 8 and 9.
PROBE_COST = 1.2e-8


def probe_seconds(n: int, n_landmarks: int, trials: int) -> float:
    """Estimated seconds of ``trials`` probes (each enumerates every map)."""
    return trials * map_count(n, n, n_landmarks) * n * n * PROBE_COST


def optimal_matching(D: np.ndarray, Dt: np.ndarray, landmarks=()) -> np.ndarray:
    """Exact ``T_opt = argmin_T Σ (D[x,x'] − D̃[Tx,Tx'])²`` by enumeration.

    Bijections of the N points of ``D`` fixing ``landmarks`` (identity included).
    """
    n = D.shape[0]
    maps = enumerate_maps(n, n, landmarks)
    best, best_t = math.inf, None
    for s in range(0, maps.shape[0], _BLOCK):
        T = maps[s : s + _BLOCK]
        cost = np.sum((D[None] - Dt[T[:, :, None], T[:, None, :]]) ** 2, axis=(1, 2))
        k = int(np.argmin(cost))
        if cost[k] < best:
            best, best_t = float(cost[k]), T[k].copy()
    return best_t


def probe_ratio(D: np.ndarray, Dt: np.ndarray, landmarks=()) -> float | None:
    """One probe ``d(T_opt, Id) / d(X, X̃)``; None when ``D̃ == D``."""
    dist = float(np.sqrt(np.sum((D - Dt) ** 2)))
    if dist == 0.0:
        return None
    t = optimal_matching(D, Dt, landmarks)
    return float(np.sqrt(np.sum(D[np.arange(D.shape[0]), t] ** 2))) / dist


def _relabelled(D, t):
    """``D*`` with ``D*[t x, t x'] = D[x, x']``: the shape relabelled so that ``t`` is an isometry
    X → X̃ (the construction of Theorem 4.1)."""
    inv = np.empty(D.shape[0], dtype=np.int64)
    inv[t] = np.arange(D.shape[0])
    return D[np.ix_(inv, inv)]


def _perturbed(D, kind, witness, free, noise, rng):
    """The perturbed copy D̃ of one probe (``kappa_probes``): the witness construction, a blend
    towards it or towards a random relabelling of the ``free`` samples (λ uniform in (0.55, 1)),
    or symmetric Gaussian noise of standard deviation ``noise``, clipped at 0."""
    n = D.shape[0]
    if kind == "witness":
        return _relabelled(D, witness)
    if kind == "witness-blend":
        lam = rng.uniform(0.55, 1.0)
        return (1.0 - lam) * D + lam * _relabelled(D, witness)
    if kind == "blend":
        t = np.arange(n)
        t[free] = rng.permutation(free)
        lam = rng.uniform(0.55, 1.0)
        return (1.0 - lam) * D + lam * _relabelled(D, t)
    E = rng.standard_normal((n, n))
    E = np.triu(E, 1)
    return np.maximum(D + noise * (E + E.T), 0.0)


def _checked(n, L, trials, scale, seed, time_limit, force):
    """The probe parameters validated (``kappa_probes``'s Raises): (trials, scale, seed, time_limit)."""
    free = n - len(L)
    if free > MAX_PROBE_POINTS:
        raise TooLargeError(
            f"kappa probes enumerate all {map_count(n, n, len(L))} maps per trial; "
            f"limited to {MAX_PROBE_POINTS} free samples, got {free} (use fewer points or more landmarks)"
        )
    trials = check_int(trials, "trials", lo=1)
    scale = check_float(scale, "scale", lo=0.0, lo_open=True, hi=10.0)
    seed = check_seed(seed)
    if time_limit is not None:
        time_limit = check_float(time_limit, "time_limit", lo=0.0, lo_open=True)
    estimate = probe_seconds(n, len(L), trials)
    if time_limit is None or estimate <= time_limit:
        check_cost(f"{trials} kappa probes at N = {n} ({map_count(n, n, len(L))} maps each)", estimate,
                   force=force, hint="use fewer --trials, a --time-limit, or --force")
    return trials, scale, seed, time_limit


def kappa_probes(D, trials: int = 20, seed: int = 0, landmarks=(), scale: float = 0.05,
                 time_limit: float | None = None, force: bool = False, progress=None) -> ProbeResult:
    """Probe κ with ``trials`` perturbed copies of ``D`` (module docstring).

    Parameters
    ----------
    D : (N, N) array_like
        Distance matrix of the samples (bijection score).
    trials : int
        Number of probes; the first is the Theorem 4.1 construction (when σ is
        finite), then noise, blends towards random relabellings, and blends
        towards the witness with λ uniform in (1/2, 1), in turn.
    seed : int
        Seed of ``numpy.random.default_rng``.
    landmarks : sequence of int
        Samples fixed by every map, including ``T_opt``.
    scale : float
        Noise level, relative to the RMS distance.
    time_limit : float or None
        Stop probing after this many seconds (the probes so far are returned,
        with a note).
    force : bool
        Run even when the estimated time is beyond ``shapecond.limits``.
    progress : callable(done, total) or None
        Called after each probe.

    Raises
    ------
    TooLargeError
        Above ``MAX_PROBE_POINTS`` free samples, or when the estimated time of
        the probes exceeds the limit and ``force`` is False.
    """
    t0 = time.perf_counter()
    D, n, L = check_instance(D, None, landmarks)
    trials, scale, seed, time_limit = _checked(n, L, trials, scale, seed, time_limit, force)
    deadline = None if time_limit is None else t0 + time_limit
    notes = []
    rng = np.random.default_rng(seed)
    ex = exact_sigma(D, landmarks=L)
    sigma, w = ex.sigma, ex.witness
    rms = float(np.sqrt(np.mean(D[~np.eye(n, dtype=bool)] ** 2)))
    freeidx = np.setdiff1d(np.arange(n), L)
    ratios, kinds = [], []
    k = 0
    while len(ratios) < trials and k < 4 * trials + 8:
        kind = ("witness" if k == 0 else ("noise", "blend", "witness-blend")[(k - 1) % 3])
        k += 1
        if kind.startswith("witness") and (w is None or math.isinf(sigma)):
            continue
        r = probe_ratio(D, _perturbed(D, kind, w, freeidx, scale * rms, rng), L)
        if r is None:
            continue
        ratios.append(r)
        kinds.append(kind)
        if progress is not None:
            progress(len(ratios), trials)
        if deadline is not None and time.perf_counter() > deadline and len(ratios) < trials:
            notes.append(f"time limit of {time_limit:g} s reached after {len(ratios)} of {trials} probes")
            break
    return ProbeResult(tuple(ratios), tuple(kinds), sigma, w, time.perf_counter() - t0, tuple(notes))


__all__ = ["kappa_bracket", "kappa_probes", "ProbeResult", "probe_ratio", "optimal_matching", "MAX_PROBE_POINTS"]

"""Exact global symmetry score σ(X) (paper Eq. 5, L² case).

σ(X) = sup_{T ≠ Id} sqrt(d²(T) / Dist²(T)) over injective maps ``T`` of the
``N`` samples into the ``M`` points of ``D`` (``M == N``: the paper's
bijections; ``M > N``: the dense-target score) that fix every
landmark (T(l) = l).  ``σ = inf`` when a non-identity map is an isometry up to
round-off (``objective.is_isometry``); the witness is then that map.

Two exact methods:

- **enumeration** of every map, vectorised in blocks, when there are at most
  ``ENUMERATION_LIMIT`` (= 9!) maps: N <= 9 bijections, or e.g. N <= 6 samples
  into M <= 10 targets; landmarks shrink the count.
- **branch and bound** (``_bnb``) otherwise: a depth-first tree with a moving
  Dinkelbach parameter and a Gilmore–Lawler + linear-assignment node bound
  whose validity is argued in ``shapecond.symmetry._bnb``.  It is warm-started
  from a swap local search and stops at ``time_limit``, reporting
  ``finished=False`` and ``sigma=None`` rather than a possibly wrong value.

Maps ``t`` with ``d²(T) = 0`` other than the identity (duplicate points) score 0,
as in ``objective.map_score``.  When no non-identity map exists (fewer than two
free samples and ``M == N``), σ = 0 with no witness.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import TooLargeError
from ..limits import human_bytes
from ..threads import one_blas_thread
from . import objective
from ._result import FieldsToDict
from ._bnb import branch_and_bound, ratio_of, swap_search
from .objective import check_instance
from .search import witness_search

#: Largest number of maps enumerated (9! = 362 880, about 0.5 s).
ENUMERATION_LIMIT = 362_880
_BLOCK = 16_384


@dataclass(frozen=True)
class ExactResult(FieldsToDict):
    """Outcome of ``exact_sigma``.

    Attributes
    ----------
    sigma : float or None
        σ(X) (``math.inf`` for an isometry); ``None`` when not finished in time.
    witness : (N,) int ndarray or None
        A map attaining σ (when finished) or the best map found so far.
    finished : bool
    seconds : float
    method : str
        ``"enumeration"`` or ``"branch-and-bound"``.
    lower : float
        σ of ``witness`` (a certified lower bound even when not finished).
    nodes : int
        Maps enumerated or tree nodes visited.
    """

    sigma: float | None
    witness: np.ndarray | None
    finished: bool
    seconds: float
    method: str
    lower: float = 0.0
    nodes: int = 0


def map_count(n: int, m: int, n_landmarks: int) -> int:
    """Number of injective maps of the free samples into the free targets."""
    return math.perm(m - n_landmarks, n - n_landmarks)


def enumerate_maps(n: int, m: int, landmarks=()) -> np.ndarray:
    """All injective maps fixing ``landmarks``, as a (count, n) int array.

    Built column by column with numpy (no Python loop over maps).
    """
    L = np.asarray(list(landmarks), dtype=np.int64)
    free = np.setdiff1d(np.arange(n), L)
    targets = np.setdiff1d(np.arange(m), L)
    r = targets.size
    idx = np.zeros((1, 0), dtype=np.int16)
    used = np.zeros((1, r), dtype=bool)
    for _ in range(free.size):
        rows, cols = np.nonzero(~used)
        idx = np.concatenate([idx[rows], cols[:, None].astype(np.int16)], axis=1)
        used = used[rows]
        used[np.arange(rows.size), cols] = True
    maps = np.empty((idx.shape[0], n), dtype=np.int64)
    maps[:, L] = L
    maps[:, free] = targets[idx]
    return maps


def _enumerate(D, n, L):
    """Best ratio² and map by exhaustive search (blocks of ``_BLOCK`` maps)."""
    maps = enumerate_maps(n, D.shape[0], L)
    ident = np.all(maps == np.arange(n), axis=1)
    maps = maps[~ident]
    Dx = D[:n, :n]
    floor = objective.isometry_floor(D, n)
    best_r, best_t = 0.0, None
    for s in range(0, maps.shape[0], _BLOCK):
        T = maps[s : s + _BLOCK]
        num = np.sum(D[np.arange(n), T] ** 2, axis=1)
        den = np.sum((Dx[None] - D[T[:, :, None], T[:, None, :]]) ** 2, axis=(1, 2))
        iso = (den <= floor) & (num > 0)
        if np.any(iso):
            return math.inf, T[int(np.argmax(iso))].copy(), maps.shape[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(num > 0, num / np.where(den > 0, den, 1.0), 0.0)
        k = int(np.argmax(r))
        if r[k] > best_r:
            best_r, best_t = float(r[k]), T[k].copy()
    return best_r, best_t, maps.shape[0]


#: Branch and bound needing more memory than this is refused unless forced: it only
#: finishes for N up to about 20, where it needs a few MB.
BNB_MAX_BYTES = 2**30


def bnb_bytes(n: int, m: int, n_landmarks: int) -> float:
    """Memory of the branch and bound's per-depth cross terms C1: 8 (free + 1) N M bytes."""
    return 8.0 * (n - n_landmarks + 1) * n * m


def _warm_start(D, n, L, warm=None):
    """A good map to start the tree search from: ``warm``'s witness when given (the caller's
    search already ran, so nothing is recomputed before the time limit starts to count), else
    the best of our swap ascent and a quick ``search.witness_search``.

    Only speeds the tree search up: its result never depends on the warm start.
    """
    def admissible(w):  # an injective map of the N samples fixing every landmark
        return w.shape == (n,) and np.unique(w).size == n and all(w[l] == l for l in L)

    if warm is not None:
        w = np.asarray(warm.witness, dtype=np.int64)
        if admissible(w):
            return ratio_of(D, w), w
    best = swap_search(D, n, L, np.random.default_rng(0))
    w = np.asarray(witness_search(D, n_samples=n, landmarks=L, seed=0, effort="quick").witness, dtype=np.int64)
    if admissible(w):
        r = ratio_of(D, w)
        if r > best[0]:
            best = (r, w)
    return best


def exact_sigma(D, n_samples=None, landmarks=(), time_limit=None, warm=None, force: bool = False) -> ExactResult:
    """Exact σ(X) of Eq. 5 by enumeration or branch and bound.

    Parameters
    ----------
    D : (M, M) array_like
        Symmetric distance matrix, zero diagonal; the first ``n_samples`` points
        are the samples X.
    n_samples : int, optional
        N (default M: bijections of all points).
    landmarks : sequence of int
        Sample indices fixed by every map.
    time_limit : float, optional
        Seconds for branch and bound (enumeration is not interrupted; it is
        only chosen below ``ENUMERATION_LIMIT`` maps).
    warm : object with ``witness`` (a map), optional
        A known good map (e.g. from ``search.witness_search``) to start the tree
        search from; without it a quick witness search is run first.
    force : bool
        Run branch and bound even when its memory (``bnb_bytes``) exceeds
        ``BNB_MAX_BYTES``, or without a time limit beyond 16 free samples.

    Returns
    -------
    ExactResult

    Raises
    ------
    TooLargeError
        When branch and bound is needed and its memory is beyond the limit, or
        when it has no time limit beyond 16 free samples (it could run for hours),
        unless ``force``.
    """
    t0 = time.perf_counter()
    D, n, L = check_instance(D, n_samples, landmarks)
    L = [int(v) for v in L]
    M = D.shape[0]
    count = map_count(n, M, len(L))
    if count <= 1:
        return ExactResult(0.0, None, True, time.perf_counter() - t0, "enumeration", 0.0, 0)
    if count <= ENUMERATION_LIMIT:
        r, t, nodes = _enumerate(D, n, L)
        method = "enumeration"
        finished = True
    else:
        need = bnb_bytes(n, M, len(L))
        if not force and need > BNB_MAX_BYTES:
            raise TooLargeError(f"branch and bound at N = {n}, M = {M} needs {human_bytes(need)} "
                                f"(limit {human_bytes(BNB_MAX_BYTES)}) and cannot finish at this size; "
                                "use --force")
        if not force and time_limit is None and n - len(L) > 16:
            raise TooLargeError(f"branch and bound for {n - len(L)} free samples has no time bound; give a time limit "
                                "or use --force")
        deadline = None if time_limit is None else t0 + float(time_limit)
        with one_blas_thread():
            r0, w0 = _warm_start(D, n, L, warm)
            r, t, finished, nodes = branch_and_bound(D, n, L, r0, w0, deadline)
        method = "branch-and-bound"
    lower = math.sqrt(r) if t is not None else 0.0
    sigma = lower if finished else None
    return ExactResult(sigma, t, finished, time.perf_counter() - t0, method, lower, nodes)


__all__ = ["ExactResult", "exact_sigma", "check_instance", "enumerate_maps", "map_count", "ratio_of"]

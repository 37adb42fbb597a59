"""Exact global symmetry score σ(X) (paper Eq. 5, L² case; DESIGN.md section 3).

σ(X) = sup_{T ≠ Id} sqrt(d²(T) / Dist²(T)) over injective maps ``T`` of the
``N`` samples into the ``M`` points of ``D`` (``M == N``: the paper's
bijections; ``M > N``: the dense-target score of issue 4) that fix every
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
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import InputError
from . import objective
from ._bnb import branch_and_bound, ratio_of, swap_search

#: Largest number of maps enumerated (9! = 362 880, about 0.5 s).
ENUMERATION_LIMIT = 362_880
_BLOCK = 16_384


@dataclass(frozen=True)
class ExactResult:
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

    def to_dict(self) -> dict:
        """The fields as a dict (numpy arrays included; ``cli.common.jsonable`` converts them)."""
        return asdict(self)


def check_instance(D, n_samples=None, landmarks=()):
    """Validate a score instance; return ``(D, N, landmarks)`` as arrays/ints.

    Raises ``InputError`` (one line) for a non-square, non-finite, negative or
    asymmetric ``D`` (relative tolerance 1e-9), a nonzero diagonal, ``N`` out
    of ``[2, M]``, or landmarks out of ``range(N)`` or repeated.
    """
    D = np.asarray(D, dtype=np.float64)
    if D.ndim != 2 or D.shape[0] != D.shape[1]:
        raise InputError(f"distance matrix must be square, got shape {D.shape}")
    if not np.all(np.isfinite(D)):
        raise InputError("distance matrix contains NaN or infinite entries")
    if np.any(D < 0):
        raise InputError("distance matrix has negative entries")
    M = D.shape[0]
    scale = float(np.max(D)) if D.size else 0.0
    if not np.allclose(D, D.T, rtol=0.0, atol=1e-9 * max(scale, 1e-300)):
        raise InputError("distance matrix is not symmetric")
    if np.any(np.diag(D) != 0):
        raise InputError("distance matrix has a nonzero diagonal")
    n = M if n_samples is None else int(n_samples)
    if n < 2 or n > M:
        raise InputError(f"number of samples must be in [2, {M}], got {n}")
    L = [int(l) for l in landmarks]
    if len(set(L)) != len(L):
        raise InputError("landmarks are repeated")
    bad = [l for l in L if l < 0 or l >= n]
    if bad:
        raise InputError(f"landmark {bad[0]} is not a sample index in [0, {n})")
    return 0.5 * (D + D.T), n, L


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
    scale2 = float(np.sum(Dx**2))
    best_r, best_t = 0.0, None
    for s in range(0, maps.shape[0], _BLOCK):
        T = maps[s : s + _BLOCK]
        num = np.sum(D[np.arange(n), T] ** 2, axis=1)
        den = np.sum((Dx[None] - D[T[:, :, None], T[:, None, :]]) ** 2, axis=(1, 2))
        iso = (den <= (objective.ISOMETRY_RTOL**2) * scale2) & (num > 0)
        if np.any(iso):
            return math.inf, T[int(np.argmax(iso))].copy(), maps.shape[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(num > 0, num / np.where(den > 0, den, 1.0), 0.0)
        k = int(np.argmax(r))
        if r[k] > best_r:
            best_r, best_t = float(r[k]), T[k].copy()
    return best_r, best_t, maps.shape[0]


def _warm_start(D, n, L):
    """Best of our swap ascent and the witness search (``search.witness_search``).

    Only speeds the tree search up: its result never depends on the warm start.
    """
    best = swap_search(D, n, L, np.random.default_rng(0))
    try:
        from .search import witness_search
    except ImportError:  # pragma: no cover - the search module is optional here
        return best
    res = witness_search(D, n_samples=n, landmarks=L, seed=0, effort="quick")
    w = np.asarray(res.witness, dtype=np.int64)
    valid = w.shape == (n,) and np.unique(w).size == n and all(w[l] == l for l in L)
    if valid:
        r = ratio_of(D, w)
        if r > best[0]:
            best = (r, w)
    return best


def _single_thread_blas():
    """Small products only lose time to BLAS threads on a shared machine."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover
        import contextlib

        return contextlib.nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


def exact_sigma(D, n_samples=None, landmarks=(), time_limit=None) -> ExactResult:
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

    Returns
    -------
    ExactResult
    """
    t0 = time.perf_counter()
    D, n, L = check_instance(D, n_samples, landmarks)
    M = D.shape[0]
    count = map_count(n, M, len(L))
    if count <= 1:
        return ExactResult(0.0, None, True, time.perf_counter() - t0, "enumeration", 0.0, 0)
    if count <= ENUMERATION_LIMIT:
        r, t, nodes = _enumerate(D, n, L)
        method = "enumeration"
        finished = True
    else:
        deadline = None if time_limit is None else t0 + float(time_limit)
        with _single_thread_blas():
            r0, w0 = _warm_start(D, n, L)
            r, t, finished, nodes = branch_and_bound(D, n, L, r0, w0, deadline)
        method = "branch-and-bound"
    lower = math.sqrt(r) if t is not None else 0.0
    sigma = lower if finished else None
    return ExactResult(sigma, t, finished, time.perf_counter() - t0, method, lower, nodes)


__all__ = ["ExactResult", "exact_sigma", "check_instance", "enumerate_maps", "map_count", "ratio_of"]

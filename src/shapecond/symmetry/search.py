"""Lower bound of the global symmetry score with a witness map.

σ(X) = sup_{T ≠ Id} sqrt(d²(T) / Dist²(T)) (paper Eq. 5, L² case), the sup over
maps fixing every landmark.  Any map T ≠ Id gives σ(X) ≥ σ_T, so the best map
found by a search is a certified lower bound and the map itself is the
*witness*: the near-isometry that makes the shape hard to match.

The search is a multistart local search on the ratio itself (not only on a
fixed-s objective): moves swap the images of two samples or, with dense
targets (M > N), send one sample to a free target among the k nearest of its
current image; every move is evaluated in O(1) from the maintained products
G and H of ``objective`` and applied by a rank-1 update
(``shapecond.symmetry._kernels``, numba).  Starts, in order: the best single
swap (exact, :func:`best_single_swap`), warm starts, reflections of the MDS
embedding onto Y (``starts.reflection_starts``), spectral sign-flip maps,
Gilmore-Lawler assignment maps over a grid of s, a fixed-s ladder on
d² − s·Dist², random starts, then iterated local search (random kicks of the
best maps).  With dense targets all of this runs on the bijections of X first
(G is N × N, cheap) and the best few maps are then refined over Y.

The starts of a phase are independent: they are polished by parallel threads
(``shapecond.threads``, one per thread at a time) and their results taken in order,
which gives the pool of polishing them one after the other, with any number of
threads (the ladder and the kicks, each built from the results before it, stay
serial).

Perfect symmetry: a map whose exact Dist² is round-off
(``objective.is_isometry``) gives σ = ``math.inf`` and stops the search.  The
identity (d² = 0) is never a witness.  Given a seed the result is
deterministic unless ``time_limit`` cuts the search short.
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass

import numpy as np

from shapecond.jsonable import jsonable
from shapecond.errors import InputError
from shapecond.symmetry import _kernels as K
from shapecond.symmetry import objective as obj
from shapecond.symmetry import starts as S

from shapecond.threads import one_blas_thread
from shapecond.threads import n_threads, thread_map

#: Work per effort level: MDS coordinates / reflection starts kept, spectral vectors / sign pairs / starts polished,
#: Gilmore-Lawler grid size / starts polished, ladder runs, random starts,
#: ILS kicks, maps refined over dense targets, dense kicks.  ``small``: on
#: small instances, where a local search costs microseconds, the random starts
#: and the kicks are each raised to ``small / n_free²``.  ``warm``: a search continued from the
#: maps of a previous one (``starts``) on an instance that differs by one fixed sample, as the
#: next-landmark suggestion runs it: the single swap, the warm starts and the kicks only, none
#: of the structured starts (spectral, Gilmore-Lawler, ladder, random) that a fresh instance needs.
EFFORTS = {
    "quick": dict(reflect=(6, 2), vectors=6, pairs=3, spectral=4, gl=6, gl_polish=3, ladder=1,
                  random=2, kicks=10, dense=2, dense_kicks=2, small=5e3),
    "default": dict(reflect=(8, 2), vectors=10, pairs=5, spectral=5, gl=8, gl_polish=3, ladder=1,
                    random=2, kicks=24, dense=3, dense_kicks=4, small=1e4),
    "thorough": dict(reflect=(10, 4), vectors=16, pairs=8, spectral=24, gl=16, gl_polish=10, ladder=4,
                     random=24, kicks=200, dense=6, dense_kicks=30, small=2e5),
    "warm": dict(reflect=(6, 2), kicks=10, dense=2, dense_kicks=2, small=5e3, fresh=False),
}

#: Reassignment moves consider the ``DENSE_K`` nearest targets of the current image.
DENSE_K = 16
#: How many distinct local optima a result keeps (warm starts for CNBS).
KEEP = 5
#: With a budget and landmarks, a start whose distances from some landmark are off by more than
#: sqrt(HOPELESS_START) = 10 times the RMS budget (an anchor row above HOPELESS_START · budget / N)
#: is not polished.  On TOSCA cat0 (N = 400, 1-5 landmarks) every such start (the ladder's rungs,
#: the second reflection, a Gilmore-Lawler start: rows 110-190x) ended infeasible after up to 1,000
#: moves, half the time of a search; starts at 4-13x ended feasible, the best map among them.  Checked
#: on a shape it was not chosen on (SMAL_r hippo5, CNBS-scale -k 6): the same landmarks and δ.  While the
#: pool is empty the least far start is kept (a search on a shape matched to itself had none left).
HOPELESS_START = 100.0


@dataclass(frozen=True)
class SearchResult:
    """Best map found by :func:`witness_search` (a lower bound of σ, Eq. 5).

    ``sigma`` is ``math.inf`` when ``witness`` is a non-identity isometry.
    ``maps``/``sigmas``: up to ``KEEP`` distinct local optima, best first.
    """

    sigma: float
    witness: np.ndarray
    d2: float
    dist2: float
    maps: tuple
    sigmas: tuple
    seconds: float

    def to_dict(self) -> dict:
        return jsonable({"sigma": self.sigma, "witness": self.witness.tolist(), "d2": self.d2,
                "dist2": self.dist2, "sigmas": list(self.sigmas), "seconds": self.seconds})


def prepare_instance(D, n_samples=None, landmarks=()):
    """Validate a search instance (``objective.check_instance``): (contiguous D, N, sorted landmarks,
    free samples).  ``InputError`` unless a map other than the identity fixes every landmark (two free
    samples, or one with dense targets)."""
    D, n, lm = obj.check_instance(D, n_samples, landmarks)
    m = D.shape[0]
    D = np.ascontiguousarray(D)
    free = np.setdiff1d(np.arange(n, dtype=np.int64), lm)
    if free.size < 2 and not (free.size == 1 and m > n):
        raise InputError("at least two samples must be free of landmarks: "
                         "otherwise every admissible map is the identity")
    return D, n, lm, free


def best_single_swap(D, n_samples=None, landmarks=()) -> tuple[float, int, int]:
    """Exact best map that exchanges two free samples: (σ, a, b).

    For the swap (a b), d² = 2 D[a,b]² and Dist² = 4 Σ_{x ≠ a,b} (D[x,a] − D[x,b])²,
    all pairs at once (``objective.swap_terms``: one O(N³) product, then O(N²)).  Every
    metric space has σ ≥ 1/sqrt(2(N − 2)) from these maps; a swap that is an isometry gives ``inf``.
    """
    D, n, lm, free = prepare_instance(D, n_samples, landmarks)
    if free.size < 2:
        return 0.0, -1, -1
    num, den = obj.swap_terms(D[:n, :n], free)
    iso = (den <= obj.isometry_floor(D, n)) & (num > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(num > 0, num / np.where(den > 0, den, 1.0), -1.0)
    r[iso] = np.inf
    np.fill_diagonal(r, -1.0)
    i, j = np.unravel_index(int(np.argmax(r)), r.shape)
    best = r[i, j]
    return (math.inf if best == np.inf else math.sqrt(max(best, 0.0))), int(free[i]), int(free[j])


def best_reassignment(D, n, free) -> np.ndarray:
    """The identity with one free sample sent to a target outside X: the best such map by σ.

    Σ_x (D[x,a] − D[x,y])² for all pairs (a, y) from one product; a thin tip's
    sample sent to a target just beside it is often the dense witness of a
    shape without symmetry.
    """
    ys = np.arange(n, D.shape[0])
    t = np.arange(n, dtype=np.int64)
    if free.size == 0 or ys.size == 0:
        return t
    X, Y = D[:n, free], D[:n, ys]
    sq = np.sum(X**2, axis=0)[:, None] + np.sum(Y**2, axis=0)[None, :] - 2.0 * X.T @ Y
    num = D[np.ix_(free, ys)] ** 2
    den = 2.0 * np.maximum(sq - num, 1e-300)  # the x = a term is D[a,y]²
    i, j = np.unravel_index(int(np.argmax(num / den)), num.shape)
    t[free[i]] = ys[j]
    return t


def widest_swap(D, n, free, budget) -> tuple[int, int]:
    """The swap of two free samples with the largest d² among those with Dist² ≤ ``budget``
    (``(-1, -1)`` if none)."""
    num, den = obj.swap_terms(np.asarray(D)[:n, :n], free)
    num = np.where(den <= budget, num, -1.0)
    np.fill_diagonal(num, -1.0)
    i, j = np.unravel_index(int(np.argmax(num)), num.shape)
    return (int(free[i]), int(free[j])) if num[i, j] > 0 else (-1, -1)


#: ``nearest_targets`` of read-only matrices: (id(D), k) -> (weak reference to D, lists).
_KNN: dict = {}


def nearest_targets(D: np.ndarray, k: int) -> np.ndarray:
    """(M, k) int64: the ``k`` nearest other targets of each target (unordered), from one
    ``argpartition`` of every row of ``D`` (0.1-0.2 s at M = 3,200).

    Kept for a read-only ``D`` (``checks.check_distance_matrix`` returns one) while it lives: every
    witness search and CNBS heat map on a shape builds a ``SearchStage`` with the same lists.
    """
    key = (id(D), int(k))
    hit = _KNN.get(key)
    if hit is not None and hit[0]() is D:
        return hit[1]
    knn = np.ascontiguousarray(np.argpartition(D, k, axis=1)[:, : k + 1])
    # drop each target itself from its own list (distance 0)
    knn = np.ascontiguousarray(np.array([r[r != i][:k] for i, r in enumerate(knn)], dtype=np.int64))
    if not D.flags.writeable:  # shared by every search on D: read-only, as D is
        knn.flags.writeable = False
        _KNN[key] = (weakref.ref(D, lambda _, key=key: _KNN.pop(key, None)), knn)
    return knn


class SearchStage:
    """One search space: maps of the n samples into the M points of ``D``.

    Public so that warm-started searches (``selection.warm``, CNBS) can run the
    compiled local search from their own starts with the same neighbour lists.
    """

    def __init__(self, D, n, free, dense_k):
        self.D, self.n, self.free = D, n, free
        m = D.shape[0]
        k = min(dense_k, m - 1) if m > n else 0
        self.knn = nearest_targets(D, k) if k else np.zeros((m, 0), dtype=np.int64)
        self.floor = obj.isometry_floor(D, n)

    def space(self, free=None) -> K.Space:
        """The compiled search's ``Space`` with the stage's free samples (or ``free``)."""
        return K.Space(self.D, self.n, self.free if free is None else free, self.knn, self.floor)

    def goal(self, mode=K.MODE_RATIO, s=0.0, anchors=(), max_moves=None, stop=math.inf) -> K.Goal:
        """The compiled search's ``Goal``: ``mode`` with parameter ``s``, at most ``max_moves``
        moves (default 50 N), stopping above ``stop``; ``anchors``: in ``MODE_BUDGET``, landmark
        rows each kept within s / n."""
        cap = 50 * self.n if max_moves is None else max_moves
        return K.Goal(mode, float(s), cap, float(stop), np.asarray(anchors, dtype=np.int64), float(s) / self.n)

    def start(self, t, anchors=()) -> K.MapState:
        """The compiled search's ``MapState`` of map ``t`` (used as is, updated by the search):
        its products G and H (``objective``), its image, its anchor rows, d² and Dist²."""
        D = self.D
        used = np.zeros(D.shape[0], dtype=bool)
        used[t] = True
        return K.MapState(t, obj.cross_product(D, t), obj.image_energy(D, t), used, obj.anchor_rows(D, t, anchors),
                          obj.d2(D, t), obj.dist2(D, t))

    def polish(self, t, mode=K.MODE_RATIO, s=0.0, max_moves=None, anchors=()):
        """Local search from map t; returns the new map (t is not modified).

        ``anchors``: in ``MODE_BUDGET``, landmark rows each kept within s / n.
        """
        t = np.array(t, dtype=np.int64)
        goal = self.goal(mode, s, anchors, max_moves)
        K.local_search(self.space(), goal, self.start(t, goal.anchors))
        return t

    def polished(self, ts, mode=K.MODE_RATIO, s=0.0, anchors=()):
        """Yield ``(t, polish(t))`` for each start of ``ts`` in order, polished ``n_threads()`` at a
        time by parallel threads (``shapecond.threads``).  A chunk is computed when its first item is
        asked for, so a caller that stops early (a time limit, σ = ∞) has polished at most one chunk
        more than a serial loop, and takes the same results in the same order."""
        ts, k = [np.asarray(t, dtype=np.int64) for t in ts], n_threads()
        for i in range(0, len(ts), k):
            chunk = ts[i:i + k]
            yield from zip(chunk, thread_map(lambda t: self.polish(t, mode, s, anchors=anchors), chunk))


class MapPool:
    """Distinct maps with their exact scores, best first.

    The score is σ² (``inf`` for an isometry) or, with a ``budget``, d² for maps
    with Dist² ≤ budget whose ``anchors`` rows (``objective.anchor_rows``) are each
    within budget / n, and minus the total excess for the others.
    """

    def __init__(self, D, n, budget=None, anchors=()):
        self.D, self.n, self.items, self.budget = D, n, {}, budget
        self.anchors = np.asarray(anchors, dtype=np.int64)

    def value(self, t) -> tuple[float, float, float]:
        num = obj.d2(self.D, t)
        den = obj.dist2(self.D, t)
        if self.budget is not None:
            rows = obj.anchor_rows(self.D, t, self.anchors)
            exc = max(den - self.budget, 0.0) + float(np.sum(np.maximum(rows - self.budget / self.n, 0.0)))
            return (num if exc == 0.0 else -exc), num, den
        if num == 0.0:
            return 0.0, num, den
        if obj.is_isometry(self.D, den, self.n):
            return math.inf, num, den
        return num / den, num, den

    def add(self, t) -> float:
        key = np.asarray(t, dtype=np.int64).tobytes()
        if key not in self.items:
            v, num, den = self.value(t)
            self.items[key] = (v, np.array(t, dtype=np.int64), num, den)
        return self.items[key][0]

    def top(self, k):
        return sorted(self.items.values(), key=lambda it: -it[0])[:k]

    def best_value(self) -> float:
        return max((it[0] for it in self.items.values()), default=0.0)

    def result(self, seconds: float) -> SearchResult:
        """The ``KEEP`` best moving maps as a ``SearchResult`` (σ, or sqrt(d²) with a budget);
        with a budget and no moving map within it, the identity (δ = 0)."""
        tops = [it for it in self.top(KEEP) if it[0] > 0.0]
        if not tops and self.budget is not None:
            ident = np.arange(self.n, dtype=np.int64)
            return SearchResult(sigma=0.0, witness=ident, d2=0.0, dist2=0.0, maps=(ident,), sigmas=(0.0,),
                                seconds=seconds)
        if not tops:  # cannot happen with >= 2 free samples; kept as a guard
            raise InputError("no non-identity map satisfies the landmarks")
        _, t, num, den = tops[0]
        sig = [math.inf if it[0] == math.inf else math.sqrt(it[0]) for it in tops]
        return SearchResult(sigma=sig[0], witness=t, d2=num, dist2=den, maps=tuple(it[1] for it in tops),
                            sigmas=tuple(sig), seconds=seconds)


def kick_limit(n_free: int) -> int:
    """Largest kick of the iterated local searches: N/8 swaps, between 3 and 12 (a kick is 2 to
    this many; larger ones cost many moves to polish and rarely end higher)."""
    return max(3, min(12, n_free // 8))


def kick(rng, t, free, size):
    """Rotate the images of ``size`` random free samples (an ILS perturbation)."""
    t = t.copy()
    idx = rng.choice(free, size=min(size, free.size), replace=False)
    t[idx] = t[np.roll(idx, 1)]
    return t


def _dense_kick(rng, t, free, knn, m, size):
    """Kick over dense targets: a rotation plus moves to random free nearby targets."""
    t = kick(rng, t, free, size)
    used = np.zeros(m, dtype=bool)
    used[t] = True
    for a in rng.choice(free, size=min(size, free.size), replace=False):
        cand = [y for y in knn[t[a]] if not used[y]]
        if cand:
            y = cand[int(rng.integers(len(cand)))]
            used[t[a]], used[y] = False, True
            t[a] = y
    return t


def witness_search(D, n_samples=None, landmarks=(), seed=0, starts=(), effort="default",
                   time_limit=None, budget=None) -> SearchResult:
    """Lower bound of σ (Eq. 5) with the map attaining it; see the module docstring.

    With ``budget`` the same search maximises d²(T) over the maps with
    Dist²(T) ≤ ``budget`` whose landmark rows ``objective.anchor_rows`` are each at
    most ``budget / N`` instead (the scale-aware score, ``shapecond.symmetry.scale``);
    ``sigma`` is then sqrt(d²) of the witness.

    Parameters
    ----------
    D : (M, M) distance matrix; the samples X are the first ``n_samples`` points
        (default M: bijections of X, the paper's score; M > N: dense targets).
    landmarks : sample indices with T(l) = l.
    seed : seed of ``np.random.default_rng``; the result is deterministic.
    starts : extra initial maps (warm starts), repaired to fix landmarks and be
        injective.
    effort : "quick", "default", "thorough", or "warm" to continue from ``starts`` (see ``EFFORTS``).
    time_limit : seconds; the search stops between local searches when reached.
    """
    with one_blas_thread():  # the small products here only lose time to BLAS threads
        return _witness_search(D, n_samples, landmarks, seed, starts, effort, time_limit, budget)


def _witness_search(D, n_samples, landmarks, seed, starts, effort, time_limit, budget) -> SearchResult:
    t_start = time.perf_counter()
    if effort not in EFFORTS:
        raise InputError(f"effort must be one of {sorted(EFFORTS)}, got {effort!r}")
    instance = prepare_instance(D, n_samples, landmarks)
    D, n, lm, free = instance
    deadline = math.inf if time_limit is None else t_start + float(time_limit)
    run = _SearchRun(instance, EFFORTS[effort], budget, np.random.default_rng(seed), deadline)
    warm = [S.repair(t, n, D.shape[0], lm) for t in starts]
    s_swap = run.single_swap()
    run.run_all(run.bij, [t for t in warm if t.max() < n])
    # past late() no start is added to the pool any more: the stages are not even built
    if free.size >= 3 and not run.late() and run.cfg.get("fresh", True):
        run.spectral()
        s_ref = 1.0 / max(s_swap, 1e-6) ** 2 if math.isfinite(s_swap) else 1.0
        for stage in (lambda: run.ladder(run.gilmore_lawler(s_ref), s_ref), run.random_starts):
            if not run.late():
                stage()
    if free.size >= 3 and not run.late():
        run.kicks()
    if run.dense is not None and not run.late():
        run.dense_refine([t for t in warm if t.max() >= n])
    return run.pool.result(time.perf_counter() - t_start)


class _SearchRun:
    """One run of ``witness_search``: the pool of maps found, the search stages over X (``bij``)
    and, with dense targets, over Y (``dense``), the random generator and the clock.  Each
    method is one family of starts of the module docstring, in the order they run; every start
    is polished and its local optimum added to the pool until ``late()``.  ``instance`` is
    ``prepare_instance``'s (D, n, landmarks, free samples)."""

    def __init__(self, instance, cfg, budget, rng, deadline):
        D, n, lm, free = instance
        self.D, self.n, self.lm, self.free, self.cfg, self.budget = D, n, lm, free, cfg, budget
        self.rng, self.deadline = rng, deadline
        self.pool = MapPool(D, n, budget, lm)
        self.mode, self.s = (K.MODE_RATIO, 0.0) if budget is None else (K.MODE_BUDGET, float(budget))
        self.bij = SearchStage(np.ascontiguousarray(D[:n, :n]), n, free, 0)
        self.dense = SearchStage(D, n, free, DENSE_K) if D.shape[0] > n else None

    @property
    def extra(self) -> int:
        """Random starts and kicks at least: on small instances, where a local search costs
        microseconds, ``EFFORTS[...]["small"] / n_free²``."""
        return int(self.cfg["small"] / self.free.size**2)

    @property
    def time_bound(self) -> float | None:
        """The deadline as a ``time.perf_counter()`` time, None without a time limit."""
        return None if self.deadline == math.inf else self.deadline

    def late(self) -> bool:
        """Past the time limit, or an isometry found (σ = ∞: nothing can beat it)."""
        return time.perf_counter() > self.deadline or self.pool.best_value() == math.inf

    def run_all(self, stage, ts):
        """Polish every start of ``ts`` (``SearchStage.polished``), adding the results in order
        until ``late()``: the same pool as polishing them one after the other.  With a budget,
        starts far off a landmark row's budget are dropped (``HOPELESS_START``), except the least far
        one while the pool holds no map (the kicks and the result need one)."""
        if self.budget is not None and self.lm.size and len(ts):
            far = [float(np.max(obj.anchor_rows(self.D, t, self.lm))) for t in ts]
            cap = HOPELESS_START * self.budget / self.n
            kept = [t for t, f in zip(ts, far) if f <= cap]
            ts = kept if kept or self.pool.items else [ts[int(np.argmin(far))]]
        done = stage.polished(ts, self.mode, self.s, self.lm)
        while not self.late():
            item = next(done, None)
            if item is None:
                return
            self.pool.add(item[1])

    def single_swap(self) -> float:
        """1. The best single swap (exact; with a budget the widest within it), kept and polished.
        Returns σ of the best single swap (0 without two free samples)."""
        D, n, free = self.D, self.n, self.free
        if free.size < 2:
            return 0.0
        s_swap, a, b = best_single_swap(D, n, self.lm)
        if self.budget is not None:  # the widest swap within the budget instead
            a, b = widest_swap(D, n, free, self.budget)
        if a >= 0:
            self.pool.add(S.swap_map(n, a, b))
            self.run_all(self.bij, [S.swap_map(n, a, b)])
        return s_swap

    def spectral(self):
        """2. Spectral sign-flip starts, the most promising ones polished; without dense targets
        the reflections of the MDS embedding too (with them they are built over Y, step 7)."""
        cfg, bij = self.cfg, self.bij
        cand = S.spectral_starts(bij.D, self.free, cfg["vectors"], cfg["pairs"], deadline=self.time_bound)
        cand.sort(key=lambda t: -self.pool.value(t)[0])
        self.run_all(bij, cand[: cfg["spectral"]])
        if self.dense is None:
            self.run_all(bij, S.reflection_starts(bij.D, self.n, self.free, self.lm, *cfg["reflect"]))

    def gilmore_lawler(self, s_ref) -> list:
        """3. Gilmore-Lawler assignment starts over a grid of s around ``s_ref``; the best few
        polished.  Returns all of them, best first."""
        grid = [s_ref * 4.0 ** (1 - j) for j in range(self.cfg["gl"])]
        cand = S.gilmore_lawler_starts(self.bij.D, self.free, self.lm, grid, deadline=self.time_bound)
        gl_best = sorted(cand, key=lambda t: -self.pool.value(t)[0])
        self.run_all(self.bij, gl_best[: self.cfg["gl_polish"]])
        return gl_best

    def ladder(self, gl_best, s_ref):
        """4. Fixed-s ladder: maximise d² − s·Dist² for increasing s from the best Gilmore-Lawler
        starts (random ones beyond them), each rung's map polished on the ratio."""
        bij, n = self.bij, self.n
        for r in range(self.cfg["ladder"]):
            t = gl_best[r] if r < len(gl_best) else S.random_start(self.rng, n, self.free)
            for j in range(6, -1, -1):
                if self.late():
                    break
                t = bij.polish(t, mode=K.MODE_FIXED_S, s=s_ref * 4.0**-j)
                if np.any(t != np.arange(n)):
                    self.run_all(bij, [t])

    def random_starts(self):
        """5. Random bijections of the free samples."""
        # random starts end far below the structured ones on large shapes (TOSCA, N = 400:
        # σ 0.26 against 0.54) while costing the most moves: fewer of them there
        cfg, free = self.cfg, self.free
        n_random = cfg["random"] if free.size <= 200 else cfg["random"] // 2
        self.run_all(self.bij, [S.random_start(self.rng, self.n, free) for _ in range(max(n_random, self.extra))])

    def kicks(self):
        """6. Iterated local search: kick one of the three best maps, polish."""
        rng, free = self.rng, self.free
        hi = kick_limit(free.size)
        for i in range(max(self.cfg["kicks"], self.extra)):
            if self.late():
                break
            tops = self.pool.top(3)
            base = tops[0][1] if i % 3 else tops[i // 3 % len(tops)][1]
            self.run_all(self.bij, [kick(rng, base, free, int(rng.integers(2, hi + 1)))])

    def dense_refine(self, warm_dense):
        """7. Dense targets: the best bijections, the dense warm starts, the reflections of the MDS
        embedding onto Y and the best single reassignment, polished over Y; then dense kicks."""
        D, n, free, dense, rng = self.D, self.n, self.free, self.dense, self.rng
        refine = [it[1] for it in self.pool.top(self.cfg["dense"])] + list(warm_dense)
        # reflections onto Y: the mirror of a TOSCA animal scores 1.2-1.9 as a
        # bijection of X (below the best swap, so never among the maps above)
        # but 3.3-3.7 over Y; no start built on X alone reaches that basin
        refine += S.reflection_starts(D, n, free, self.lm, *self.cfg["reflect"])
        if free.size >= 1:
            refine.append(best_reassignment(D, n, free))
        self.run_all(dense, refine)
        for i in range(self.cfg["dense_kicks"]):
            if self.late():
                break
            base = self.pool.top(2)[i % 2 if len(self.pool.items) > 1 else 0][1]
            self.run_all(dense, [_dense_kick(rng, base, free, dense.knn, D.shape[0],
                                             int(rng.integers(2, max(3, free.size // 10) + 1)))])

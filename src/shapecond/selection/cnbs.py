"""Condition Number Based Sampling, global version (paper Section 6).

CNBS greedily adds the landmark that lowers the global symmetry score σ (paper Eq. 5)
most.  The heat map of a step is σ with each candidate sample p fixed in addition to
the landmarks L so far (paper Figures 1 and 4); the next landmark is its argmin.  The
scores after each landmark form the "vector of symmetry scores" of Section 6.

σ is known only through a lower bound with a witness map (``witness_search``), so the
heat map is a lower bound per candidate, assembled in four steps:

1. **Fixed by the witness.**  If the best witness map T of the previous step already
   fixes p (T(p) = p, e.g. p on the mirror plane of a mirror witness) and, on the
   scale-aware score (``budget``), keeps p's distance row within budget / N (the
   constraint p adds as a landmark: ``objective.anchor_rows``, O(N)), T is feasible with
   p fixed, so the bound does not move: heat[p] = σ_L.  No search is run.  A T that fixes
   p but breaks its row is not a map of p's problem: p is searched as the others are.
2. **Warm start.**  Otherwise each of the best ``n_maps`` distinct witness maps is
   repaired by one move so that T(p) = p (swap p with its pre-image q, T(q) := T(p);
   or, with dense targets when p is nobody's image, reassign T(p) := p), and the
   compiled local search is re-run from these starts only, with L ∪ {p} fixed
   (``WarmPolisher``).
3. **Floor.**  The best single swap of two samples avoiding L ∪ {p}, for every p at
   once from one O(N³) table (``swap_floor``): heat[p] ≥ it.  With a budget only the
   swaps within it whose distance rows at L ∪ {p} stay within budget / N count.
4. **Re-solves.**  The candidates the witness maps move farthest
   (max over maps of D[p, T(p)]) are where fixing p hurts the witness most and where
   the argmin lies; the ``resolve_fraction`` (default 20 %) of them with the largest
   move are searched again; heat[p] is the max of all bounds.  The first prototype
   re-solved them with a fresh multistart search; here a fresh ``witness_search``
   costs 8-18 s at N = 400 on the shared machine (its spectral and Gilmore-Lawler
   starts do not depend on p but are recomputed), so the default re-solve is an
   iterated local search instead: ``N_KICKS`` random kicks (random swaps of free
   samples, applied by rank-1 updates) of the repaired base maps, each polished
   (``resolve="ils"``);
   ``resolve="full"`` gives the prototype's behaviour.  Whether the argmin agrees
   with full re-solves of every candidate is checked in tests (small N) and by the
   project's landmark benchmark on TOSCA.
5. **Leader verification.**  The argmin is searched again from the best maps found
   for the ``n_cross`` highest-valued other candidates (repaired to fix it) and, for
   N <= ``FULL_VERIFY_N``, by a fresh ``witness_search``; if its value rises, the new
   argmin is verified in turn (at most ``max_verify`` rounds).  Warm starts alone can
   miss a map that only exists with p fixed; this catches it where it matters.  Each
   distinct donor map is searched once (donors often share their best map: a repeated
   start finds nothing new, and on TOSCA cat0 repeats were most of the verification's
   time).  With pruning a verification stops once the leader's value passes the runner-up's
   (in the tie walk below: the window's end), since it has then lost the comparison it was
   verified for; if the runner-up's value rises in turn and the cut leader becomes the
   argmin again, its verification is run again from its start in full (``complete``), so
   the landmarks are those of verifications run in full.

6. **Pruning** (``prune=True``, what ``cnbs_landmarks`` uses).  Candidates are
   evaluated in tie-break order, and each search stops as soon as its value passes the
   smallest complete value so far (``_kernels.local_search``'s ``stop``): values only
   grow during a search, so such a candidate cannot be the argmin.  Candidates whose
   floor alone reaches the incumbent are not searched at all (they lose the tie).  A
   pruned candidate that becomes the argmin after verification raised the leader's
   value is evaluated in full before it is accepted.  Pruned values are weaker (still
   valid) lower bounds, marked in ``HeatMap.pruned``; pictures use the unpruned map.
   On TOSCA cat0 at N = 400 this cut 15 landmarks from 490 s to about 75 s of CPU.

Ties (all heat values inf on an exactly symmetric shape, for instance) are broken by
the larger move, then the smaller index.  On the scale-aware score (``budget``) values
within the resolution of δ (``scale.resolution``, half a sample spacing) of the smallest
are ties too, broken first by the larger distance to the landmarks so far: the
farthest-point rule among candidates the sampling cannot rank.  Without it the greedy
follows differences of a fraction of a sample spacing and stacks landmarks at one tip
once δ has reached its plateau (benchmarks, landmark spread).  The argmin m is found
as above; then the candidates are walked from the farthest, each searched only until
its value passes m + tolerance, and the first that stays below (after verification)
is the choice.  And each next heat map of δ starts from a fresh ``witness_search`` with
the new landmark (warm-started from the chosen candidate's maps; none after the last
landmark, where no heat map follows), not from those maps alone: warm starts repaired
from maps of fewer landmarks miss the widest map within the budget (on TOSCA wolf, heat
values of 0.06 where a fresh search finds δ = 0.137), and the heat map can only rank
candidates against a base that has it.

Threads (``shapecond.threads``): with pruning, candidates go one at a time (in chunks the
incumbent lags behind and prunes far less) and draw their kicks from one generator in
order; the searches from the starts of one candidate run in parallel and are taken in
order up to the first above the incumbent, the generator rewound to where a serial loop
would have left it, so the landmarks are those of a serial run.  Without pruning (the
pictures), ``CHUNK`` candidates are searched at once, each drawing its kicks from a
generator seeded by the seed and the candidate.  No result depends on the thread count.

Everything is deterministic given ``seed``, whatever the number of BLAS threads: the
entry points run with one (``threads.single_blas_thread``), since a threaded product
sums in another order and the greedy follows near-ties of such sums.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..checks import check_landmark_count
from ..errors import InputError
from ..threads import single_blas_thread
from ..symmetry import objective as obj
from ..symmetry.scale import resolution
from ..symmetry.search import witness_search
from ..symmetry.starts import distinct_maps
from ..threads import thread_map
from .swap_floor import swap_floor, swap_table
from .warm import WarmPolisher

#: Share of the candidates, those moved farthest by the witness maps, that get a
#: full re-solve in every heat map (20 % kept the argmin at N = 400 in the prototype).
RESOLVE_FRACTION = 0.2
#: Number of best distinct witness maps used as warm starts.
N_MAPS = 4
#: Kicked restarts per re-solved candidate (``resolve="ils"``).
N_KICKS = 6
#: Up to this N the leaders of a heat map are verified by a fresh witness_search.
FULL_VERIFY_N = 200
#: Donors of the leader verification: the best maps of this many highest-valued candidates.
N_CROSS = 24
#: Rounds of leader verification at most.
MAX_VERIFY = 8
#: Candidates of an unpruned heat map searched at once by parallel threads.
CHUNK = 8


@dataclass(frozen=True)
class HeatMapOptions:
    """How a CNBS heat map is computed (module docstring, steps 2-6).

    Attributes
    ----------
    seed, effort : of the witness searches (the base search, full re-solves, verification).
    n_maps : best distinct witness maps used as warm starts (``N_MAPS``).
    resolve_fraction : share of candidates (moved farthest) re-solved; 1.0 re-solves all.
    resolve : "ils" (``n_kicks`` random kicks of the repaired base maps, each polished) or
        "full" (a fresh ``witness_search`` with ``effort``, seconds per candidate at N = 400).
    n_kicks : kicked restarts per re-solved candidate (``N_KICKS``).
    n_cross : donors of the leader verification (``N_CROSS``).
    max_verify : rounds of leader verification at most (``MAX_VERIFY``).
    prune : stop each candidate's search once its value passes the incumbent (step 6):
        the same argmin for a fraction of the work, but the values of the ``pruned``
        candidates are weaker lower bounds.  Off for pictures.
    """

    seed: int = 0
    effort: str = "default"
    n_maps: int = N_MAPS
    resolve_fraction: float = RESOLVE_FRACTION
    resolve: str = "ils"
    n_kicks: int = N_KICKS
    n_cross: int = N_CROSS
    max_verify: int = MAX_VERIFY
    prune: bool = False

    def __post_init__(self):
        if self.resolve not in ("ils", "full"):
            raise InputError(f"resolve must be 'ils' or 'full', got {self.resolve!r}")
        if not 0.0 <= self.resolve_fraction <= 1.0:
            raise InputError("resolve fraction must lie in [0, 1]")


@dataclass(frozen=True)
class CNBSOptions(HeatMapOptions):
    """``HeatMapOptions`` of greedy CNBS (``cnbs_landmarks``): its heat maps are pruned by
    default (only their argmins are used), and ``keep_heat_maps`` keeps them in the result."""

    prune: bool = True
    keep_heat_maps: bool = False


def repair_fixing(t: np.ndarray, p: int) -> np.ndarray:
    """One move making T(p) = p: swap with p's pre-image, or reassign p to itself."""
    t = np.array(t, dtype=np.int64, copy=True)
    if t[p] == p:
        return t
    pre = np.flatnonzero(t == p)
    if pre.size:
        q = int(pre[0])
        t[q] = t[p]
    t[p] = p
    return t


@dataclass
class HeatMap:
    """σ lower bound with each candidate sample fixed (paper Figures 1 and 4).

    ``values[p]`` is nan for p in ``landmarks`` (not a candidate); ``results[p]`` is
    the search result whose witness attains the warm/full part of ``values[p]``;
    ``pruned[p]`` is True where the search stopped early once p could no longer be
    the argmin (``heat_map(prune=True)``; all False without pruning).
    """

    values: np.ndarray
    sigma_before: float
    landmarks: tuple
    moved: np.ndarray
    resolved: np.ndarray
    pruned: np.ndarray | None = None
    results: dict = field(repr=False, default_factory=dict)
    seconds: float = 0.0
    tie: float = 0.0
    spread: np.ndarray | None = None

    def improvement(self) -> np.ndarray:
        """σ before minus σ with p fixed (0 where the witness fixes p)."""
        with np.errstate(invalid="ignore"):
            return np.where(np.isinf(self.values) & np.isinf(self.sigma_before), 0.0,
                            self.sigma_before - self.values)

    def argmin(self) -> int:
        """The next landmark: the smallest value; ties (within ``tie``) go to the larger
        ``spread`` (distance to the landmarks), then the larger move, then the smaller index."""
        cand = np.flatnonzero(~np.isnan(self.values))
        v = self.values[cand]
        if self.tie > 0 and self.spread is not None and np.isfinite(v.min()):
            near = cand[v <= v.min() + self.tie]
            order = np.lexsort((near, -self.moved[near], -self.spread[near]))
            return int(near[order[0]])
        order = np.lexsort((cand, -self.moved[cand], v))
        return int(cand[order[0]])


def _maps_of(res, n_maps):
    maps = list(getattr(res, "maps", None) or [])
    if not maps:
        maps = [res.witness]
    return [np.asarray(m, dtype=np.int64) for m in maps[:n_maps]]


@single_blas_thread
def heat_map(D, n_samples=None, landmarks=(), base=None, budget=None, progress=None,
             options: HeatMapOptions = HeatMapOptions()) -> HeatMap:
    """The CNBS heat map: σ (lower bound) with each candidate sample fixed.

    Parameters
    ----------
    D : (M, M) array; the first ``n_samples`` points are the samples X.
    landmarks : sample indices already fixed.
    base : SearchResult of ``witness_search`` with ``landmarks`` fixed (computed when None).
    budget : None for σ (Eq. 5); a Dist² budget for the scale-aware score
        (``shapecond.symmetry.scale``): values are then sqrt(d²) of the widest map
        within the budget fixing each candidate (δ(ε) = value / sqrt(N)), and values
        within sqrt(N)·``scale.resolution`` of the smallest tie (module docstring).
    progress : callable(done, total) or None.
    options : HeatMapOptions (seed, effort, warm maps, re-solves, verification, pruning).
    """
    t0 = time.perf_counter()
    opts = options
    D = np.ascontiguousarray(np.asarray(D, dtype=float))
    n = D.shape[0] if n_samples is None else int(n_samples)
    L = [int(v) for v in landmarks]
    if len(set(L)) != len(L) or any(not 0 <= v < n for v in L):
        raise InputError("landmarks must be distinct sample indices")
    if base is None:
        base = witness_search(D, n_samples=n, landmarks=L, seed=opts.seed, effort=opts.effort, budget=budget)
    run = _HeatMapRun(D, n, L, base, opts, budget)
    run.scan(progress)
    c = run.settle()
    if run.tie > 0:
        run.break_ties(c)
    # values are not clipped at sigma0: a value above it means the search with p fixed
    # found a better witness than the base search did (then sigma0 was weak).
    pruned = run.pruned.copy()
    pruned[list(run.partial)] = True  # verifications cut short: weaker lower bounds too
    return HeatMap(run.values, run.sigma0, tuple(L), run.moved, run.resolved, pruned, run.results,
                   time.perf_counter() - t0, run.tie, run.spread)


class _HeatMapRun:
    """One heat map being computed: the bound of each candidate so far (``values``, with the
    search result attaining it in ``results``) and what was done to it (``resolved``,
    ``pruned``, ``verified``).  The methods are the steps of the module docstring."""

    def __init__(self, D, n, L, base, opts, budget):
        self.D, self.n, self.L, self.base, self.opts, self.budget = D, n, L, base, opts, budget
        self.sigma0 = float(base.sigma)
        maps = _maps_of(base, opts.n_maps)
        cand = self.cand = np.array([p for p in range(n) if p not in set(L)], dtype=np.int64)
        if cand.size == 0:
            raise InputError("every sample is already a landmark")
        self.values = np.full(n, np.nan)
        self.moved = np.zeros(n)
        for t in maps:
            self.moved = np.maximum(self.moved, D[np.arange(n), t])
        self.floor = np.zeros(n)
        self.floor[cand] = swap_floor(D, n, L, cand, budget)  # step 3
        self.results = {}
        self.best_t = maps[0]
        self.credited = self._credited(cand)  # step 1
        # every warm map fixes p and the best is feasible with p fixed: nothing to verify (step 5)
        self.settled = self.credited & (self.moved == 0.0)
        self.polish = WarmPolisher(D, n, maps, L, budget)
        n_full = int(math.ceil(opts.resolve_fraction * cand.size))
        self.order = cand[np.lexsort((cand, -self.moved[cand]))]  # the tie-break order of HeatMap.argmin
        self.to_resolve = np.zeros(n, dtype=bool)
        self.to_resolve[self.order[:n_full]] = True
        self.resolved = np.zeros(n, dtype=bool)
        self.pruned = np.zeros(n, dtype=bool)
        self.verified = np.zeros(n, dtype=bool)
        self.partial = {}  # candidate -> (value, result) before its verification was cut short
        self.rounds = 0
        self.values[cand] = self.floor[cand]
        self.tie, self.spread = 0.0, None
        self.shared = np.random.default_rng(opts.seed)
        if budget is not None and L:
            self.tie = math.sqrt(n) * resolution(D, n)
            self.spread = D[:n, L].min(axis=1)

    def _credited(self, cand) -> np.ndarray:
        """Step 1: True for the candidates whose problem the best base map is feasible for, so that
        its value σ_L is theirs: it fixes p and, with a budget, keeps p's distance row within
        budget / N (the constraint p adds as a landmark, ``objective.anchor_rows``; its other
        constraints are those of L, which the base map meets).  O(N) a candidate."""
        t, n = self.best_t, self.n
        ok = np.zeros(n, dtype=bool)
        ok[cand] = t[cand] == cand
        if self.budget is not None and ok.any():
            fixed = np.flatnonzero(ok)
            ok[fixed] = obj.anchor_rows(self.D, t, fixed) <= self.budget / n
        return ok

    def take(self, p, r):
        """Keep the search result ``r`` for candidate ``p`` if it raises its bound."""
        if r is not None and (float(r.sigma) > self.values[p] or p not in self.results):
            self.values[p] = max(self.values[p], float(r.sigma))
            self.results[p] = r

    def evaluate(self, p, stop):
        """Steps 1, 2 and 4 for candidate p; True when cut short above ``stop``."""
        opts, L = self.opts, self.L
        if self.credited[p]:  # 1. fixed by the witness, within p's row budget
            self.values[p] = max(self.sigma0, self.floor[p])
            self.results[p] = self.base
            return False
        if stop < math.inf and self.floor[p] >= stop:
            return True  # its floor alone ties or beats the incumbent, which comes first
        r, cut = self.polish.bounded(L + [p], p, stop=stop)  # 2. warm starts
        self.take(p, r)
        if cut or not self.to_resolve[p]:
            return cut
        if opts.resolve == "full":  # 4. re-solve
            r = witness_search(self.D, n_samples=self.n, landmarks=L + [p], seed=opts.seed, effort=opts.effort,
                               budget=self.budget)
        else:  # "ils": kicked copies of the repaired base maps, polished
            # pruned: candidates in order, kicks from one generator (as ever); unpruned: candidates in
            # parallel, so each draws its kicks from a generator of its own
            rng = self.shared if opts.prune else np.random.default_rng([opts.seed, p])
            r, cut = self.polish.bounded(L + [p], p, rng=rng, n_kicks=opts.n_kicks, stop=stop)
        self.resolved[p] = True
        self.take(p, r)
        return cut

    def scan(self, progress):
        """Every candidate in tie-break order.  With ``prune`` one at a time (each search stops
        once it passes the smallest complete value so far, the incumbent: such a candidate
        cannot be the argmin), the searches of a candidate in parallel threads; without,
        ``CHUNK`` candidates at once."""
        order, prune = self.order, self.opts.prune
        incumbent = math.inf
        step = 1 if prune else CHUNK
        for k0 in range(0, order.size, step):
            chunk = [int(p) for p in order[k0:k0 + step]]
            stop = incumbent if prune else math.inf
            for p, cut in zip(chunk, thread_map(lambda p: self.evaluate(p, stop), chunk)):
                self.pruned[p] = cut
                if not cut:
                    incumbent = min(incumbent, self.values[p])
            if progress:
                progress(min(k0 + step, order.size), order.size)

    def verify(self, c, stop=math.inf, count=True) -> bool:
        """5. Search candidate ``c`` again from the donors' maps (repaired to fix it) and, for
        N <= FULL_VERIFY_N or resolve="full", by a fresh witness_search warm-started from its
        own best map.  ``count``: a round of its own (not the completion of a verification cut
        short, ``complete``).

        With pruning the search stops once ``c``'s value passes ``stop`` (the value at which it
        loses the comparison it is verified for): True then, and its value, a weaker lower bound,
        is kept with what it had before in ``partial`` until ``complete`` runs it in full."""
        opts, L = self.opts, self.L
        if count:
            self.verified[c] = True
            self.rounds += 1
        if self.settled[c]:
            return False  # fixed by the witness: its value sigma0 is attained and maximal
        before = (self.values[c], self.results.get(c))
        starts = distinct_maps([repair_fixing(t, c) for t in self.donor_maps])
        r, cut = self.polish.bounded(L + [c], c, extra_starts=starts, stop=stop if opts.prune else math.inf)
        if not cut and (opts.resolve == "full" or self.n <= FULL_VERIFY_N):
            own = [self.results[c].witness] if c in self.results else []
            r2 = witness_search(self.D, n_samples=self.n, landmarks=L + [c], seed=opts.seed, starts=own,
                                effort=opts.effort, budget=self.budget)
            r = r2 if r is None or float(r2.sigma) > float(r.sigma) else r
        if r is not None and float(r.sigma) > self.values[c]:
            self.values[c] = float(r.sigma)
            self.results[c] = r
        if cut:
            self.partial[c] = before
        return cut

    def complete(self, c, stop=math.inf):
        """The verification of ``c`` that was cut short, run again from its start (what it had before),
        until ``stop``: the value and result a verification in full gives when not cut again."""
        self.values[c], r = self.partial.pop(c)
        if r is None:
            self.results.pop(c, None)
        else:
            self.results[c] = r
        self.verify(c, stop, count=False)

    def runner_up(self, c) -> float:
        """The smallest value of the candidates other than ``c`` (inf if none): ``c`` stays the argmin
        of ``HeatMap.argmin`` without ties as long as its value does not pass it."""
        others = self.values[self.cand[self.cand != c]]
        return float(np.min(others)) if others.size else math.inf

    def settle(self) -> int:
        """5. Verify the leaders until the argmin is a verified candidate (at most
        ``max_verify`` rounds); a pruned candidate that becomes the argmin (after the
        leader's value rose) is first evaluated in full.  Returns the argmin."""
        L = self.L
        donors = sorted((p for p in self.results if p not in L), key=lambda p: -self.values[p])[:self.opts.n_cross]
        self.donor_maps = [self.results[p].witness for p in donors]
        while True:
            c = HeatMap(self.values, self.sigma0, tuple(L), self.moved, self.resolved).argmin()
            if c in self.partial:  # its verification stopped above the runner-up, which has since risen
                self.complete(c)
                continue
            if self.pruned[c]:  # the returned argmin is never a pruned candidate
                self.pruned[c] = self.evaluate(c, math.inf)
                continue
            if self.verified[c] or self.rounds >= self.opts.max_verify or self.settled[c]:
                return c
            self.verify(c, self.runner_up(c))

    def break_ties(self, c):
        """6'. Near-ties of δ (module docstring): walk the candidates from the farthest from the
        landmarks; the first whose value, searched until it leaves the tie (and verified),
        stays within ``tie`` of the argmin's value m wins.  Values only grow, so m stays the
        smallest and ``HeatMap.argmin`` returns the same candidate."""
        values, pruned, cand = self.values, self.pruned, self.cand
        window = values[c] + self.tie
        for p in cand[np.lexsort((cand, -self.moved[cand], -self.spread[cand]))]:
            p = int(p)
            if p == c:
                break
            if values[p] > window:
                continue  # already a lower bound above the tie
            if p in self.partial:  # verified in settle until it passed the runner-up: now until the window
                self.complete(p, window)
            if pruned[p]:
                pruned[p] = self.evaluate(p, window)  # only a pruned search is resumed
            if not pruned[p] and values[p] <= window and not self.verified[p] and \
                    self.rounds < self.opts.max_verify:
                self.verify(p, window)
            if p in self.partial and values[p] <= window:
                self.complete(p)  # cut on a tracked value whose exact re-score is within the window
            if not pruned[p] and values[p] <= window:
                break


@single_blas_thread
def full_heat_map(D, n_samples=None, landmarks=(), seed: int = 0, effort: str = "default", budget=None):
    """Reference heat map: a full multistart search for every candidate (slow; tests, benchmarks)."""
    D = np.asarray(D, dtype=float)
    n = D.shape[0] if n_samples is None else int(n_samples)
    L = [int(v) for v in landmarks]
    values = np.full(n, np.nan)
    for p in range(n):
        if p not in L:
            values[p] = float(witness_search(D, n_samples=n, landmarks=L + [p], seed=seed, effort=effort,
                                             budget=budget).sigma)
    return values


def _swap_witness(D, n, L, base, budget=None):
    S = swap_table(D, n, budget, L)
    S[L, :] = -np.inf
    S[:, L] = -np.inf
    np.fill_diagonal(S, -np.inf)
    a, b = divmod(int(np.argmax(S)), n)
    t = np.arange(n, dtype=np.int64)
    t[a], t[b] = b, a
    return WarmPolisher(D, n, _maps_of(base, N_MAPS), L[:-1], budget)(L, L[-1], extra_starts=[t])


def _next_base(D, n, L, c, hm, prev, budget):
    """The witness search result with the new landmark ``c`` fixed that the next heat map starts
    from: the heat map ``hm``'s result for ``c``, or a map attaining the single-swap floor when
    that won (warm-started from ``prev``, the base of ``hm``, if ``c`` has no result)."""
    base = hm.results.get(c)
    if base is None or float(base.sigma) < hm.values[c]:
        # the single-swap floor won: continue from a witness that attains it
        base = _swap_witness(D, n, L + [c], base or prev, budget)
    return base


def _fresh_base(D, n, landmarks, base, budget, opts):
    """For δ, a fresh search with ``landmarks`` fixed, warm-started from ``base``'s maps (module
    docstring, on ties), if it finds more than ``base``: the next heat map starts from it."""
    fresh = witness_search(D, n_samples=n, landmarks=landmarks, seed=opts.seed, effort=opts.effort,
                           starts=_maps_of(base, opts.n_maps), budget=budget)
    return fresh if float(fresh.sigma) > float(base.sigma) else base


@single_blas_thread
def cnbs_landmarks(D, n_samples, k, fixed=(), base=None, budget=None, progress=None,
                   options: CNBSOptions = CNBSOptions()):
    """Greedy CNBS: ``k`` landmarks, each the argmin of the current heat map.

    ``budget``: None for the paper's σ; a Dist² budget for the scale-aware score
    (``heat_map``), the ``cnbs-scale`` method.  ``base``: the ``witness_search``
    result with ``fixed`` fixed (and the same ``budget``), when already known.
    ``progress``: callable(step, done, total) or None.  ``options``: CNBSOptions (the
    ``HeatMapOptions`` of every step, pruned by default, and ``keep_heat_maps``).

    Returns
    -------
    dict with ``landmarks`` (new sample indices in order), ``scores`` (σ lower bound
    after each), ``initial_score`` (σ with only ``fixed``), ``heat_maps`` (list of
    HeatMap when ``keep_heat_maps``), ``witness`` (a map attaining the last score: for δ the
    fresh search of ``_fresh_base`` is not run after the last landmark, nothing would use it).
    """
    opts = options
    D = np.ascontiguousarray(np.asarray(D, dtype=float))
    n = D.shape[0] if n_samples is None else int(n_samples)
    L = check_landmark_count(k, n, fixed)
    if base is None:
        base = witness_search(D, n_samples=n, landmarks=L, seed=opts.seed, effort=opts.effort, budget=budget)
    initial = float(base.sigma)
    new, scores, maps = [], [], []
    for step in range(k):
        hm = heat_map(D, n, L, base=base, budget=budget, options=opts,
                      progress=(lambda d, t, s=step: progress(s, d, t)) if progress else None)
        c = hm.argmin()
        new.append(c)
        scores.append(float(hm.values[c]))
        base = _next_base(D, n, L, c, hm, base, budget)
        L.append(c)
        if budget is not None and step + 1 < k:  # no heat map follows the last landmark
            base = _fresh_base(D, n, L, base, budget, opts)
        if opts.keep_heat_maps:
            maps.append(hm)
        else:
            hm.results.clear()
    return {"landmarks": new, "scores": scores, "initial_score": initial, "heat_maps": maps,
            "witness": np.asarray(base.witness)}

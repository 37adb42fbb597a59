"""Condition Number Based Sampling, global version (paper Section 6).

CNBS greedily adds the landmark that lowers the global symmetry score σ (paper Eq. 5)
most.  The heat map of a step is σ with each candidate sample p fixed in addition to
the landmarks L so far (paper Figures 1 and 4); the next landmark is its argmin.  The
scores after each landmark form the "vector of symmetry scores" of Section 6.

σ is known only through a lower bound with a witness map (``witness_search``), so the
heat map is a lower bound per candidate, assembled in four steps:

1. **Fixed by the witness.**  If the best witness map T of the previous step already
   fixes p (T(p) = p, e.g. p on the mirror plane of a mirror witness), T is feasible
   with p fixed, so the bound does not move: heat[p] = σ_L.  No search is run.
2. **Warm start.**  Otherwise each of the best ``n_maps`` distinct witness maps is
   repaired by one move so that T(p) = p (swap p with its pre-image q, T(q) := T(p);
   or, with dense targets when p is nobody's image, reassign T(p) := p), and the
   compiled local search is re-run from these starts only, with L ∪ {p} fixed
   (``WarmPolisher``).
3. **Floor.**  The best single swap of two samples avoiding L ∪ {p}, for every p at
   once from one O(N³) table (``swap_scores``): heat[p] ≥ it.
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
   miss a map that only exists with p fixed; this catches it where it matters.

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
the new landmark (warm-started from the chosen candidate's maps), not from those maps
alone: warm starts repaired from maps of fewer landmarks miss the widest map within the
budget (on TOSCA wolf, heat values of 0.06 where a fresh search finds δ = 0.137), and the
heat map can only rank candidates against a base that has it.

Threads (``shapecond.threads``): with pruning, candidates go one at a time (in chunks the
incumbent lags behind and prunes far less) and draw their kicks from one generator in
order; the searches from the starts of one candidate run in parallel and are taken in
order up to the first above the incumbent, the generator rewound to where a serial loop
would have left it, so the landmarks are those of a serial run.  Without pruning (the
pictures), ``CHUNK`` candidates are searched at once, each drawing its kicks from a
generator seeded by the seed and the candidate.  No result depends on the thread count.

Everything is deterministic given ``seed``, whatever the number of BLAS threads: the
entry points run with one (``limits.single_blas_thread``), since a threaded product
sums in another order and the greedy follows near-ties of such sums.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..checks import check_landmark_count
from ..errors import InputError
from ..limits import single_blas_thread
from ..symmetry.objective import ISOMETRY_RTOL
from ..threads import thread_map
from .warm import WarmPolisher, _search_module

#: Share of the candidates, those moved farthest by the witness maps, that get a
#: full re-solve in every heat map (20 % kept the argmin at N = 400 in the prototype).
RESOLVE_FRACTION = 0.2
#: Number of best distinct witness maps used as warm starts.
N_MAPS = 4
#: Kicked restarts per re-solved candidate (``resolve="ils"``).
N_KICKS = 6
#: Up to this N the leaders of a heat map are verified by a fresh witness_search.
FULL_VERIFY_N = 200
#: Candidates of an unpruned heat map searched at once by parallel threads.
CHUNK = 8


def swap_scores(D: np.ndarray, n: int) -> np.ndarray:
    """σ of every single swap (a b) of the identity on the samples: (n, n), 0 on the diagonal.

    Swapping a and b gives d² = 2 D[a,b]² and Dist² = 4 Σ_{c ≠ a,b} (D[a,c] − D[b,c])²
    (ordered pairs, columns over X), so σ_ab² = D[a,b]² / (2 Σ_c ...).  A swap with
    round-off distortion (``objective.is_isometry``) scores inf.
    """
    Dx = np.asarray(D, float)[:n, :n]
    sq = (Dx**2).sum(axis=1)
    row = sq[:, None] + sq[None, :] - 2.0 * Dx @ Dx  # ‖D_a − D_b‖² (Dx symmetric)
    dist2 = 4.0 * np.maximum(row - 2.0 * Dx**2, 0.0)
    d2 = 2.0 * Dx**2
    scale2 = float((Dx**2).sum())
    iso = dist2 <= ISOMETRY_RTOL**2 * scale2  # round-off distortion: an isometry
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sqrt(d2 / np.where(iso, 1.0, dist2))
    s[iso & (d2 > 0)] = np.inf
    np.fill_diagonal(s, 0.0)
    return s


def swap_table(D: np.ndarray, n: int, budget=None) -> np.ndarray:
    """Value of every single swap (a b) in the units of the heat map: σ (``swap_scores``),
    or with a Dist² ``budget`` sqrt(d²) = sqrt(2)·D[a,b] for the swaps within it and 0 for the others."""
    if budget is None:
        return swap_scores(D, n)
    from ..symmetry.search import swap_terms

    num, den = swap_terms(np.asarray(D, float)[:n, :n], np.arange(n))
    S = np.where(den <= budget, np.sqrt(num), 0.0)
    np.fill_diagonal(S, 0.0)
    return S


def best_swap_avoiding(S: np.ndarray, fixed, candidates) -> np.ndarray:
    """For each candidate p, the best swap score over pairs avoiding ``fixed`` ∪ {p}."""
    S = S.copy()
    n = S.shape[0]
    fixed = list(fixed)
    S[fixed, :] = -np.inf
    S[:, fixed] = -np.inf
    np.fill_diagonal(S, -np.inf)
    out = np.full(n, -np.inf)
    flat = int(np.argmax(S))
    a, b = divmod(flat, n)
    top = S[a, b]
    for v in (a, b):
        T = S.copy()
        T[v, :] = -np.inf
        T[:, v] = -np.inf
        out[v] = T.max()
    cand = np.asarray(list(candidates), dtype=np.int64)
    res = np.where((cand == a) | (cand == b), out[cand], top)
    return np.maximum(res, 0.0)


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
def heat_map(D, n_samples=None, landmarks=(), base=None, seed: int = 0, effort: str = "default",
             n_maps: int = N_MAPS, resolve_fraction: float = RESOLVE_FRACTION,
             resolve: str = "ils", n_kicks: int = N_KICKS, n_cross: int = 24, max_verify: int = 8,
             prune: bool = False, progress=None, budget=None) -> HeatMap:
    """The CNBS heat map: σ (lower bound) with each candidate sample fixed.

    Parameters
    ----------
    D : (M, M) array; the first ``n_samples`` points are the samples X.
    landmarks : sample indices already fixed.
    base : SearchResult of ``witness_search`` with ``landmarks`` fixed (computed when None).
    effort : effort of the base search and of the full re-solves (warm starts are polished only).
    resolve_fraction : share of candidates (moved farthest) re-solved; 1.0 re-solves all.
    resolve : "ils" (default: ``n_kicks`` random kicks of the repaired base maps, each
        polished) or "full" (a fresh ``witness_search``
        with ``effort``, seconds per candidate at N = 400).
    prune : stop each candidate's search once its value passes the incumbent (step 6 of
        the module docstring): the same argmin for a fraction of the work, but the
        values of the ``pruned`` candidates are weaker lower bounds.  Off for pictures.
    progress : callable(done, total) or None.
    budget : None for σ (Eq. 5); a Dist² budget for the scale-aware score
        (``shapecond.symmetry.scale``): values are then sqrt(d²) of the widest map
        within the budget fixing each candidate (δ(ε) = value / sqrt(N)), and values
        within sqrt(N)·``scale.resolution`` of the smallest tie (module docstring).
    """
    t0 = time.perf_counter()
    search = _search_module()
    D = np.ascontiguousarray(np.asarray(D, dtype=float))
    n = D.shape[0] if n_samples is None else int(n_samples)
    L = [int(v) for v in landmarks]
    if len(set(L)) != len(L) or any(not 0 <= v < n for v in L):
        raise InputError("landmarks must be distinct sample indices")
    if resolve not in ("ils", "full"):
        raise InputError(f"resolve must be 'ils' or 'full', got {resolve!r}")
    if not 0.0 <= resolve_fraction <= 1.0:
        raise InputError("resolve fraction must lie in [0, 1]")
    if base is None:
        base = search.witness_search(D, n_samples=n, landmarks=L, seed=seed, effort=effort, budget=budget)
    sigma0 = float(base.sigma)
    maps = _maps_of(base, n_maps)
    cand = np.array([p for p in range(n) if p not in set(L)], dtype=np.int64)
    if cand.size == 0:
        raise InputError("every sample is already a landmark")
    values = np.full(n, np.nan)
    moved = np.zeros(n)
    for t in maps:
        moved = np.maximum(moved, D[np.arange(n), t])
    floor = np.zeros(n)
    floor[cand] = best_swap_avoiding(swap_table(D, n, budget), L, cand)
    results = {}
    best_t = maps[0]
    polish = WarmPolisher(D, n, maps, L, budget)
    n_full = int(math.ceil(resolve_fraction * cand.size))
    order = cand[np.lexsort((cand, -moved[cand]))]  # the tie-break order of HeatMap.argmin
    to_resolve = np.zeros(n, dtype=bool)
    to_resolve[order[:n_full]] = True
    resolved = np.zeros(n, dtype=bool)
    pruned = np.zeros(n, dtype=bool)
    values[cand] = floor[cand]
    tie, spread = 0.0, None
    shared = np.random.default_rng(seed)
    if budget is not None and L:
        from ..symmetry.scale import resolution

        tie = math.sqrt(n) * resolution(D, n)
        spread = D[:n, L].min(axis=1)

    def take(p, r):
        if r is not None and (float(r.sigma) > values[p] or p not in results):
            values[p] = max(values[p], float(r.sigma))
            results[p] = r

    def evaluate(p, stop):
        """Steps 1, 2 and 4 for candidate p; True when cut short above ``stop``."""
        if best_t[p] == p:
            values[p] = max(sigma0, floor[p])
            results[p] = base
            return False
        if stop < math.inf and floor[p] >= stop:
            return True  # its floor alone ties or beats the incumbent, which comes first
        r, cut = polish.bounded(L + [p], p, stop=stop)
        take(p, r)
        if cut or not to_resolve[p]:
            return cut
        if resolve == "full":
            r = search.witness_search(D, n_samples=n, landmarks=L + [p], seed=seed, effort=effort,
                                      budget=budget)
        else:  # "ils": kicked copies of the repaired base maps, polished
            # pruned: candidates in order, kicks from one generator (as ever); unpruned: candidates in
            # parallel, so each draws its kicks from a generator of its own
            r, cut = polish.bounded(L + [p], p, rng=shared if prune else np.random.default_rng([seed, p]),
                                    n_kicks=n_kicks, stop=stop)
        resolved[p] = True
        take(p, r)
        return cut

    # candidates in tie-break order.  With ``prune`` one at a time (each search stops once it
    # passes the smallest complete value so far, the incumbent: such a candidate cannot be the
    # argmin), the searches of a candidate in parallel threads; without, CHUNK candidates at once
    incumbent = math.inf
    step = 1 if prune else CHUNK
    for k0 in range(0, order.size, step):
        chunk = [int(p) for p in order[k0:k0 + step]]
        stop = incumbent if prune else math.inf
        for p, cut in zip(chunk, thread_map(lambda p: evaluate(p, stop), chunk)):
            pruned[p] = cut
            if not cut:
                incumbent = min(incumbent, values[p])
        if progress:
            progress(min(k0 + step, order.size), order.size)
    # 5. verify the leaders: the current argmin is searched again from the best maps
    # found for the other candidates (any of them, repaired to fix p, is feasible) and,
    # for N <= FULL_VERIFY_N or resolve="full", by a fresh witness_search warm-started
    # from its own best map; repeat until the argmin is a verified candidate.  A pruned
    # candidate that becomes the argmin (after the leader's value rose) is first
    # evaluated in full.
    verified = np.zeros(n, dtype=bool)
    donors = sorted((p for p in results if p not in L), key=lambda p: -values[p])[:n_cross]
    donor_maps = [results[p].witness for p in donors]
    rounds = 0

    def verify(c):
        nonlocal rounds
        verified[c] = True
        rounds += 1
        if moved[c] == 0.0:
            return  # fixed by the witness: its value sigma0 is attained and maximal
        starts = [repair_fixing(t, c) for t in donor_maps]
        r = polish(L + [c], c, extra_starts=starts)
        if resolve == "full" or n <= FULL_VERIFY_N:
            own = [results[c].witness] if c in results else []
            r2 = search.witness_search(D, n_samples=n, landmarks=L + [c], seed=seed, starts=own,
                                       effort=effort, budget=budget)
            r = r2 if r is None or float(r2.sigma) > float(r.sigma) else r
        if r is not None and float(r.sigma) > values[c]:
            values[c] = float(r.sigma)
            results[c] = r

    while True:
        c = HeatMap(values, sigma0, tuple(L), moved, resolved).argmin()
        if pruned[c]:  # the returned argmin is never a pruned candidate
            pruned[c] = evaluate(c, math.inf)
            continue
        if verified[c] or rounds >= max_verify or moved[c] == 0.0:
            break
        verify(c)
    # 6'. near-ties of δ (module docstring): walk the candidates from the farthest from the
    # landmarks; the first whose value, searched until it leaves the tie (and verified),
    # stays within ``tie`` of the argmin's value m wins.  Values only grow, so m stays the
    # smallest and ``HeatMap.argmin`` returns the same candidate.
    if tie > 0:
        window = values[c] + tie
        for p in cand[np.lexsort((cand, -moved[cand], -spread[cand]))]:
            p = int(p)
            if p == c:
                break
            if values[p] > window:
                continue  # already a lower bound above the tie
            if pruned[p]:
                pruned[p] = evaluate(p, window)  # only a pruned search is resumed
            if not pruned[p] and values[p] <= window and not verified[p] and rounds < max_verify:
                verify(p)
            if not pruned[p] and values[p] <= window:
                break
    # values are not clipped at sigma0: a value above it means the search with p fixed
    # found a better witness than the base search did (then sigma0 was weak).
    return HeatMap(values, sigma0, tuple(L), moved, resolved, pruned, results, time.perf_counter() - t0,
                   tie, spread)


@single_blas_thread
def full_heat_map(D, n_samples=None, landmarks=(), seed: int = 0, effort: str = "default", budget=None):
    """Reference heat map: a full multistart search for every candidate (slow; tests, benchmarks)."""
    search = _search_module()
    D = np.asarray(D, dtype=float)
    n = D.shape[0] if n_samples is None else int(n_samples)
    L = [int(v) for v in landmarks]
    values = np.full(n, np.nan)
    for p in range(n):
        if p not in L:
            values[p] = float(search.witness_search(D, n_samples=n, landmarks=L + [p], seed=seed,
                                                    effort=effort, budget=budget).sigma)
    return values


def _swap_witness(D, n, L, base, budget=None):
    S = swap_table(D, n, budget)
    S[L, :] = -np.inf
    S[:, L] = -np.inf
    np.fill_diagonal(S, -np.inf)
    a, b = divmod(int(np.argmax(S)), n)
    t = np.arange(n, dtype=np.int64)
    t[a], t[b] = b, a
    return WarmPolisher(D, n, _maps_of(base, N_MAPS), L[:-1], budget)(L, L[-1], extra_starts=[t])


@single_blas_thread
def cnbs_landmarks(D, n_samples, k: int, fixed=(), seed: int = 0, effort: str = "default",
                   n_maps: int = N_MAPS, resolve_fraction: float = RESOLVE_FRACTION,
                   resolve: str = "ils", prune: bool = True, progress=None, keep_heat_maps: bool = False,
                   budget=None, base=None):
    """Greedy CNBS: ``k`` landmarks, each the argmin of the current heat map.

    ``budget``: None for the paper's σ; a Dist² budget for the scale-aware score
    (``heat_map``), the ``cnbs-scale`` method.  ``base``: the ``witness_search``
    result with ``fixed`` fixed (and the same ``budget``), when already known.

    Returns
    -------
    dict with ``landmarks`` (new sample indices in order), ``scores`` (σ lower bound
    after each), ``initial_score`` (σ with only ``fixed``), ``heat_maps`` (list of
    HeatMap when ``keep_heat_maps``), ``witness`` (final witness map).
    """
    search = _search_module()
    D = np.ascontiguousarray(np.asarray(D, dtype=float))
    n = D.shape[0] if n_samples is None else int(n_samples)
    L = check_landmark_count(k, n, fixed)
    if base is None:
        base = search.witness_search(D, n_samples=n, landmarks=L, seed=seed, effort=effort, budget=budget)
    initial = float(base.sigma)
    new, scores, maps = [], [], []
    for step in range(k):
        hm = heat_map(D, n, L, base=base, seed=seed, effort=effort, n_maps=n_maps,
                      resolve_fraction=resolve_fraction, resolve=resolve, prune=prune,
                      progress=(lambda d, t, s=step: progress(s, d, t)) if progress else None,
                      budget=budget)
        c = hm.argmin()
        new.append(c)
        scores.append(float(hm.values[c]))
        prev, base = base, hm.results.get(c)
        if base is None or float(base.sigma) < hm.values[c]:
            # the single-swap floor won: continue from a witness that attains it
            base = _swap_witness(D, n, L + [c], base or prev, budget)
        if budget is not None:
            # δ: a fresh search with the new landmark, warm-started from the heat map's maps
            # (module docstring, on ties): the next heat map starts from it
            fresh = search.witness_search(D, n_samples=n, landmarks=L + [c], seed=seed, effort=effort,
                                          starts=_maps_of(base, n_maps), budget=budget)
            base = fresh if float(fresh.sigma) > float(base.sigma) else base
        L.append(c)
        if keep_heat_maps:
            maps.append(hm)
        else:
            hm.results.clear()
    return {"landmarks": new, "scores": scores, "initial_score": initial, "heat_maps": maps,
            "witness": np.asarray(base.witness)}

"""Warm-started local search for the CNBS heat map.

One heat map needs a lower bound of σ (paper Eq. 5) with each of N candidate samples
fixed.  A fresh ``witness_search`` per candidate costs seconds at N = 400; here each
candidate instead starts from the previous step's best witness maps, repaired by one
move so that the candidate is fixed, and only the compiled local search of
``shapecond.symmetry._kernels`` is run (``WarmPolisher``).
"""

from __future__ import annotations

import math

import numpy as np

from ..symmetry import _kernels as K
from ..symmetry import objective as obj
from ..symmetry.search import DENSE_K, KEEP, MapPool, SearchResult, SearchStage, kick_limit
from ..symmetry.starts import repair
from ..threads import n_threads, thread_map


#: With a budget (the scale-aware score), a base map whose distances from the candidate p
#: are off by more than sqrt(HOPELESS) = 2 times the RMS budget once p is fixed is not
#: searched from: no nearby map is feasible with p fixed, and unwinding it costs O(N)
#: moves of O(N·M) each.  Values stay lower bounds (they come from the other maps).
HOPELESS = 4.0


def _used(t, m):
    used = np.zeros(m, dtype=bool)
    used[t] = True
    return used


class WarmPolisher:
    """Local search from repaired warm maps only (step 2 of ``cnbs``'s module docstring).

    ``witness_search`` always adds its own multistart families (seconds per call at
    N = 400 even with ``effort="quick"``), far too slow once per candidate.  This
    runs the search's compiled local search (``_kernels.local_search``) from the base
    maps repaired by one move.  The products G = D_XX D[T, :] and H of each base map
    are computed once per heat map; the repair move updates them by the rank-1
    formulas of ``objective.swap_delta`` / ``reassign_delta`` (O(N·M) instead of the
    O(N²·M) product), so a candidate costs a copy and a few local moves.  Values are
    re-scored exactly (``search.MapPool``).  Uses the search's ``SearchStage`` (for
    the dense-target neighbour lists) and ``MapPool``.
    """

    def __init__(self, D, n, maps, landmarks=(), budget=None):
        # the objective: σ² (ratio), or d² within a Dist² budget (the scale-aware score)
        self.budget = budget
        self.mode, self.s = (K.MODE_RATIO, 0.0) if budget is None else (K.MODE_BUDGET, float(budget))
        self.D = np.ascontiguousarray(np.asarray(D, dtype=np.float64))
        self.n = n = int(n)
        m = self.D.shape[0]
        allfree = np.arange(n, dtype=np.int64)
        self.stage = SearchStage(self.D, n, allfree, DENSE_K if m > n else 0)
        self.knn, self.floor = self.stage.knn, self.stage.floor
        # polish every base map once in the full space (maps from the bijection stage
        # of the search may not be local optima over dense targets yet), so that the
        # per-candidate searches start one move away from a local optimum
        lm = np.array(sorted(int(v) for v in landmarks), dtype=np.int64)
        space, goal = self.stage.space(np.setdiff1d(allfree, lm)), self.stage.goal(self.mode, self.s, lm)
        self.base, seen = [], set()
        for t in maps:
            t = repair(np.asarray(t, dtype=np.int64), n, m, lm)
            state = self.stage.start(t, lm)
            d2v, dist2v, _ = K.local_search(space, goal, state)
            key = t.tobytes()
            if key not in seen:
                seen.add(key)
                # the search leaves G at its starting map: the repairs need the product of t
                self.base.append((t, obj.cross_product(self.D, t), state.H, d2v, dist2v))

    def _repaired(self, b, p):
        """Copy of base state ``b`` with one move making T(p) = p (G, H kept exact)."""
        D, n = self.D, self.n
        t0, G0, H0, d2v, dist2v = self.base[b]
        t, G, H = t0.copy(), G0.copy(), H0.copy()
        used = _used(t, D.shape[0])
        if t[p] != p:
            pre = np.flatnonzero(t == p)
            if pre.size:
                q = int(pre[0])
                dd, dD = obj.swap_delta(D, t, G, p, q)
                K.apply_swap(D, n, t, G, p, q)
            else:
                dd, dD = obj.reassign_delta(D, t, G, H, p, p)
                K.apply_reassign(D, n, t, G, H, used, p, p)
            d2v, dist2v = d2v + dd, dist2v + dD
        return t, G, H, used, d2v, dist2v

    def __call__(self, landmarks, p, extra_starts=(), rng=None, n_kicks=0):
        """Best local optimum from the base maps repaired to fix ``p`` (SearchResult or None).

        Also from ``extra_starts`` (full G product each) and, with ``rng``, from
        ``n_kicks`` kicked copies of the repaired base maps (random swaps of free
        samples applied by rank-1 updates: the iterated-local-search re-solve).
        """
        return self.bounded(landmarks, p, extra_starts, rng, n_kicks)[0]

    def bounded(self, landmarks, p, extra_starts=(), rng=None, n_kicks=0, stop=math.inf):
        """As ``__call__``, but give up once some map fixing ``p`` scores above ``stop``.

        Returns ``(result, pruned)``.  With ``pruned`` True the search stopped early:
        ``result.sigma > stop`` is still a valid lower bound of σ with ``p`` fixed
        (its witness fixes ``p``), only not the best this search would have found.
        Used by the pruned CNBS heat map (``cnbs.heat_map(prune=True)``), where a
        candidate above the incumbent minimum cannot be the argmin.
        """
        run = _CandidateRun(self, landmarks, p, stop, rng)
        jobs = [(b, 0) for b in range(len(self.base))]
        if rng is not None and self.base:
            # kicks as large as the witness search's (``search.kick_limit``): up to N/8 (50 at N = 400)
            # cost 3.3x the time of a heat map on TOSCA cat0 for the same argmin, and of 15 CNBS
            # landmarks 2.4x for the same landmarks on wolf0 and centaur0 (cat0: the last three
            # differ, σ after 15 re-scored 0.317 against 0.316)
            hi = kick_limit(run.free.size)
            jobs += [(k % len(self.base), int(rng.integers(2, hi + 1))) for k in range(n_kicks)]
        pruned = run.run(run.starts(jobs, extra_starts))
        return self._result(run.found, run.lm), pruned

    def _result(self, found, anchors=()):
        """SearchResult of the best maps found, the best two re-scored exactly."""
        # rank by the tracked values (rank-1 updates, exact up to round-off); the best
        # two are re-scored exactly, so the reported σ is the exact σ of its witness
        n = self.n
        ranked = [it for it in sorted(found.values(), key=lambda it: -it[0]) if it[0] > 0][:KEEP]
        pool = MapPool(self.D, n, self.budget, anchors)
        for _, t in ranked[:2]:
            pool.add(t)
        exact = pool.top(2)
        if not exact or exact[0][0] <= 0.0:
            return None
        v, t, num, den = exact[0]
        maps = [t] + [u for _, u in ranked if u.tobytes() != t.tobytes()]
        sig = [math.inf if v == math.inf else math.sqrt(v)]
        sig += [math.inf if r == math.inf else math.sqrt(max(r, 0.0)) for r, u in ranked
                if u.tobytes() != t.tobytes()]
        return SearchResult(sigma=sig[0], witness=t, d2=num, dist2=den, maps=tuple(maps), sigmas=tuple(sig),
                            seconds=0.0)


class _CandidateRun:
    """The searches of ``WarmPolisher.bounded`` for one candidate ``p``: the maps they found
    (``found``: map bytes -> (tracked value, map)), in the order a serial loop takes them."""

    def __init__(self, polisher, landmarks, p, stop, rng):
        self.w, self.p, self.rng = polisher, p, rng
        self.lm = np.array(sorted(int(v) for v in landmarks), dtype=np.int64)
        self.free = np.setdiff1d(np.arange(polisher.n, dtype=np.int64), self.lm)
        self.stop2 = stop * stop  # the search compares σ² (inf stays inf)
        self.space = polisher.stage.space(self.free)
        self.goal = polisher.stage.goal(polisher.mode, polisher.s, self.lm, stop=self.stop2)
        self.found = {}

    def keep(self, t, d2v, dist2v, rows) -> bool:
        """Record the map ``t`` with its tracked value; True when that value is above ``stop``."""
        w = self.w
        if w.budget is not None:
            lb = self.goal.anchor_budget
            exc = max(dist2v - w.budget, 0.0) + float(np.sum(np.maximum(rows - lb, 0.0)))
            r = d2v if exc == 0.0 else -exc
        else:
            r = 0.0 if d2v <= 0.0 else (math.inf if dist2v <= w.floor else d2v / dist2v)
        self.found.setdefault(t.tobytes(), (r, t))
        return r > self.stop2

    def search(self, start):
        """The local search from one prepared start: (t, d², Dist², anchor rows)."""
        t, G, H, used, d2v, dist2v = start
        rows = obj.anchor_rows(self.w.D, t, self.lm)
        d2v, dist2v, _ = K.local_search(self.space, self.goal, K.MapState(t, G, H, used, rows, d2v, dist2v))
        return t, d2v, dist2v, rows

    def starts(self, jobs, extra_starts):
        """The starts in order: ("keep", state) for a base map still a local optimum with p
        fixed, ("search", state) for the others (repaired, kicked, or ``extra_starts``)."""
        w, p, lm, rng = self.w, self.p, self.lm, self.rng
        D, n, m = w.D, w.n, w.D.shape[0]
        for b, size in jobs:
            t0, G0, H0, d20, dist20 = w.base[b]
            if size == 0 and t0[p] == p and np.all(t0[lm] == lm):
                # still a local optimum with p fixed (for σ; with a budget, p's row may now break it)
                if w.budget is None:
                    yield "keep", (t0, d20, dist20, None)
                else:  # G is only read by the search
                    yield "search", (t0.copy(), G0, H0.copy(), _used(t0, m), d20, dist20)
                continue
            t, G, H, used, d2v, dist2v = w._repaired(b, p)
            if np.any(t[lm] != lm):
                continue  # a base map that moves a landmark (cannot happen for true warm maps)
            if w.budget is not None and obj.anchor_rows(D, t, [p])[0] > HOPELESS * self.goal.anchor_budget:
                continue  # p kills this map (see HOPELESS)
            for _ in range(size - 1):
                a, c = rng.choice(self.free, size=2, replace=False)
                dd, dD = obj.swap_delta(D, t, G, int(a), int(c))
                K.apply_swap(D, n, t, G, int(a), int(c))
                d2v, dist2v = d2v + dd, dist2v + dD
            yield "search", (t, G, H, used, d2v, dist2v)
        for t in extra_starts:
            t = repair(t, n, m, lm)
            yield "search", (t, D[:n, :n] @ D[t, :], np.sum(D[t, :] ** 2, axis=0), _used(t, m), obj.d2(D, t),
                             obj.dist2(D, t))

    def run(self, starts) -> bool:
        """Search from ``starts``, a few at once in parallel threads (``shapecond.threads``), their
        results taken in order up to the first above ``stop``: what a serial loop would keep.
        The kicks of the starts prepared beyond that one are undone in ``rng`` too (its state
        before each start is kept), so that it moves on exactly as in a serial loop.  True when
        stopped above ``stop``."""
        rng, k = self.rng, n_threads()
        while True:
            chunk, states = [], []
            for _ in range(k):
                states.append(None if rng is None else rng.bit_generator.state)
                st = next(starts, None)
                if st is None:
                    break
                chunk.append(st)
            if not chunk:
                return False
            done = iter(thread_map(self.search, [st for kind, st in chunk if kind == "search"]))
            for i, (kind, st) in enumerate(chunk):
                if self.keep(*(st if kind == "keep" else next(done))):
                    if rng is not None and i + 1 < len(chunk):
                        rng.bit_generator.state = states[i + 1]
                    return True

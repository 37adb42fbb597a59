"""Farthest-point sampling (FPS) under a chosen metric.

As in the paper, the first sample is the vertex farthest from a seeded random
vertex; each next sample is the vertex farthest from all samples so far.  User
landmarks come first, in the order given.  With a symmetry map, every sample is
added together with its mirror image so that the sample set is closed under the
map (symmetry-consistent sampling): the paper's bijection score is then
∞ for an exactly symmetric mesh.  When the solver computes many rows per solve,
the rows of the next steps are fetched ahead in blocks (``_Rows``); the samples
are exactly those of one row at a time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from tqdm import tqdm

from ..errors import InputError

#: Keep every source's full distance row (float32) when they fit in this many
#: bytes, so that D can be symmetrised as (D + Dᵀ)/2; beyond it, D[i, j] for
#: j < i comes from the later row only (the heat method is symmetric up to ~1 %).
ROW_BUDGET_BYTES = 512 * 2**20
#: Rows fetched ahead but not used yet are kept up to this many bytes (at least one block of them).
SPARE_BYTES = 128 * 2**20


@dataclass(frozen=True)
class FPSResult:
    """Samples in FPS order, their raw distance matrix and the Voronoi labels.

    Attributes
    ----------
    samples : (N,) int64 internal vertex indices, in sampling order.
    D : (N, N) float64 raw distances between the samples (symmetric, zero diagonal).
    min_dist : (n,) distance of every vertex to its closest sample.
    nearest : (n,) index into ``samples`` of every vertex's closest sample.
    rows : (N, n) float32 distances from every sample to every vertex, when kept (``keep_rows``), else None.
    """

    samples: np.ndarray
    D: np.ndarray
    min_dist: np.ndarray
    nearest: np.ndarray
    rows: np.ndarray | None = None


class _Front:
    """What FPS's next choice depends on: each vertex's distance to the nearest sample, and the samples.

    ``score`` is that distance with -inf at the samples, so that the next
    sample is its argmax.
    """

    def __init__(self, n: int):
        self.score = np.full(n, np.inf)
        self.is_sample = np.zeros(n, dtype=bool)
        self.count = 0

    def copy(self) -> "_Front":
        other = _Front.__new__(_Front)
        other.score, other.is_sample, other.count = self.score.copy(), self.is_sample.copy(), self.count
        return other

    def take(self, v: int, row: np.ndarray) -> None:
        np.minimum(self.score, row, out=self.score)
        self.score[v] = -np.inf
        self.is_sample[v] = True
        self.count += 1

    @property
    def min_dist(self) -> np.ndarray:
        return np.maximum(self.score, 0.0)  # a sample is at distance 0 from itself


def _farthest_order(front: _Front, boundaries, symmetry, row_of):
    """Yield the vertices FPS takes from ``front`` on, taking each with its row ``row_of(v)``.

    The one definition of the order, used both for the real sampling and, with
    guessed rows, to foresee which rows the next steps will need.
    """
    n = front.min_dist.size
    for stop in boundaries:
        while front.count < stop:
            cand = front.score
            if symmetry is not None and stop - front.count == 1:
                # one slot left: only a self-symmetric vertex keeps closure
                cand = np.where(symmetry == np.arange(n), cand, -np.inf)
                if not np.isfinite(cand.max()):
                    raise InputError("the symmetry map has no self-symmetric vertex: use an even number of points")
            v = int(np.argmax(cand))
            front.take(v, row_of(v))
            yield v
            if symmetry is not None and not front.is_sample[symmetry[v]]:
                w = int(symmetry[v])
                front.take(w, row_of(w))
                yield w


class _Rows:
    """Rows of the solver, fetched ahead in blocks of ``solver.block``.

    FPS is sequential: the next sample depends on the row of the last one.  When
    the solver solves many sources together, the rows of the next steps are
    fetched together with the one needed now, foreseen by running the same FPS
    order on straight-line distances (``solver.guess``).  The order itself is
    always decided on the true rows, so the samples are exactly those of
    one-at-a-time FPS; a wrong guess only costs a row computed for nothing
    (about 3 % extra rows at M = 3,200 on TOSCA cat0, with 16 per block).
    """

    def __init__(self, solver):
        self.solver = solver
        self.block = int(getattr(solver, "block", 1))
        self.spare: dict[int, np.ndarray] = {}
        self.computed = 0

    def fetch(self, vertices) -> None:
        todo = [v for v in dict.fromkeys(int(x) for x in vertices) if v not in self.spare]
        if todo:
            for v, row in zip(todo, self.solver.distances(todo)):
                self.spare[v] = row
            self.computed += len(todo)
        keep = max(self.block, SPARE_BYTES // (8 * self.solver.n))
        for v in list(self.spare)[: max(0, len(self.spare) - keep - len(todo))]:
            del self.spare[v]  # the oldest wrong guesses: bounded memory

    def get(self, v: int, front: _Front, boundaries, symmetry) -> np.ndarray:
        if v not in self.spare:
            wanted = [v]
            if self.block > 1:
                ahead = front.copy()
                ahead.take(v, self.solver.guess(v))
                for w in _farthest_order(ahead, boundaries, symmetry, self.solver.guess):
                    if len(wanted) >= self.block:
                        break
                    wanted.append(w)
            self.fetch(wanted)
        return self.spare.pop(v)


def _checked_request(n: int, n_samples: int, landmarks) -> list[int]:
    """The landmarks as ints, once ``n_samples`` samples with them are possible among ``n`` vertices."""
    if n_samples < 3:
        raise InputError(f"at least 3 samples are needed, got {n_samples}")
    if n_samples > n:
        raise InputError(f"cannot take {n_samples} samples from {n} vertices")
    landmarks = [int(v) for v in landmarks]
    if len(set(landmarks)) != len(landmarks):
        raise InputError("landmarks are repeated")
    if len(landmarks) > n_samples:
        raise InputError(f"{len(landmarks)} landmarks but only {n_samples} samples requested")
    return landmarks


def farthest_point_sampling(solver, n_samples: int, landmarks=(), seed: int = 0,
                            symmetry=None, stops=(), progress: bool = False,
                            keep_rows: bool | None = None) -> FPSResult:
    """Sample ``n_samples`` vertices by FPS with distances from ``solver``.

    Parameters
    ----------
    solver : DistanceSolver
        Anything with ``.n`` and ``.distances(sources) -> (k, n)``; with
        ``.block > 1`` and ``.guess(v)`` rows are fetched ahead in blocks
        (same samples, fewer solves).
    n_samples : int
    landmarks : sequence of int
        Internal vertex indices placed first, in order.
    seed : int
        Seed of the random start vertex (scikit-learn's ``random_state`` idea).
    symmetry : (n,) int array or None
        Mirror image of each vertex; samples are then added in mirror pairs.
    stops : sequence of int
        Prefix sizes that must also be closed under ``symmetry`` (e.g. N when
        sampling M = 8N dense targets whose first N are the samples).
    keep_rows : bool or None
        Keep every sample's distance row (float32) and return them as
        ``FPSResult.rows``; None: only when they fit in ``ROW_BUDGET_BYTES``
        (and then only to symmetrise ``D``).
    """
    n = solver.n
    landmarks = _checked_request(n, n_samples, landmarks)
    if symmetry is not None:
        symmetry = np.asarray(symmetry, dtype=np.int64)
    wanted = keep_rows
    if keep_rows is None:
        keep_rows = n_samples * n * 4 <= ROW_BUDGET_BYTES
    rows = np.empty((n_samples, n), dtype=np.float32) if keep_rows else None
    D = np.zeros((n_samples, n_samples))
    samples: list[int] = []
    nearest = np.zeros(n, dtype=np.int64)
    front = _Front(n)
    source = _Rows(solver)
    boundaries = sorted({int(s) for s in stops if 0 < s < n_samples} | {n_samples})
    bar = tqdm(total=n_samples, desc="sampling", unit="pt", disable=not progress or None, leave=False)

    def row_of(v: int) -> np.ndarray:
        row = source.get(v, front, boundaries, symmetry)
        k = len(samples)
        if rows is not None:
            rows[k] = row  # D is symmetrised from the kept rows at the end
        elif k:
            D[k, :k] = D[:k, k] = row[samples]
        nearest[row < front.score] = k
        samples.append(v)
        bar.update(1)
        return row

    source.fetch(landmarks)
    for v in landmarks:
        front.take(v, row_of(v))
    if symmetry is not None:
        for v in landmarks:
            if not front.is_sample[symmetry[v]] and len(samples) < n_samples:
                front.take(int(symmetry[v]), row_of(int(symmetry[v])))
    if not samples:
        rng = np.random.default_rng(seed)
        start = solver.distances([int(rng.integers(n))])[0]
        first = int(np.argmax(start))
        front.take(first, row_of(first))
        if symmetry is not None and not front.is_sample[symmetry[first]]:
            front.take(int(symmetry[first]), row_of(int(symmetry[first])))
    for _ in _farthest_order(front, boundaries, symmetry, row_of):
        pass
    bar.close()
    idx = np.asarray(samples, dtype=np.int64)
    if rows is not None:
        D = rows[:, idx].astype(np.float64)
        D = 0.5 * (D + D.T)
        np.fill_diagonal(D, 0.0)
    return FPSResult(idx, D, front.min_dist, nearest, rows if wanted else None)

"""Farthest-point sampling (FPS) under a chosen metric.

As in the paper, the first sample is the vertex farthest from a seeded random
vertex; each next sample is the vertex farthest from all samples so far.  User
landmarks come first, in the order given.  With a symmetry map, every sample is
added together with its mirror image so that the sample set is closed under the
map (symmetry-consistent sampling): the paper's bijection score is then
∞ for an exactly symmetric mesh.
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


@dataclass(frozen=True)
class FPSResult:
    """Samples in FPS order, their raw distance matrix and the Voronoi labels.

    Attributes
    ----------
    samples : (N,) int64 internal vertex indices, in sampling order.
    D : (N, N) float64 raw distances between the samples (symmetric, zero diagonal).
    min_dist : (n,) distance of every vertex to its closest sample.
    nearest : (n,) index into ``samples`` of every vertex's closest sample.
    """

    samples: np.ndarray
    D: np.ndarray
    min_dist: np.ndarray
    nearest: np.ndarray


def farthest_point_sampling(solver, n_samples: int, landmarks=(), seed: int = 0,
                            symmetry=None, stops=(), progress: bool = False) -> FPSResult:
    """Sample ``n_samples`` vertices by FPS with distances from ``solver``.

    Parameters
    ----------
    solver : DistanceSolver
        Anything with ``.n`` and ``.distances(sources) -> (k, n)``.
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
    """
    n = solver.n
    if n_samples < 3:
        raise InputError(f"at least 3 samples are needed, got {n_samples}")
    if n_samples > n:
        raise InputError(f"cannot take {n_samples} samples from {n} vertices")
    landmarks = [int(v) for v in landmarks]
    if len(set(landmarks)) != len(landmarks):
        raise InputError("landmarks are repeated")
    if len(landmarks) > n_samples:
        raise InputError(f"{len(landmarks)} landmarks but only {n_samples} samples requested")
    keep_rows = n_samples * n * 4 <= ROW_BUDGET_BYTES
    rows = np.empty((n_samples, n), dtype=np.float32) if keep_rows else None
    D = np.zeros((n_samples, n_samples))
    samples: list[int] = []
    min_dist = np.full(n, np.inf)
    nearest = np.zeros(n, dtype=np.int64)
    is_sample = np.zeros(n, dtype=bool)
    bar = tqdm(total=n_samples, desc="sampling", unit="pt", disable=not progress or None, leave=False)

    def add(v: int) -> None:
        row = solver.distances([v])[0]
        k = len(samples)
        if rows is not None:
            rows[k] = row  # D is symmetrised from the kept rows at the end
        elif k:
            D[k, :k] = D[:k, k] = row[samples]
        closer = row < min_dist
        min_dist[closer] = row[closer]
        nearest[closer] = k
        samples.append(v)
        is_sample[v] = True
        bar.update(1)

    for v in landmarks:
        add(v)
    if symmetry is not None:
        symmetry = np.asarray(symmetry, dtype=np.int64)
        for v in landmarks:
            if not is_sample[symmetry[v]] and len(samples) < n_samples:
                add(int(symmetry[v]))
    if not samples:
        rng = np.random.default_rng(seed)
        start = solver.distances([int(rng.integers(n))])[0]
        add(int(np.argmax(start)))
        if symmetry is not None and not is_sample[symmetry[samples[0]]]:
            add(int(symmetry[samples[0]]))
    boundaries = sorted({int(s) for s in stops if 0 < s < n_samples} | {n_samples})
    for stop in boundaries:
        while len(samples) < stop:
            cand = np.where(is_sample, -np.inf, min_dist)
            if symmetry is None:
                add(int(np.argmax(cand)))
                continue
            if stop - len(samples) == 1:  # one slot left: only a self-symmetric vertex keeps closure
                cand = np.where(symmetry == np.arange(n), cand, -np.inf)
                if not np.isfinite(cand.max()):
                    raise InputError("the symmetry map has no self-symmetric vertex: use an even number of points")
            v = int(np.argmax(cand))
            add(v)
            if not is_sample[symmetry[v]]:
                add(int(symmetry[v]))
    bar.close()
    idx = np.asarray(samples, dtype=np.int64)
    if rows is not None:
        D = rows[:, idx].astype(np.float64)
        D = 0.5 * (D + D.T)
        np.fill_diagonal(D, 0.0)
    return FPSResult(idx, D, min_dist, nearest)

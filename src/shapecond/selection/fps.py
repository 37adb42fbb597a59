"""Farthest point sampling of landmarks (the baseline of paper Section 7).

The paper's start: the first landmark is the sample farthest from a seeded random
sample; each next one is the sample farthest (in D) from those chosen so far.  On a
``MetricShape`` built by FPS with the same seed this reproduces a prefix of the
sample order; it is recomputed here from ``D`` so that it also works on matrices
and with pre-fixed landmarks.
"""

from __future__ import annotations

import numpy as np

from ..checks import check_landmark_count


def fps_landmarks(D: np.ndarray, n_samples: int, k: int, seed: int = 0, fixed=()) -> list[int]:
    """``k`` sample indices by farthest point sampling over the first ``n_samples`` rows of D.

    Parameters
    ----------
    D : (M, M) array, distances (the samples are the first ``n_samples`` points).
    n_samples : int
    k : int, number of landmarks to add.
    seed : int, chooses the random starting point (paper: farthest from a random point).
    fixed : sample indices already chosen; the new ones are farthest from them too
        and the seeded start is skipped.

    Returns
    -------
    list of int, the new landmarks in order.
    """
    n = int(n_samples)
    fixed = check_landmark_count(k, n, fixed)
    Dx = np.asarray(D, dtype=float)[:n, :n]
    chosen: list[int] = []
    if fixed:
        mind = Dx[fixed].min(axis=0)
    elif k:
        r = int(np.random.default_rng(seed).integers(n))
        first = int(np.argmax(Dx[r]))
        chosen.append(first)
        mind = Dx[first].copy()
    else:
        return []
    while len(chosen) < k:
        mind[fixed + chosen] = -1.0
        nxt = int(np.argmax(mind))
        chosen.append(nxt)
        mind = np.minimum(mind, Dx[nxt])
    return chosen

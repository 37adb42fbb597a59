"""The single-swap floor of a CNBS heat map (step 3 of ``cnbs``): a lower bound for every candidate at once.

A single swap (a b) of two samples, the identity elsewhere, is a map of the problem with the landmarks
``L`` and a candidate ``p`` fixed when it moves none of them and, on the scale-aware score δ(ε)
(``symmetry.scale``), stays within its budget: Dist² within the budget and every fixed point's distance
row within budget / N (``objective.anchor_rows``).  The best such swap is a value some map of the
candidate's problem reaches, so the heat map's value of p is never below it.  One O(N³) table of
every swap's value serves every candidate (``swap_table``); on σ the best swap avoiding ``p`` is the
table's best unless p is one of its two samples (``best_swap_avoiding``), on δ(ε) p's own row must
be checked swap by swap (``best_swap_within``).
"""

from __future__ import annotations

import numpy as np

from ..symmetry.objective import isometry_floor, swap_terms

#: Swaps looked at a time for every candidate by ``best_swap_within``.
SWAP_CHUNK = 256


def swap_scores(D: np.ndarray, n: int) -> np.ndarray:
    """σ of every single swap (a b) of the identity on the samples: (n, n), 0 on the diagonal.

    σ_ab = sqrt(d² / Dist²) of the swap (Eq. 5) from ``objective.swap_terms``; a swap
    with round-off distortion (``objective.isometry_floor``) scores inf.
    """
    Dx = np.asarray(D, float)[:n, :n]
    d2, dist2 = swap_terms(Dx, np.arange(n))
    iso = dist2 <= isometry_floor(Dx)  # round-off distortion: an isometry
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sqrt(d2 / np.where(iso, 1.0, dist2))
    s[iso & (d2 > 0)] = np.inf
    np.fill_diagonal(s, 0.0)
    return s


def swap_table(D: np.ndarray, n: int, budget=None, landmarks=()) -> np.ndarray:
    """Value of every single swap (a b) in the units of the heat map: σ (``swap_scores``),
    or with a Dist² ``budget`` sqrt(d²) = sqrt(2)·D[a,b] for the swaps within it whose distance
    rows at the ``landmarks`` stay within budget / n too, and 0 for the others.

    The row of a landmark l under the swap (a b) (``objective.anchor_rows``) is
    2 (D[l,a] − D[l,b])²: a swap within the Dist² budget can break it (δ(ε)'s problem,
    ``symmetry.scale``), and is then no map of the problem with l fixed.
    """
    if budget is None:
        return swap_scores(D, n)
    Dx = np.asarray(D, float)[:n, :n]
    num, den = swap_terms(Dx, np.arange(n))
    ok = den <= budget
    for l in landmarks:
        ok &= 2.0 * (Dx[l][:, None] - Dx[l][None, :]) ** 2 <= budget / n
    S = np.where(ok, np.sqrt(num), 0.0)
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


def best_swap_within(S: np.ndarray, D: np.ndarray, fixed, candidates, row_budget: float) -> np.ndarray:
    """For each candidate p, the best value of ``S`` (``swap_table`` with a budget and the landmarks
    ``fixed``) over the swaps (a b) avoiding ``fixed`` ∪ {p} whose row at p, 2 (D[p,a] − D[p,b])²,
    stays within ``row_budget``: the single-swap floor of δ(ε) with p added as a landmark (0 if none).

    The swaps are walked best first, ``SWAP_CHUNK`` at a time for every candidate still without
    one: O(N) a candidate and swap looked at, most candidates settled by the first chunk.
    """
    S = np.array(S, dtype=float, copy=True)
    fixed = list(fixed)
    S[fixed, :] = 0.0
    S[:, fixed] = 0.0
    a, b = np.nonzero(S > 0.0)
    v = S[a, b]
    order = np.lexsort((b, a, -v))  # best first; ties by index, deterministic
    a, b, v = a[order], b[order], v[order]
    cand = np.asarray(list(candidates), dtype=np.int64)
    out = np.zeros(cand.size)
    todo = np.arange(cand.size)
    for k0 in range(0, v.size, SWAP_CHUNK):
        if todo.size == 0:
            break
        pa, pb, p = a[k0:k0 + SWAP_CHUNK], b[k0:k0 + SWAP_CHUNK], cand[todo][:, None]
        ok = (2.0 * (D[p, pa] - D[p, pb]) ** 2 <= row_budget) & (p != pa) & (p != pb)
        hit = ok.any(axis=1)
        out[todo[hit]] = v[k0 + np.argmax(ok[hit], axis=1)]
        todo = todo[~hit]
    return out


def swap_floor(D: np.ndarray, n: int, landmarks, candidates, budget=None) -> np.ndarray:
    """Step 3 of the heat map: for each candidate p, the best single swap of samples avoiding the
    ``landmarks`` ∪ {p}, in the heat map's units (``swap_table``), a lower bound of its value: on σ
    any such swap (``best_swap_avoiding``); with a budget only those within it, the landmarks' and
    p's distance rows included (``best_swap_within``)."""
    if budget is None:
        return best_swap_avoiding(swap_scores(D, n), landmarks, candidates)
    S = swap_table(D, n, budget, landmarks)
    return best_swap_within(S, np.asarray(D, float), landmarks, candidates, budget / n)

"""The objective of the global symmetry score (paper Section 4, Eqs. 2, 3 and 5).

A metric shape is a distance matrix ``D`` over a point set ``Y`` (``M`` points)
whose first ``N`` points are the samples ``X``.  A *map* is an int array ``t``
of length ``N`` with ``T(x) = t[x]``, injective into ``range(M)``.  With
``M == N`` a map is a permutation of the samples: the paper's bijections.  With
``M > N`` the samples may land on the denser targets of ``Y`` (the dense-target
score); the formulas below are the same.

    d²(T)    = Σ_x D[x, T x]²                                  (Eq. 2, L²)
    Dist²(T) = Σ_{x,x'} (D[x, x'] − D[T x, T x'])²             (Eq. 3, L²)
    σ_T      = sqrt(d²(T) / Dist²(T))                          (Eq. 5)

Both sums run over ordered pairs (each unordered pair counts twice), as in
``‖D − P D Pᵀ‖²_F`` for a permutation matrix ``P``.

Incremental form used by the search.  Write
``Dist² = C_X + C_T − 2 S`` with ``C_X = Σ D[x,x']²`` (fixed),
``C_T = Σ D[Tx,Tx']²`` and ``S = Σ D[x,x'] D[Tx,Tx']``, and keep

    G[x, y] = Σ_{x'} D[x, x'] D[T x', y]      (N × M, ``cross_product``)
    H[y]    = Σ_{x'} D[T x', y]²              (M,     ``image_energy``)

so that ``S = Σ_x G[x, T x]`` and a swap or a reassignment changes ``Dist²`` by
a closed form in O(1) (``swap_delta``, ``reassign_delta``).  Swaps of the identity
have their own closed form, all pairs at once (``swap_terms``).
"""

from __future__ import annotations

import math

import numpy as np

from ..checks import check_distance_matrix
from ..errors import InputError

#: A map whose distortion is below this fraction of the shape's own size is an
#: isometry: ``sqrt(Dist²(T)) <= ISOMETRY_RTOL * ‖D_XX‖_F`` gives σ = ∞.
#: Round-off alone stays below 1e-13, but meshes are stored with 6-7 significant
#: digits (float32, ASCII OFF), so the distances of an exactly symmetric mesh carry
#: relative errors of about 1e-7: the mirror map of TOSCA's cat0 (a mirror-
#: symmetric triangulation) distorts its geodesic matrix by 2e-8.  An asymmetry
#: below one part in a million is below what such data can show, so it counts as
#: an isometry; anything larger is reported as a finite score.
ISOMETRY_RTOL = 1e-6


def check_instance(D, n_samples=None, landmarks=()):
    """Validate a score instance; return ``(D, N, sorted landmarks)``.

    ``D`` goes through ``checks.check_distance_matrix`` (square, real, finite,
    non-negative, symmetric, zero diagonal; a matrix that passed before is
    accepted in O(1)); ``N`` must lie in ``[2, M]`` and the landmarks be distinct
    sample indices.  Every score function calls this first, so an invalid
    matrix never yields a number.
    """
    D = check_distance_matrix(D)
    M = D.shape[0]
    if n_samples is None:
        n = M
    else:
        if isinstance(n_samples, (bool, np.bool_)) or not isinstance(n_samples, (int, np.integer)):
            raise InputError(f"the number of samples must be an integer, got {n_samples!r}")
        n = int(n_samples)
    if n < 2 or n > M:
        raise InputError(f"the number of samples must be in [2, {M}], got {n}")
    try:
        L = np.asarray(list(landmarks), dtype=np.int64).ravel()
    except (TypeError, ValueError, OverflowError):
        raise InputError("landmarks must be sample indices (integers)") from None
    if L.size and (L.min() < 0 or L.max() >= n):
        bad = int(L[(L < 0) | (L >= n)][0])
        raise InputError(f"landmark {bad} is not a sample index in [0, {n})")
    if np.unique(L).size != L.size:
        raise InputError("landmarks are repeated")
    return D, n, np.sort(L)


def _as_map(D: np.ndarray, t) -> np.ndarray:
    t = np.asarray(t, dtype=np.int64)
    if t.ndim != 1 or t.size > D.shape[0]:
        raise ValueError("a map must be a 1-D array of at most M target indices")
    return t


def d2(D: np.ndarray, t) -> float:
    """Squared L² displacement d²(T) = Σ_x D[x, T x]² (Eq. 2 with p = 2)."""
    t = _as_map(D, t)
    return float(np.sum(D[np.arange(t.size), t] ** 2))


def image_block(D: np.ndarray, t) -> np.ndarray:
    """D[T x, T x'] for every pair of samples, shape (n, n): ``D[np.ix_(t, t)]``.

    A C-contiguous ``D`` is read by one flat ``take`` (the same entries, 3x faster at
    N = 400, M = 3,200 than the fancy index, whose general machinery dominated the exact
    re-scoring of every map the witness search and the CNBS heat map find).
    """
    t = _as_map(D, t)
    if D.flags.c_contiguous:
        return D.reshape(-1).take(t[:, None] * D.shape[1] + t)
    return D[np.ix_(t, t)]


def dist2(D: np.ndarray, t) -> float:
    """Squared L² distortion Dist²(T) = Σ_{x,x'} (D[x,x'] − D[Tx,Tx'])² (Eq. 3, p = 2)."""
    t = _as_map(D, t)
    n = t.size
    return float(np.sum((D[:n, :n] - image_block(D, t)) ** 2))


def anchor_rows(D: np.ndarray, t, anchors) -> np.ndarray:
    """Σ_x (D[l, x] − D[l, T x])² for every anchor ``l`` (a landmark, T(l) = l): how much the
    map distorts the distances to each landmark (the rows of Dist² at the landmarks)."""
    t = _as_map(D, t)
    a = np.asarray(anchors, dtype=np.int64)
    if a.size == 0:
        return np.zeros(0)
    n = t.size
    return np.sum((D[np.ix_(a, np.arange(n))] - D[np.ix_(a, t)]) ** 2, axis=1)


def isometry_floor(D, n: int | None = None) -> float:
    """The largest Dist² that is round-off: ``ISOMETRY_RTOL² · ‖D_XX‖²_F`` over the first ``n`` points.

    A map whose distortion (Eq. 3) is at most this is an isometry (σ = ∞, Eq. 5); every
    decision "is this map an isometry?" compares against this one number.
    """
    D = np.asarray(D, dtype=np.float64)
    n = D.shape[0] if n is None else n
    return (ISOMETRY_RTOL**2) * float(np.sum(D[:n, :n] ** 2))


def is_isometry(D: np.ndarray, dist2_value: float, n: int | None = None) -> bool:
    """True when a distortion ``dist2_value`` is round-off (``isometry_floor``)."""
    return dist2_value <= isometry_floor(D, n)


def map_score(D: np.ndarray, t) -> float:
    """σ_T = sqrt(d²(T) / Dist²(T)) of one map; ``inf`` for a non-identity isometry.

    The identity (d² = 0) scores 0 by convention: it is excluded from the sup of
    Eq. 5 and never a witness.
    """
    t = _as_map(D, t)
    num = d2(D, t)
    if num == 0.0:
        return 0.0
    den = dist2(D, t)
    if is_isometry(D, den, t.size):
        return math.inf
    return math.sqrt(num / den)


def cross_product(D: np.ndarray, t) -> np.ndarray:
    """G[x, y] = Σ_{x'} D[x, x'] D[T x', y], shape (N, M)."""
    t = _as_map(D, t)
    n = t.size
    return D[:n, :n] @ D[t, :]


def image_energy(D: np.ndarray, t) -> np.ndarray:
    """H[y] = Σ_{x'} D[T x', y]², shape (M,)."""
    t = _as_map(D, t)
    return np.sum(D[t, :] ** 2, axis=0)


def swap_delta(D: np.ndarray, t, G: np.ndarray, a: int, b: int) -> tuple[float, float]:
    """Change of (d², Dist²) when T(a) and T(b) are exchanged, in O(1) given ``G``.

    With ``ta = T a`` and ``tb = T b``::

        ΔS     = 2 (G[a,tb] − G[a,ta] − G[b,tb] + G[b,ta] + 2 D[a,b] D[ta,tb])
        ΔDist² = −2 ΔS          (C_T does not change under a swap)
    """
    ta, tb = int(t[a]), int(t[b])
    dd2 = D[a, tb] ** 2 + D[b, ta] ** 2 - D[a, ta] ** 2 - D[b, tb] ** 2
    dS = 2.0 * (G[a, tb] - G[a, ta] - G[b, tb] + G[b, ta] + 2.0 * D[a, b] * D[ta, tb])
    return float(dd2), float(-2.0 * dS)


def reassign_delta(D: np.ndarray, t, G: np.ndarray, H: np.ndarray, a: int, y: int) -> tuple[float, float]:
    """Change of (d², Dist²) when T(a) moves to a target ``y`` outside the image.

    ::

        ΔS     = 2 (G[a,y] − G[a,ta])
        ΔC_T   = 2 (H[y] − D[ta,y]² − H[ta])
        ΔDist² = ΔC_T − 2 ΔS
    """
    ta = int(t[a])
    dd2 = D[a, y] ** 2 - D[a, ta] ** 2
    dS = 2.0 * (G[a, y] - G[a, ta])
    dC = 2.0 * (H[y] - D[ta, y] ** 2 - H[ta])
    return float(dd2), float(dC - 2.0 * dS)


def swap_terms(X: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(d², Dist²) of every swap (a b) of two free samples, as |free| × |free| tables.

    The identity with ``a`` and ``b`` exchanged has (Eqs. 2 and 3, ordered pairs)::

        d²    = 2 X[a,b]²
        Dist² = 4 Σ_{x ≠ a,b} (X[x,a] − X[x,b])² = 4 (K[a,a] + K[b,b] − 2 K[a,b] − 2 X[a,b]²)

    with ``K = X X`` (``X`` = D over the samples, symmetric): all pairs from one O(N³)
    product.  The diagonal is (0, 0).  The best single swap, the swap floor of σ and of
    every CNBS heat map, reads this table.
    """
    Kx = X @ X
    dg = np.diag(Kx)
    Xf = X[np.ix_(free, free)]
    Q = dg[free][:, None] + dg[free][None, :] - 2.0 * Kx[np.ix_(free, free)] - 2.0 * Xf**2
    return 2.0 * Xf**2, 4.0 * np.maximum(Q, 0.0)

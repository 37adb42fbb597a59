"""Extremal points of the heat kernel signature (a baseline of paper Section 7).

The heat kernel signature (Sun, Ovsjanikov, Guibas 2009) of a vertex at time t is
HKS(x, t) = Σ_i exp(−λ_i t) φ_i(x)², with (λ_i, φ_i) the eigenpairs of L φ = λ A φ.
Its local maxima at a moderate time sit on the tips of protrusions (feet, tail,
head, fingers), the classical feature points for landmark-based matching.

Choices (the paper leaves them open):

* operator: on a mesh, the first ``n_eigs = 30`` eigenpairs of the shape's one
  Laplace–Beltrami basis (``shapes.laplace``: robust-laplacian's intrinsic Delaunay
  cotan Laplacian and lumped areas, total area 1, so times are scale-free; cached, and
  shared with the dense stage of matching).  Point clouds and distance matrices have no
  mesh: a Gaussian-kernel graph Laplacian on the samples (symmetric normalisation,
  ε = mean distance to the 8th nearest sample) stands in for it.
* time: ``t = exp(log t_min + time_fraction · (log t_max − log t_min))`` with Sun et
  al.'s range t_min = 4 ln 10 / λ_max, t_max = 4 ln 10 / λ_1 and
  ``time_fraction = 0.3`` (on TOSCA cats and dogs this lights up the four feet,
  tail and head and nothing on the body; 0.1 is noisier, 0.6 keeps only the tail).
* extremal point: a vertex whose HKS is at least that of every vertex of its 2-ring
  (mesh) or of its 8 nearest samples (graph); ordered by decreasing HKS; each is
  replaced by the sample standing for it and repeats are dropped.
* fewer maxima than requested: the rest are filled by farthest point sampling from
  those found (documented fallback, reported in ``hks_landmarks``'s second value).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from ..shapes.laplace import DEFAULT_EIGENPAIRS, laplace_basis
from .fps import fps_landmarks
from .result import sample_of_vertex


def heat_kernel_signature(evals: np.ndarray, evecs: np.ndarray, t: float) -> np.ndarray:
    """HKS(x, t) = Σ_i exp(−λ_i t) φ_i(x)² for every row x of ``evecs``."""
    return (evecs**2 * np.exp(-evals * t)).sum(axis=1)


def _mesh_spectrum(geometry, n_eigs):
    basis = laplace_basis(geometry, max(n_eigs, DEFAULT_EIGENPAIRS))
    return basis.evals[:n_eigs], basis.evecs[:, :n_eigs]


def _graph_spectrum(D, n_eigs, knn=8):
    n = D.shape[0]
    kk = min(knn, n - 1)
    eps = float(np.mean(np.sort(D, axis=1)[:, kk])) or 1.0
    W = np.exp(-((D / eps) ** 2))
    deg = W.sum(axis=1)
    S = W / np.sqrt(np.outer(deg, deg))
    w, U = np.linalg.eigh(np.eye(n) - S)
    k = min(n_eigs, n)
    return np.clip(w[:k], 0.0, None), U[:, :k] / np.sqrt(deg)[:, None] * math.sqrt(deg.sum())


def _time(evals, fraction):
    pos = evals[evals > 1e-9 * max(evals.max(), 1e-300)]
    if pos.size < 2:
        raise InputError("the shape's Laplacian has too few non-zero eigenvalues for a heat kernel signature")
    lo, hi = math.log(4 * math.log(10) / pos.max()), math.log(4 * math.log(10) / pos.min())
    return math.exp(lo + fraction * (hi - lo))


def _local_maxima(h, neighbourhood: sp.csr_matrix) -> np.ndarray:
    nb = neighbourhood.tocsr()
    nmax = np.full(h.size, -np.inf)
    rows = np.flatnonzero(np.diff(nb.indptr))
    vals = np.maximum.reduceat(h[nb.indices], nb.indptr[rows]) if nb.nnz else np.zeros(0)
    nmax[rows] = vals
    peaks = np.flatnonzero(h >= nmax)
    return peaks[np.argsort(-h[peaks], kind="stable")]


@dataclass(frozen=True)
class HKSOptions:
    """The options of ``hks_landmarks``.

    Attributes
    ----------
    time_fraction : the diffusion time of the signature, as a fraction of the spectrum's time range (``_time``).
    n_eigs : eigenpairs of the Laplacian the signature is summed over.
    """

    time_fraction: float = 0.3
    n_eigs: int = 30


def hks_landmarks(shape, k: int, seed: int = 0, options: HKSOptions = HKSOptions()):
    """``k`` sample indices at extremal points of the HKS, by decreasing value (FPS from ``seed`` fills up).

    Returns
    -------
    (list of int, int)
        The landmarks and how many of them are HKS maxima (the rest filled by FPS).
    """
    n = int(shape.n_samples)
    time_fraction, n_eigs = options.time_fraction, options.n_eigs
    if not 1 <= k <= n:
        raise InputError(f"cannot choose {k} landmarks among {n} samples")
    if not 0.0 <= time_fraction <= 1.0:
        raise InputError("the HKS time fraction must lie in [0, 1]")
    if not (isinstance(n_eigs, (int, np.integer)) and n_eigs >= 2):
        raise InputError(f"n_eigs must be an integer >= 2, got {n_eigs!r}")
    g = shape.geometry
    if g is not None and g.faces is not None:
        V, F = np.asarray(g.vertices, float), np.asarray(g.faces)
        w, U = _mesh_spectrum(g, n_eigs)
        h = heat_kernel_signature(w, U, _time(w, time_fraction))
        nv = V.shape[0]
        i, j = F.ravel(), np.roll(F, 1, axis=1).ravel()
        A = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(nv, nv)).tocsr()
        A = ((A + A.T) > 0).astype(np.int8)
        ring2 = ((A @ A + A) > 0).tocsr()
        ring2.setdiag(0)
        ring2.eliminate_zeros()
        peaks = [sample_of_vertex(shape, int(v)) for v in _local_maxima(h, ring2)]
    else:
        Dx = np.asarray(shape.D, float)[:n, :n]
        w, U = _graph_spectrum(Dx, n_eigs)
        h = heat_kernel_signature(w, U, _time(w, time_fraction))
        kk = min(8, n - 1)
        nbr = np.argsort(Dx, axis=1)[:, 1 : kk + 1]
        nb = sp.csr_matrix((np.ones(nbr.size), (np.repeat(np.arange(n), kk), nbr.ravel())), shape=(n, n))
        peaks = [int(v) for v in _local_maxima(h, nb)]
    chosen: list[int] = []
    for p in peaks:
        if p not in chosen:
            chosen.append(p)
        if len(chosen) == k:
            break
    n_peaks = len(chosen)
    if n_peaks < k:
        chosen += fps_landmarks(shape.D, n, k - n_peaks, seed=seed, fixed=chosen)
    return chosen, n_peaks

"""Seeded graph matching: FAQ with the landmarks as seeds.

The second matcher, so users see whether good landmarks still help a modern
quadratic-assignment solver.  ``scipy.optimize.quadratic_assignment`` with
``method="faq"`` (Vogelstein et al. 2015, Frank–Wolfe on the doubly stochastic
relaxation) and ``partial_match`` = the landmark pairs (Fishkind et al. 2019,
seeded graph matching).  Direction: **source to target**, ``t[x] = col_ind[x]``.

Exact objective, maximised over permutations ``T`` fixing the landmarks::

    objective="distance":  S(T) = Σ_{x,x'} D_s[x, x'] · D_t[T x, T x']
    objective="gaussian":  Σ_{x,x'} K_s[x, x'] · K_t[T x, T x'],   K = exp(-D² / (2 s²))

Since ``Σ D_s²`` and ``Σ D_t[T·,T·]²`` do not depend on a permutation ``T``,
maximising ``S`` is minimising the paper's distortion
``Dist²(T) = Σ (D_s[x,x'] − D_t[Tx,Tx'])²`` (Eq. 3, L²): FAQ attacks the very
objective the symmetry score is about.  The Gaussian variant weighs local
agreement (like LH05's affinity) and ignores far pairs.

Start: ``init="descriptor"`` (default) starts FAQ from the linear assignment
minimising the landmark-descriptor distance of ``candidates.descriptor_cost``;
``init="barycenter"`` is scipy's uninformed start ``J/n``.  FAQ needs equal
sample counts on both sides.

Nesting (``nested=True``, default; more than three landmarks): the seeds'
first three are matched too (this very function), that map is sent to the
other seeds (``nested.with_landmarks``) and FAQ is started from it; the map
with the largest objective among the three (the fresh FAQ, the warm FAQ and
the start itself) is returned, so more correct seeds never end on a lower
objective than the first three's map when it satisfies them
(``shapecond.matching.nested``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment, quadratic_assignment

from shapecond.errors import InputError
from shapecond.matching.candidates import check_distances, check_landmarks, descriptor_cost
from shapecond.matching.nested import core_size, with_landmarks
from shapecond.matching.spectral import SampleMatch, default_sigma


def _score(A, B, t) -> float:
    """The objective ``Σ_{x,x'} A[x, x'] · B[T x, T x']`` of the map ``t`` (module docstring)."""
    return float((A * B[np.ix_(t, t)]).sum())


@dataclass(frozen=True)
class FAQOptions:
    """The options of ``faq_match`` (module docstring).

    Attributes
    ----------
    objective : "distance" or "gaussian".
    init : "descriptor" or "barycenter".
    sigma : kernel width for ``objective="gaussian"``; default
        ``default_sigma(D_source, sigma_factor)``.
    sigma_factor : see ``sigma``.
    quantile_weight : weight of the intrinsic part of the descriptors (``candidates``).
    maxiter : Frank–Wolfe iterations.
    seed : passed to scipy as ``rng`` (used only for randomised starts).
    nested : also solve with the first three seeds and keep the larger objective;
        ``info["start"]`` says which start won (``"descriptor"``/``"barycenter"``, or ``"core"``).
    sides : (source, target) side features of the samples (``orientation``), appended to the
        descriptors of the start; None: distances alone.
    """

    objective: str = "distance"
    init: str = "descriptor"
    sigma: float | None = None
    sigma_factor: float = 3.0
    quantile_weight: float = 0.5
    maxiter: int = 60
    seed: int = 0
    nested: bool = True
    sides: tuple | None = None

    def __post_init__(self):
        if self.objective not in ("distance", "gaussian"):
            raise InputError(f"unknown FAQ objective {self.objective!r} (distance or gaussian)")
        if self.init not in ("descriptor", "barycenter"):
            raise InputError(f"unknown FAQ start {self.init!r} (descriptor or barycenter)")


def _start_matrix(n, ls, lt, rows, cols):
    """FAQ's start over the non-seed nodes: the permutation matrix sending the ``rows``-th free
    source node to the ``cols``-th free target node (scipy orders the non-seed nodes
    increasingly, as ``np.setdiff1d`` does)."""
    P0 = np.zeros((n - ls.size, n - lt.size))
    P0[rows, cols] = 1.0
    return P0


def _objective_matrices(Ds, Dt, opts):
    """(A, B, s): the matrices whose ``Σ A · B[T, T]`` FAQ maximises (module docstring) and the
    Gaussian width (None for ``objective="distance"``)."""
    if opts.objective != "gaussian":
        return Ds, Dt, None
    s = default_sigma(Ds, opts.sigma_factor) if opts.sigma is None else float(opts.sigma)
    return np.exp(-Ds ** 2 / (2 * s * s)), np.exp(-Dt ** 2 / (2 * s * s)), s


def faq_match(D_source, D_target, landmarks_source=(), landmarks_target=(),
              options: FAQOptions = FAQOptions()) -> SampleMatch:
    """FAQ seeded graph matching, source to target (module docstring).

    Parameters
    ----------
    D_source, D_target : (N, N) arrays
        Sample distances of source and target, same units and same N.
    landmarks_source, landmarks_target : sequences of int
        Seeds (fixed pairs), sample indices.
    options : FAQOptions
        ``objective``, ``init``, ``sigma``, ``maxiter``, ``seed``, ``nested``...

    Returns
    -------
    SampleMatch
        ``info["value"]`` is the objective of ``t``.
    """
    opts = options
    t0 = time.perf_counter()
    Ds, Dt = check_distances(D_source, D_target)
    if Ds.shape != Dt.shape:
        raise InputError(
            f"FAQ needs the same number of samples on both shapes ({Ds.shape[0]} vs {Dt.shape[0]})")
    ls, lt = check_landmarks(Ds.shape[0], Dt.shape[0], landmarks_source, landmarks_target)
    n = Ds.shape[0]
    A, B, s = _objective_matrices(Ds, Dt, opts)
    faq = dict(maximize=True, maxiter=opts.maxiter, rng=np.random.default_rng(opts.seed))
    if ls.size:
        faq["partial_match"] = np.column_stack([ls, lt])
    if opts.init == "descriptor" and ls.size < n:
        free_s = np.setdiff1d(np.arange(n), ls)
        free_t = np.setdiff1d(np.arange(n), lt)
        cost = descriptor_cost(Ds, Dt, ls, lt, opts.quantile_weight, opts.sides)[np.ix_(free_s, free_t)]
        faq["P0"] = _start_matrix(n, ls, lt, *linear_sum_assignment(cost))
    res = quadratic_assignment(A, B, method="faq", options=faq)
    t = np.asarray(res.col_ind, dtype=np.int64)
    # the value of scipy's ``res.fun``, summed here as for the other maps compared with it
    info = dict(objective=opts.objective, init=opts.init, sigma=s, value=_score(A, B, t),
                iterations=int(res.nit), start=opts.init)
    n_core = core_size(ls.size)
    if opts.nested and n_core:
        t = _nested(Ds, Dt, (ls, lt), n_core, (A, B, faq), opts, t, info)
    info["seconds"] = time.perf_counter() - t0
    return SampleMatch(t, "faq", info)


def _nested(Ds, Dt, seeds, n_core, problem, opts, t, info):
    """Nesting (module docstring): the first ``n_core`` seeds' map sent to the other seeds, and FAQ
    warm-started from it; returns the map of the largest objective among ``t``, that start and
    the warm FAQ (``info`` updated when it is not ``t``)."""
    (ls, lt), (A, B, faq) = seeds, problem
    n = Ds.shape[0]
    core = faq_match(Ds, Dt, ls[:n_core], lt[:n_core], opts)
    start = with_landmarks(core.t, ls, lt)
    free_s = np.setdiff1d(np.arange(n), ls)
    free_t = np.setdiff1d(np.arange(n), lt)
    P0 = _start_matrix(n, ls, lt, np.arange(free_s.size), np.searchsorted(free_t, start[free_s]))
    warm = quadratic_assignment(A, B, method="faq", options={**faq, "P0": P0})
    for cand in (start, np.asarray(warm.col_ind, dtype=np.int64)):
        value = _score(A, B, cand)
        if value > info["value"]:
            t = cand
            info.update(value=value, start="core")
    return t

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

import numpy as np
from scipy.optimize import linear_sum_assignment, quadratic_assignment

from shapecond.checks import check_distance_matrix
from shapecond.errors import InputError
from shapecond.matching.candidates import check_landmarks, descriptor_cost
from shapecond.matching.nested import core_size, with_landmarks
from shapecond.matching.spectral import SampleMatch, default_sigma


def _score(A, B, t) -> float:
    """The objective ``Σ_{x,x'} A[x, x'] · B[T x, T x']`` of the map ``t`` (module docstring)."""
    return float((A * B[np.ix_(t, t)]).sum())


def faq_match(D_source, D_target, landmarks_source=(), landmarks_target=(),
              objective: str = "distance", init: str = "descriptor",
              sigma: float | None = None, sigma_factor: float = 3.0,
              quantile_weight: float = 0.5, maxiter: int = 60, seed: int = 0,
              nested: bool = True) -> SampleMatch:
    """FAQ seeded graph matching, source to target (module docstring).

    Parameters
    ----------
    D_source, D_target : (N, N) arrays
        Sample distances of source and target, same units and same N.
    landmarks_source, landmarks_target : sequences of int
        Seeds (fixed pairs), sample indices.
    objective : {"distance", "gaussian"}
    init : {"descriptor", "barycenter"}
    sigma : float, optional
        Kernel width for ``objective="gaussian"``; default
        ``default_sigma(D_source, sigma_factor)``.
    maxiter : int
        Frank–Wolfe iterations.
    seed : int
        Passed to scipy as ``rng`` (used only for randomised starts).
    nested : bool
        Also solve with the first three seeds and keep the larger objective
        (module docstring); ``info["start"]`` says which start won
        (``"descriptor"``/``"barycenter"``, or ``"core"``).

    Returns
    -------
    SampleMatch
        ``info["value"]`` is the objective of ``t``.
    """
    t0 = time.perf_counter()
    check_distance_matrix(D_source, "source distances")  # one clear error for NaN, inf, asymmetry...
    check_distance_matrix(D_target, "target distances")
    Ds = np.asarray(D_source, dtype=np.float64)
    Dt = np.asarray(D_target, dtype=np.float64)
    if Ds.shape != Dt.shape:
        raise InputError(
            f"FAQ needs the same number of samples on both shapes ({Ds.shape[0]} vs {Dt.shape[0]})")
    if objective not in ("distance", "gaussian"):
        raise InputError(f"unknown FAQ objective {objective!r} (distance or gaussian)")
    if init not in ("descriptor", "barycenter"):
        raise InputError(f"unknown FAQ start {init!r} (descriptor or barycenter)")
    ls, lt = check_landmarks(Ds.shape[0], Dt.shape[0], landmarks_source, landmarks_target)
    n = Ds.shape[0]
    s = None
    if objective == "gaussian":
        s = default_sigma(Ds, sigma_factor) if sigma is None else float(sigma)
        A, B = np.exp(-Ds ** 2 / (2 * s * s)), np.exp(-Dt ** 2 / (2 * s * s))
    else:
        A, B = Ds, Dt
    options = dict(maximize=True, maxiter=maxiter, rng=np.random.default_rng(seed))
    if ls.size:
        options["partial_match"] = np.column_stack([ls, lt])
    if init == "descriptor" and ls.size < n:
        free_s = np.setdiff1d(np.arange(n), ls)
        free_t = np.setdiff1d(np.arange(n), lt)
        cost = descriptor_cost(Ds, Dt, ls, lt, quantile_weight)[np.ix_(free_s, free_t)]
        r, c = linear_sum_assignment(cost)
        P0 = np.zeros((free_s.size, free_t.size))
        # scipy orders the non-seed nodes increasingly, as free_s / free_t are
        P0[r, c] = 1.0
        options["P0"] = P0
    res = quadratic_assignment(A, B, method="faq", options=options)
    t = np.asarray(res.col_ind, dtype=np.int64)
    # the value of scipy's ``res.fun``, summed here as for the other maps compared with it
    info = dict(objective=objective, init=init, sigma=s, value=_score(A, B, t),
                iterations=int(res.nit), start=init)
    n_core = core_size(ls.size)
    if nested and n_core:
        core = faq_match(Ds, Dt, ls[:n_core], lt[:n_core], objective=objective, init=init,
                         sigma=sigma, sigma_factor=sigma_factor, quantile_weight=quantile_weight,
                         maxiter=maxiter, seed=seed, nested=nested)
        start = with_landmarks(core.t, ls, lt)
        free_s = np.setdiff1d(np.arange(n), ls)
        free_t = np.setdiff1d(np.arange(n), lt)
        P0 = np.zeros((free_s.size, free_t.size))
        P0[np.arange(free_s.size), np.searchsorted(free_t, start[free_s])] = 1.0
        warm = quadratic_assignment(A, B, method="faq", options={**options, "P0": P0})
        for cand in (start, np.asarray(warm.col_ind, dtype=np.int64)):
            value = _score(A, B, cand)
            if value > info["value"]:
                t = cand
                info.update(value=value, start="core")
    info["seconds"] = time.perf_counter() - t0
    return SampleMatch(t, "faq", info)

"""Seeded graph matching: FAQ with the landmarks as seeds.

The second matcher, so users see whether good landmarks still help a modern
quadratic-assignment solver.  ``scipy.optimize.quadratic_assignment`` with
``method="faq"`` (Vogelstein et al. 2015, Frank–Wolfe on the doubly stochastic
relaxation) and ``partial_match`` = the landmark pairs (Fishkind et al. 2019,
seeded graph matching).  Direction: **source to target**, ``t[x] = col_ind[x]``.

Exact objective, maximised over permutations ``T`` fixing the landmarks::

    objective="distance":  S(T) = Σ_{x,x'} D_s[x, x'] · D_t[T x, T x']
    objective="gaussian":  Σ_{x,x'} K_s[x, x'] · K_t[T x, T x'],   K = exp(-D² / (2 s²))
    objective="local":     "gaussian" with s read off the landmarks (below)

Since ``Σ D_s²`` and ``Σ D_t[T·,T·]²`` do not depend on a permutation ``T``,
maximising ``S`` is minimising the paper's distortion
``Dist²(T) = Σ (D_s[x,x'] − D_t[Tx,Tx'])²`` (Eq. 3, L²): FAQ attacks the very
objective the symmetry score is about.  The Gaussian variant weighs local
agreement (like LH05's affinity) and ignores far pairs.

**Off isometry: a width read off the landmarks (``objective="local"``, an option, not the default).**
Between two species the true sample map can distort long geodesic distances more than a wrong one:
SMAL_r, the cow to four other animals, the PLS method's 6 landmarks, the RMS of ``D_s − D_t[T,T]``
under the true map (its images snapped to the nearest target sample) exceeds that of FAQ's map on
two of the four (0.131 against 0.114 sqrt(area) where FAQ sends the cow's head to a horse's front
hoof, 0.129 sqrt(area) wrong at the samples; 0.087 against 0.074); weighed by a Gaussian of a few
sample spacings, the same comparison prefers the true map on all four.  The landmark pairs say how far to trust the distances: with ``r`` the
mean over the pairs of ``|log(D_t[l_i, l_j] / D_s[l_i, l_j])|``, a distance ``d`` changes by about
``r d`` between the shapes and stays within the sample spacing ``h`` (``spectral.default_sigma``) up
to ``d = h / r``.  ``objective="local"`` is the Gaussian objective of that width (``local_width``;
the distance objective with fewer than 2 landmarks or where ``h / r`` exceeds every sample
distance); no constant is set.  Measured with 6 exact landmarks and the dense stage after (the
project's release benchmarks, ``shapecond evaluate --counts 3 --landmark-count 6``, FAQ; means in
10⁻³ sqrt(area), distance → local):

* SMAL_r, the cow to its first 8 animals: PLS 54.8 → 46.6 (worst 105 → 53), HKS 38.7 → 39.2, CNBS
  39.9 → 40.0, FPS 34.3 → 33.4; with 3 landmarks PLS 82.1 → 68.4, CNBS 63.6 → 50.3, FPS 76.4 → 82.7.
* TOSCA_r, one test pair per class: FPS 15.4 → 18.1, HKS 21.2 → 24.5, CNBS 19.6 → 18.7, PLS 15.0 → 15.3;
  victoria12 → victoria23 goes wrong with every method (FPS 24 → 46, HKS 39 → 66, with 3 CNBS
  landmarks 37 → 85).  There the width is 0.3–0.6 of the largest distance, and a Gaussian objective
  lets a part far from every landmark flip: the landmarks' own terms act only within the width.

So the distance objective stays the default; ``local`` serves pairs of different species whose
landmarks leave the extremities free (``match --faq-objective local``).  Tried on those pairs and not
adopted: the landmarks' rows kept long-range (their distances) beside the local block (victoria12 →
victoria23, 6 landmarks: CNBS's 52 against 40 for the local objective alone, HKS's 63 against 65);
FAQ on the local objective climbing also from the distance objective's map (one more FAQ run; with 6
landmarks every SMAL_r method's mean within 1 ×10⁻³, TOSCA_r unchanged); choosing between the two
objectives' maps by the error bar or by the map's distortion ε̂ (on 10 such pairs the bar was equal
on 7, and ε̂ preferred the worse map on 4).

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
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import linear_sum_assignment, quadratic_assignment

from shapecond.errors import InputError
from shapecond.matching.candidates import check_distances, check_landmarks, descriptor_cost
from shapecond.matching.nested import core_size, with_landmarks
from shapecond.matching.spectral import SampleMatch, default_sigma


#: FAQ's objectives (module docstring).
FAQ_OBJECTIVES = ("distance", "gaussian", "local")


def local_width(D_source, D_target, landmarks_source, landmarks_target) -> float | None:
    """The width ``s = h / r`` of ``objective="local"`` (module docstring): the sample spacing over the
    mean log-ratio of the landmark pairs' distances on the two shapes; None (the distance objective)
    with fewer than 2 landmarks or when ``s`` is at least the largest source distance."""
    ls, lt = np.asarray(landmarks_source), np.asarray(landmarks_target)
    if ls.size < 2:
        return None
    iu = np.triu_indices(ls.size, 1)
    ratio = D_target[np.ix_(lt, lt)][iu] / D_source[np.ix_(ls, ls)][iu]
    r = float(np.abs(np.log(ratio)).mean())
    h = default_sigma(D_source)
    return None if not r > 0 or h / r >= float(D_source.max()) else h / r


def _resolved(Ds, Dt, ls, lt, opts):
    """``opts`` with ``objective="local"`` resolved to the Gaussian of ``local_width`` or the distance
    objective; the nested run with the first seeds keeps that width (the maps' objectives compare)."""
    if opts.objective != "local":
        return opts
    s = local_width(Ds, Dt, ls, lt)
    return replace(opts, objective="distance") if s is None else replace(opts, objective="gaussian", sigma=s)


def _score(A, B, t) -> float:
    """The objective ``Σ_{x,x'} A[x, x'] · B[T x, T x']`` of the map ``t`` (module docstring)."""
    return float((A * B[np.ix_(t, t)]).sum())


@dataclass(frozen=True)
class FAQOptions:
    """The options of ``faq_match`` (module docstring).

    Attributes
    ----------
    objective : "distance", "gaussian" or "local" (module docstring).
    init : "descriptor" or "barycenter".
    sigma : kernel width for ``objective="gaussian"``; default
        ``default_sigma(D_source, sigma_factor)``.  ``objective="local"`` measures its own
        (``local_width``).
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
        if self.objective not in FAQ_OBJECTIVES:
            raise InputError(f"unknown FAQ objective {self.objective!r} ({', '.join(FAQ_OBJECTIVES)})")
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
    opts = _resolved(Ds, Dt, ls, lt, opts)
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

"""Spectral matching of Leordeanu and Hebert (ICCV 2005) with fixed landmarks.

The paper under reproduction (Ovsjanikov, Huang, Guibas 2011, Section 7)
matches its landmark sets with LH05; this module is that matcher on sample
distance matrices.  Direction: **source to target**; the result ``t`` gives,
for every source sample ``x``, the target sample ``t[x]``.  The paper says
neither how candidates were chosen nor how the eigenvector was discretised;
every such choice is listed here.

1. Candidates ``a = (x -> y)``: the ``k`` best target samples of each source
   sample by landmark-distance descriptors (``candidates.k_best_candidates``);
   landmark pairs are the only candidate of their source sample.
2. Pairwise affinity (LH05's ``M``)::

       M[a, b] = K(D_s[x, x'], D_t[y, y'])    for a = (x->y), b = (x'->y')

   with a consistency kernel ``K`` (``consistency.Kernel``), ``M[a, b] = 0`` when the
   two assignments conflict (``x = x'`` or ``y = y'``, LH05's mapping
   constraints) and on the diagonal (no unary term: the descriptor already
   chose the candidates).  The first round uses LH05's Gaussian
   ``exp(-(D_s − D_t)² / (2 s²))`` (their truncated quadratic ``4.5 − d²/(2s²)``
   cut at ``3 s`` is its piecewise counterpart) with width ``s = sigma_factor × h``,
   ``h`` the median nearest-neighbour spacing of the source samples.
3. Principal eigenvector ``v`` of ``M`` by power iteration (``M`` is
   non-negative and symmetric, so ``v ≥ 0``).
4. Discretisation: LH05's greedy rule (accept the largest ``v[a]``, reject
   every candidate conflicting with it, repeat while ``v > 0``), or, with
   ``rounding="assignment"`` (default), the linear assignment maximising ``Σ v``.
   Source samples left without a candidate are completed by a linear
   assignment over the free targets minimising the mean disagreement of
   distances to the matched samples (LH05 returns a partial map).
5. Refinement (``refine=True``, default; not in LH05).  Rounding the
   eigenvector can end far below the identity *on LH05's own objective*
   ``Σ_{x≠x'} K(D_s[x,x'], D_t[Tx,Tx'])`` (TOSCA david0 → david1, 15 landmarks:
   greedy 136,906 against 147,061 for the true map), so the rounded map is
   only a start for a discrete ascent of that objective (``refine.polish``:
   swaps of neighbouring images and linear reassignments, each accepted only
   when the objective grows; ``refine.robust_reassignment`` for regions shifted
   as a whole).  It runs coarse to fine:

   * a *global* kernel ``Kernel(tol=h, rel=ρ)``, ``ρ`` measured from the input
     as twice the median relative distance disagreement ``|D_s − D_t[T,T]| / D_s``
     of the rounded map (the non-isometry the map has to tolerate), fixes the
     coarse layout;
   * then a *local* kernel ``Kernel(tol=h/2, radius=3h)``.  Real deformations
     change long geodesic distances by 5–20 % (TOSCA dog, median 7 %, 1 % of
     pairs above 30 %) but the distances between samples a few spacings apart
     by a fraction of ``h``: only pairs within about ``3h`` (the first two
     rings of neighbours) are weighed, and a disagreement of one spacing
     ``h`` (a sample shifted to its neighbour) costs a factor ``e⁻²``.  Under a
     global kernel the true map is not a local maximum on such data.

   Then the spectral step is repeated (at most ``rounds`` times, while the
   objective grows) with candidates iterated from the current map — each
   source sample's image and its ``k − 1`` nearest target samples — and the
   local kernel as affinity, followed by the same refinement.  ``info``
   reports the candidates of the round that produced the map
   (``SampleMatch.candidates``) and its objective.
6. Nesting (``nested=True``, default; with more than three landmarks): the
   problem with the first three landmarks is matched too, its map sent to the
   other landmarks and refined, and the map with the larger objective is
   returned (``shapecond.matching.nested``: more correct landmarks never end
   on a lower objective than the first three's map when it satisfies them).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numba
import numpy as np
import scipy.sparse as sp
from scipy.linalg.blas import ssymv
from scipy.optimize import linear_sum_assignment
from scipy.sparse.linalg import LinearOperator, eigsh

from shapecond.errors import InputError, TooLargeError
from shapecond.matching import consistency
from shapecond.matching import refine as R
from shapecond.matching.candidates import Candidates, band_candidates, check_distances, k_best_candidates
from shapecond.matching.nested import core_size, with_landmarks

#: refuse dense affinity matrices above this many bytes (float32)
MAX_AFFINITY_BYTES = 3 * 2**30


@dataclass(frozen=True)
class SampleMatch:
    """A map between samples, source to target.

    Attributes
    ----------
    t : (N_s,) int64
        ``t[x]`` is the target sample matched to source sample ``x``.
    matcher : str
        "lh05" or "faq".
    info : dict
        Diagnostics (iterations, sigma, candidate counts, seconds...).
    candidates : Candidates or None
        LH05: the candidate assignments of the spectral round that produced ``t``.
    """

    t: np.ndarray
    matcher: str
    info: dict = field(default_factory=dict)
    candidates: Candidates | None = field(default=None, repr=False)


def default_sigma(D_source: np.ndarray, factor: float = 1.0) -> float:
    """``factor ×`` median distance from a source sample to its nearest other sample."""
    D = np.asarray(D_source, dtype=np.float64)
    off = D + np.diag(np.full(D.shape[0], np.inf))
    return float(factor * np.median(off.min(axis=1)))


@numba.njit(parallel=True, cache=True, error_model="numpy")
def _affinity_kernel(Ds, Dt, src, tgt, kp, upper):
    """M over every pair of candidates (``src[i] -> tgt[i]``) for the kernel ``kp``, dense, float32.

    ``upper``: write the upper triangle (``j >= i``) only and leave the rest 0, all that
    ``principal_eigenvector``'s ``ssymv`` reads of a symmetric ``M`` (half the work).  The
    entries are ``consistency._k``'s, evaluated branch-free (the zero cases selected after the
    arithmetic) so that the inner loop vectorises: ~3x faster, the same values.
    """
    t0, r2, iw2, cut2 = kp
    C = src.size
    M = np.zeros((C, C), dtype=np.float32)  # fresh zero pages: the unwritten half costs nothing
    for i in numba.prange(C):
        x, y = src[i], tgt[i]
        ds, dt, out = Ds[x], Dt[y], M[i]
        for j in range(i if upper else 0, C):
            x2, y2 = src[j], tgt[j]
            d = ds[x2]
            d2 = d * d
            diff = d - dt[y2]
            u = max(1.0 - diff * diff / (consistency.SUPPORT * consistency.SUPPORT * (t0 + r2 * d2)), 0.0)
            w = 1.0 - d2 * iw2
            v = u * u * w * w
            out[j] = 0.0 if (x == x2 or y == y2 or d2 >= cut2) else v
    return M


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _sparse_affinity_kernel(out, Ds, Dt, cand, by_source, near, kp):
    """CSR pattern and values of M for a kernel ``kp`` of finite support, in one pass; returns indptr.

    ``cand = (src, tgt)``: candidate ``i`` is ``src[i] -> tgt[i]``; with ``by_source =
    (order, starts)``, ``order[starts[x]:starts[x + 1]]`` lists the candidates of source
    sample ``x``; ``near[x]`` the other source samples within the kernel's support (-1
    padded).  Row ``i`` (candidate ``x -> y``) holds, for each ``x2`` of ``near[x]`` in
    turn and each candidate ``j`` of ``x2`` with another target, ``K(D_s[x, x2], D_t[y,
    tgt[j]])`` when positive.  Rows are written (branch-free) one after the other into
    ``out = (indices, data)``, which hold at least the total of the rows' upper bounds
    (the candidates of the neighbours).
    """
    indices, data = out
    src, tgt = cand
    order, starts = by_source
    C = src.size
    indptr = np.zeros(C + 1, dtype=np.int64)
    p = 0
    for i in range(C):
        x = src[i]
        y = tgt[i]
        for q in range(near.shape[1]):
            x2 = near[x, q]
            if x2 < 0:
                break
            d = Ds[x, x2]
            for r in range(starts[x2], starts[x2 + 1]):
                j = order[r]
                y2 = tgt[j]
                if y2 != y:
                    v = consistency._k(d, Dt[y, y2], kp)
                    indices[p] = j
                    data[p] = v
                    p += 1 if v > 0.0 else 0
        indptr[i + 1] = p
    return indptr


def affinity_matrix(D_source, D_target, cand: Candidates, kernel, block: int = 512,
                    compiled: bool = True, upper: bool = False):
    """Pairwise affinity ``M`` over the candidates (module docstring, step 2), float32.

    ``kernel`` is a ``consistency.Kernel`` or a float ``s`` (LH05's kernel of width
    ``s``).  A kernel of finite radius gives a ``scipy.sparse.csr_matrix`` (most
    candidate pairs are beyond its support), otherwise a dense array.
    ``compiled=True`` fills ``M`` with a numba kernel (one pass, ~10x faster);
    the NumPy block version (dense) is the reference the tests compare it with.
    ``upper=True``: a compiled dense ``M`` has its upper triangle only (the rest 0),
    enough for ``principal_eigenvector`` (``M`` is symmetric) at half the cost.
    """
    kernel = kernel if isinstance(kernel, consistency.Kernel) else consistency.Kernel(float(kernel))
    C = cand.size
    Ds = np.ascontiguousarray(D_source, dtype=np.float64)
    Dt = np.ascontiguousarray(D_target, dtype=np.float64)
    src, tgt = np.ascontiguousarray(cand.source), np.ascontiguousarray(cand.target)
    kp = kernel.params()
    if compiled and np.isfinite(kernel.radius):
        order = np.argsort(src, kind="stable")
        starts = np.searchsorted(src[order], np.arange(Ds.shape[0] + 1))
        near = consistency.support_lists(Ds, kp[3])
        # room for every row's upper bound, allocated by NumPy (huge pages: few page faults)
        counts = np.diff(starts)
        bound = int(np.where(near >= 0, counts[np.maximum(near, 0)], 0).sum(axis=1)[src].sum())
        indices = np.empty(bound, dtype=np.int32)
        data = np.empty(bound, dtype=np.float32)
        indptr = _sparse_affinity_kernel((indices, data), Ds, Dt, (src, tgt), (order, starts), near, kp)
        for a in (indices, data):  # cut to the entries in place (realloc): a view of the larger array
            a.resize(indptr[-1], refcheck=False)  # would be copied by scipy's csr_matrix (its ``prune``)
        return sp.csr_matrix((data, indices, indptr), shape=(C, C))
    if 4 * C * C > MAX_AFFINITY_BYTES:
        raise TooLargeError(
            f"{C} candidates need a {4 * C * C / 2**30:.1f} GB affinity matrix; lower k or N")
    if compiled:
        return _affinity_kernel(Ds, Dt, src, tgt, kp, upper)
    t0, r2, iw2, cut2 = kp
    M = np.empty((C, C), dtype=np.float32)
    for lo in range(0, C, block):
        hi = min(C, lo + block)
        d = Ds[np.ix_(src[lo:hi], src)]
        diff = d - Dt[np.ix_(tgt[lo:hi], tgt)]
        u = np.maximum(1.0 - diff * diff / (consistency.SUPPORT ** 2 * (t0 + r2 * d * d)), 0.0)
        blk = (u * (1.0 - d * d * iw2)) ** 2
        blk[d * d >= cut2] = 0.0
        blk[src[lo:hi, None] == src[None, :]] = 0.0
        blk[tgt[lo:hi, None] == tgt[None, :]] = 0.0
        M[lo:hi] = blk
    return M


def principal_eigenvector(M: np.ndarray, tol: float = 1e-7, max_iter: int = 500, v0=None):
    """Power iteration for the Perron vector of a non-negative symmetric ``M``.

    ``v0``: a non-negative start (default: the constant vector).  A dense
    float32 ``M`` is multiplied by BLAS ``ssymv`` on its upper triangle: the
    products are memory-bound and read half of ``M`` (measured 1.7x faster at
    C ≈ 8,000, the first LH05 round; the same maps on 120 TOSCA pairs, the
    vector within 6e-8 of ``M @ v``'s), so its lower triangle is never read
    (``affinity_matrix(..., upper=True)`` suffices).

    Returns
    -------
    v : (C,) float64, unit norm, non-negative
    iterations : int
    converged : bool
    """
    C = M.shape[0]
    v = np.full(C, 1.0, dtype=np.float32) if v0 is None else np.asarray(v0, dtype=np.float32).copy()
    v /= max(float(np.linalg.norm(v)), 1e-30)
    dense = isinstance(M, np.ndarray) and M.dtype == np.float32 and M.flags.c_contiguous
    for it in range(1, max_iter + 1):
        # M.T is M in Fortran order: its lower triangle is M's upper one
        w = ssymv(1.0, M.T, v, lower=1) if dense else M @ v
        nrm = float(np.linalg.norm(w))
        if nrm == 0.0:
            return v.astype(np.float64), it, True
        w /= nrm
        if float(np.abs(w - v).max()) < tol:
            return w.astype(np.float64), it, True
        v = w
    return v.astype(np.float64), max_iter, False


def lanczos_perron_vector(M: np.ndarray, v0=None, tol: float = 1e-6):
    """The Perron vector of a non-negative symmetric ``M`` by Lanczos (ARPACK ``eigsh``).

    Power iteration needs ``O(1 / gap)`` products; on the local affinities of
    the refined rounds (small spectral gap) that was 100+ products against
    about 20 here.  Returns ``(v, products, True)`` with ``v ≥ 0``, unit norm.
    """
    calls = [0]

    def matvec(x):
        calls[0] += 1
        return M @ np.asarray(x, dtype=np.float32)

    C = M.shape[0]
    start = np.ones(C) if v0 is None else np.asarray(v0, dtype=np.float64)
    _, V = eigsh(LinearOperator((C, C), matvec=matvec, dtype=np.float32), k=1, which="LA",
                 tol=tol, v0=start)
    v = np.abs(V[:, 0]).astype(np.float64)
    return v / max(float(np.linalg.norm(v)), 1e-30), calls[0], True


def greedy_discretisation(cand: Candidates, v: np.ndarray, n_source: int) -> np.ndarray:
    """LH05's greedy rounding; ``-1`` marks source samples left unmatched."""
    t = np.full(n_source, -1, dtype=np.int64)
    taken = set()
    t[cand.landmarks_source] = cand.landmarks_target
    taken.update(cand.landmarks_target.tolist())
    for a in np.argsort(-v, kind="stable"):
        if v[a] <= 0:
            break
        x, y = int(cand.source[a]), int(cand.target[a])
        if t[x] < 0 and y not in taken:
            t[x] = y
            taken.add(y)
    return t


def assignment_rounding(cand: Candidates, v: np.ndarray, n_source: int, n_target: int):
    """Linear assignment maximising ``Σ v`` over candidates; non-candidates become ``-1``."""
    P = np.zeros((n_source, n_target))
    np.maximum.at(P, (cand.source, cand.target), v)
    P[cand.landmarks_source, :] = 0.0
    P[cand.landmarks_source, cand.landmarks_target] = 2.0 + v.max(initial=0.0)
    rows, cols = linear_sum_assignment(P, maximize=True)
    t = np.full(n_source, -1, dtype=np.int64)
    ok = P[rows, cols] > 0
    t[rows[ok]] = cols[ok]
    return t


def complete_map(D_source, D_target, t: np.ndarray) -> np.ndarray:
    """Assign the ``-1`` entries of ``t`` to free targets by distance consistency.

    Cost of ``x -> y``: mean over matched ``a`` of ``|D_s[x, a] - D_t[y, t[a]]|``,
    minimised jointly by ``linear_sum_assignment``.
    """
    t = t.copy()
    todo = np.flatnonzero(t < 0)
    if todo.size == 0:
        return t
    done = np.flatnonzero(t >= 0)
    free = np.setdiff1d(np.arange(D_target.shape[0]), t[done])
    if done.size == 0:
        cost = np.zeros((todo.size, free.size))
    else:
        a = D_source[np.ix_(todo, done)]
        b = D_target[np.ix_(free, t[done])]
        cost = np.abs(a[:, None, :] - b[None, :, :]).mean(axis=2)
    r, c = linear_sum_assignment(cost)
    t[todo[r]] = free[c]
    return t


def fine_kernel(h: float) -> consistency.Kernel:
    """The local kernel of the refinement (module docstring, step 5) for sample spacing ``h``;
    ``info["objective"]`` of a refined ``lh05_match`` is ``consistency.objective`` under it."""
    return consistency.Kernel(0.5 * h, 0.0, 3.0 * h)


@dataclass(frozen=True)
class LH05Options:
    """The options of ``lh05_match`` (module docstring, steps 1-6).

    Attributes
    ----------
    k : candidates per source sample.
    sigma : width ``s`` of the first round's Gaussian affinity; default
        ``sigma_factor × h`` (step 2).
    sigma_factor : see ``sigma``.
    rounding : "assignment" (linear assignment) or "greedy" (LH05's greedy discretisation).
    refine : step 5; ``refine=False, rounding="greedy"`` is the plain LH05 of the paper.
    rounds : at most this many spectral rounds on candidates iterated from the map.
    quantile_weight : weight of the intrinsic part of the descriptors (``candidates``).
    tol, max_iter : of the first round's power iteration.
    nested : step 6: with more than three landmarks and ``refine``, also match with the
        first three (this very function), send that map to the other landmarks, refine it
        and keep the larger objective (``nested``).
    sides : (source, target) side features of the samples (``orientation``), appended to the
        candidates' descriptors; None: distances alone.
    """

    k: int = 20
    sigma: float | None = None
    sigma_factor: float = 2.0
    rounding: str = "assignment"
    refine: bool = True
    rounds: int = 3
    quantile_weight: float = 0.5
    tol: float = 1e-7
    max_iter: int = 500
    nested: bool = True
    sides: tuple | None = None

    def __post_init__(self):
        if self.rounding not in ("greedy", "assignment"):
            raise InputError(f"unknown rounding {self.rounding!r} (greedy or assignment)")


def lh05_match(D_source, D_target, landmarks_source=(), landmarks_target=(),
               options: LH05Options = LH05Options()) -> SampleMatch:
    """Leordeanu–Hebert spectral matching with landmarks, source to target.

    Parameters
    ----------
    D_source : (N_s, N_s) array
        Source sample distances.
    D_target : (N_t, N_t) array, N_t >= N_s
        Target sample distances, same units.
    landmarks_source, landmarks_target : sequences of int
        Corresponding landmark sample indices; they stay fixed.
    options : LH05Options
        ``k``, ``sigma``, ``rounding``, ``refine``, ``rounds``, ``nested``...

    Returns
    -------
    SampleMatch
        ``t`` is a total injective map of source samples into target samples;
        ``info["objective"]`` is the local-kernel objective of ``t`` (refined runs);
        ``info["start"]`` says whether ``t`` came from this problem's own
        spectral start (``"spectral"``) or from the first three landmarks'
        map (``"core"``).  With ``nested``, ``info["objective"]`` is at least that
        of the map matched with the first three landmarks whenever that map sends
        the others to their images.
    """
    opts = options
    t0 = time.perf_counter()
    run = _LH05(*check_distances(D_source, D_target), opts)
    cand = k_best_candidates(run.Ds, run.Dt, landmarks_source, landmarks_target, opts.k, opts.quantile_weight,
                             opts.sides)
    h = default_sigma(run.Ds, 1.0)
    s = opts.sigma_factor * h if opts.sigma is None else float(opts.sigma)
    if not s > 0:
        raise InputError("the affinity width sigma must be positive")
    t, (iters, conv) = run.spectral_round(cand, s)
    info = dict(k=opts.k, candidates=cand.size, sigma=s, iterations=iters, converged=conv,
                rounding=opts.rounding, refine=opts.refine)
    if opts.refine and h > 0:
        t, cand = run.refined(t, cand, h, info)
    info["seconds"] = time.perf_counter() - t0
    return SampleMatch(t, "lh05", info, cand)


class _LH05:
    """The distances of one ``lh05_match`` problem, its options and its steps (module docstring)."""

    def __init__(self, Ds, Dt, opts):
        self.Ds, self.Dt, self.opts = Ds, Dt, opts

    def spectral_round(self, cand, kernel, start=None):
        """Steps 2-4: the affinity of ``cand``, its Perron vector (power iteration; Lanczos from
        ``start``, a map, in the refined rounds), rounded and completed.  Returns (map,
        (iterations, converged))."""
        Ds, Dt, opts = self.Ds, self.Dt, self.opts
        M = affinity_matrix(Ds, Dt, cand, kernel, upper=start is None)
        if start is None:  # dense, float32: ssymv reads the upper triangle only
            v, iters, conv = principal_eigenvector(M, opts.tol, opts.max_iter)
        else:  # local affinities have a small spectral gap: Lanczos, not power iteration
            v, iters, conv = lanczos_perron_vector(M, 0.1 + (start[cand.source] == cand.target))
        del M
        n_s, n_t = Ds.shape[0], Dt.shape[0]
        rounded = (greedy_discretisation(cand, v, n_s) if opts.rounding == "greedy"
                   else assignment_rounding(cand, v, n_s, n_t))
        return complete_map(Ds, Dt, rounded), (iters, conv)

    def refined(self, t, cand, h, info):
        """Steps 5 and 6 from the rounded map ``t``: (map, candidates of the round that produced
        it); ``info`` receives the objective and where the map came from."""
        Ds, Dt, opts = self.Ds, self.Dt, self.opts
        free = np.setdiff1d(np.arange(Ds.shape[0]), cand.landmarks_source)
        knn = R.neighbours(Dt, max(opts.k, 64))
        iu = np.triu_indices(Ds.shape[0], 1)
        ds = Ds[iu]
        rel = np.abs(ds - Dt[t][:, t][iu]) / np.maximum(ds, h)
        coarse = consistency.Kernel(h, 2.0 * float(np.median(rel)))
        fine = fine_kernel(h)
        t, _ = R.polish(Ds, Dt, t, free, coarse, knn)
        best = None
        for _ in range(max(opts.rounds, 1)):
            c = band_candidates(t, knn, cand.landmarks_source, cand.landmarks_target, opts.k)
            t_r, _ = self.spectral_round(c, fine, t)
            t_r, f = R.refine(Ds, Dt, t_r, free, fine, knn)
            if best is not None and not f > best[1]:
                break
            best = (t_r, f, c)
            t = t_r
        t, f, cand = best
        info.update(objective=f, coarse_rel=coarse.rel, h=h, candidates=cand.size, start="spectral")
        n_core = core_size(cand.landmarks_source.size)
        if opts.nested and n_core:  # 6. the first three landmarks' map, sent to the others
            ls, lt = cand.landmarks_source, cand.landmarks_target
            core = lh05_match(Ds, Dt, ls[:n_core], lt[:n_core], opts)
            t_c, f_c = R.refine(Ds, Dt, with_landmarks(core.t, ls, lt), free, fine, knn)
            if f_c > f:
                t, f = t_c, f_c
                cand = core.candidates
                info.update(objective=f, candidates=cand.size, start="core")
        return t, cand

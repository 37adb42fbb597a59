"""Start maps of the witness search.

All starts are bijections of the samples X (the first ``n`` points), built
from ``DX = D[:n, :n]``; landmarks are fixed points.  The search refines them
(and, with dense targets, moves them onto the denser set Y afterwards).

* ``swap_map``: the identity with two samples exchanged (best single swap).
* ``spectral_starts``: sign-flip maps.  A symmetry T of a metric space
  commutes with D, so it maps each embedding coordinate of a (simple)
  eigenvector to ± itself; flipping the signs of a few coordinates and solving
  a linear assignment gives candidate maps.  Two embeddings: classical MDS of
  D² and diffusion coordinates of a Gaussian kernel of D.  Spectral starts
  alone are not enough (on an animal the antisymmetric vector was 6th by |λ|),
  hence the other families.
* ``gilmore_lawler_starts``: argmax ⟨W − s·GL, P⟩ over bijections P, with
  ``W[x, y] = D[x, y]²`` (displacement) and ``GL[x, y]`` the Gilmore-Lawler
  lower bound of the distortion of row x sent to y (sorted rows matched; exact
  on landmark columns).  Since Dist²(T) ≥ Σ_x GL[x, Tx], small s favours large
  displacement, large s near-isometries; a grid of s gives a family of starts.
* ``reflection_starts``: reflections of the MDS embedding (and their
  out-of-sample extension to the targets Y).  A mirror usually flips the sign
  of *several* MDS coordinates at once (centaur0: four of the first eight), so
  single flips and pairs miss it; all 2^k − 1 sign patterns of the first k
  coordinates are ranked by how well the reflected X lands on Y, and the best
  few are refined by ICP (nearest targets + orthogonal Procrustes).
* ``random_start``: a random permutation of the free samples.
* ``repair``: makes any user map a valid start (landmarks fixed, injective).
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import threading
import time

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree
from shapecond.threads import n_threads, thread_map


def swap_map(n: int, a: int, b: int) -> np.ndarray:
    """The identity on ``range(n)`` with ``a`` and ``b`` exchanged."""
    t = np.arange(n, dtype=np.int64)
    t[a], t[b] = b, a
    return t


def random_start(rng: np.random.Generator, n: int, free: np.ndarray) -> np.ndarray:
    """A uniformly random bijection of X fixing every non-free sample."""
    t = np.arange(n, dtype=np.int64)
    t[free] = rng.permutation(free)
    return t


def repair(t, n: int, m: int, landmarks: np.ndarray) -> np.ndarray:
    """Turn an arbitrary int array into a valid map: length n, values in
    ``range(m)``, injective, ``t[l] = l`` for every landmark.

    Entries out of range, duplicated or sitting on a landmark's target are
    replaced by unused targets, samples first (lowest index first), so a
    bijection of X stays a bijection of X.
    """
    t = np.asarray(t, dtype=np.int64).ravel()
    if t.size != n:
        raise ValueError(f"a start map must have length {n}, got {t.size}")
    t = t.copy()
    lm = set(int(x) for x in landmarks)
    t[list(lm)] = list(lm)
    taken = set(lm)
    bad = []
    for x in range(n):
        if x in lm:
            continue
        y = int(t[x])
        if y < 0 or y >= m or y in taken:
            bad.append(x)
        else:
            taken.add(y)
    spare = (y for y in range(m) if y not in taken)
    for x in bad:
        t[x] = next(spare)
    return t


def _assign(score: np.ndarray, free: np.ndarray, n: int) -> np.ndarray:
    """Bijection of X maximising Σ score[x, T x] over the free samples."""
    t = np.arange(n, dtype=np.int64)
    rows, cols = linear_sum_assignment(score[np.ix_(free, free)], maximize=True)
    t[free[rows]] = free[cols]
    return t


#: Results remembered per function (``_memo``).
MEMO_SIZE = 4
_memo_lock = threading.Lock()


def _key(value):
    """A hashable key of an argument: the content of an array (O(size) hash), else the value."""
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        return hashlib.blake2b(a.view(np.uint8), digest_size=16).digest(), a.shape, a.dtype.str
    if isinstance(value, (list, tuple)):
        return tuple(_key(v) for v in value)
    return value


def _read_only(result):
    if isinstance(result, np.ndarray):
        result.flags.writeable = False
    else:
        for t in result:
            t.flags.writeable = False
    return result


def _memo(f):
    """Remember the last ``MEMO_SIZE`` results of ``f``, keyed by the content of its arguments.

    The score of a shape runs σ's and δ(ε)'s witness searches on the same samples with the
    same landmarks, and each builds the same embeddings (O(N³) eigendecompositions) and the
    same spectral and Gilmore-Lawler starts (about 50 linear assignments, 0.7 s at N = 400)
    from them; hashing the arguments costs O(N²).  Results are read-only arrays (a list of
    maps comes back as a new list), so no caller can change a remembered one.
    A keyword ``deadline`` (a ``time.perf_counter()`` time, for the functions that take one) is
    not part of the key, and a result computed past it (perhaps cut short) is not remembered.
    """
    memo: dict = {}

    @functools.wraps(f)
    def wrapped(*args, deadline=None, **kwargs):
        key = _key((args, tuple(sorted(kwargs.items()))))
        with _memo_lock:
            hit = memo.get(key)
        if hit is None:
            hit = _read_only(f(*args, **kwargs) if deadline is None else f(*args, deadline=deadline, **kwargs))
            if deadline is None or time.perf_counter() <= deadline:
                with _memo_lock:
                    memo[key] = hit
                    while len(memo) > MEMO_SIZE:
                        memo.pop(next(iter(memo)))
        return hit if isinstance(hit, np.ndarray) else list(hit)

    return wrapped


@_memo
def classical_mds(D: np.ndarray, k: int = 3) -> np.ndarray:
    """Classical (Torgerson) MDS coordinates (n, k) of a distance matrix, scaled by sqrt(eigenvalue).

    Also places a distance-matrix input in space for pictures (``viz``).
    """
    D = np.asarray(D, dtype=float)
    n = D.shape[0]
    J = np.eye(n) - 1.0 / n
    B = -0.5 * J @ (D**2) @ J
    lam, V = np.linalg.eigh(B)
    order = np.argsort(lam)[::-1][:k]
    X = V[:, order] * np.sqrt(np.clip(lam[order], 0.0, None))
    return np.hstack([X, np.zeros((n, k - X.shape[1]))]) if X.shape[1] < k else X


@_memo
def _diffusion(DX: np.ndarray, k: int) -> np.ndarray:
    """Diffusion coordinates (n, k) of a Gaussian kernel of DX (constant dropped)."""
    n = DX.shape[0]
    nn = np.sort(DX, axis=1)[:, 1 : min(n, 8)]
    eps = 2.0 * float(np.median(nn)) if nn.size else 1.0
    K = np.exp(-((DX / max(eps, 1e-12)) ** 2))
    deg = K.sum(axis=1)
    A = K / np.sqrt(np.outer(deg, deg))
    lam, V = np.linalg.eigh(A)
    order = np.argsort(lam)[::-1][1 : k + 1]
    phi = V[:, order] / np.sqrt(deg)[:, None]
    phi /= np.maximum(np.linalg.norm(phi, axis=0), 1e-300)
    return phi * np.clip(lam[order], 0.0, None)


def _until(f, jobs, deadline) -> list:
    """``thread_map(f, jobs)`` a chunk of ``n_threads()`` jobs at a time, stopping once the
    ``time.perf_counter()`` time ``deadline`` (None: none) is past: the results of the jobs done."""
    if deadline is None:
        return thread_map(f, jobs)
    out, k = [], n_threads()
    for i in range(0, len(jobs), k):
        if time.perf_counter() > deadline:
            break
        out += thread_map(f, jobs[i:i + k])
    return out


@_memo
def spectral_starts(DX: np.ndarray, free: np.ndarray, n_vectors: int = 10,
                    n_pairs: int = 5, deadline=None) -> list[np.ndarray]:
    """Sign-flip starts from two embeddings (MDS and diffusion).

    For each embedding Φ (n × k, k = n_vectors) and each sign pattern S that
    flips one coordinate, or two among the first ``n_pairs``, the start is the
    bijection maximising Σ_x ⟨Φ_x S, Φ_{T x}⟩ (linear assignment).  Maps equal
    to the identity are dropped; duplicates are removed.  Past ``deadline`` (a
    ``time.perf_counter()`` time) no more assignment is started.
    """
    n = DX.shape[0]
    k = max(1, min(n_vectors, n - 2))
    patterns = [(i,) for i in range(k)]
    patterns += list(itertools.combinations(range(min(n_pairs, k)), 2))
    def start(job):
        phi, pat = job
        sgn = np.ones(phi.shape[1])
        sgn[[p for p in pat if p < phi.shape[1]]] = -1.0
        return _assign((phi * sgn) @ phi.T, free, n)

    jobs = [(phi, pat) for phi in (classical_mds(DX, k), _diffusion(DX, k)) for pat in patterns]
    return _distinct(_until(start, jobs, deadline), n)  # linear assignments release the GIL


def distinct_maps(maps) -> list:
    """``maps`` in order without repeats (a search from a repeated start finds nothing new)."""
    out, seen = [], set()
    for t in maps:
        key = np.asarray(t, dtype=np.int64).tobytes()
        if key not in seen:
            seen.add(key)
            out.append(t)
    return out


def _distinct(maps, n: int) -> list[np.ndarray]:
    """``maps`` in order without duplicates and without the identity."""
    return [t for t in distinct_maps(maps) if np.any(t != np.arange(n))]


def gilmore_lawler(DX: np.ndarray, landmarks: np.ndarray) -> np.ndarray:
    """GL[x, y]: lower bound of Σ_{x'} (D[x,x'] − D[y, T x'])² over maps with T x = y.

    Landmark columns are fixed by T and enter exactly; the other columns are a
    bijection among themselves, whose best pairing is the sorted order
    (rearrangement inequality).  Computed as a Gram matrix: O(n³) BLAS.
    """
    n = DX.shape[0]
    mask = np.ones(n, dtype=bool)
    mask[landmarks] = False
    R = np.sort(DX[:, mask], axis=1)
    L = DX[:, ~mask]
    F = np.hstack([R, L])
    sq = np.sum(F**2, axis=1)
    return np.maximum(sq[:, None] + sq[None, :] - 2.0 * F @ F.T, 0.0)


@_memo
def gilmore_lawler_starts(DX: np.ndarray, free: np.ndarray, landmarks: np.ndarray,
                          s_values, deadline=None) -> list[np.ndarray]:
    """Maps argmax_T Σ_x (D[x,Tx]² − s·GL[x,Tx]) for each s (linear assignments; none started past
    ``deadline``, a ``time.perf_counter()`` time)."""
    n = DX.shape[0]
    W = DX**2
    GL = gilmore_lawler(DX, landmarks)
    return _distinct(_until(lambda s: _assign(W - s * GL, free, n), list(s_values), deadline), n)


def _landmark_mds(D: np.ndarray, n: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Classical MDS of the samples X and its out-of-sample extension to Y.

    Returns ``(phi, psi)``: phi (n, k') the MDS coordinates of ``D[:n, :n]``,
    psi (M, k') the landmark-MDS coordinates (de Silva and Tenenbaum 2004) of
    every point of Y from its distances to X (psi[:n] == phi), k' ≤ k the
    coordinates with a clearly positive eigenvalue.
    """
    phi = classical_mds(D[:n, :n], k)
    lam = np.sum(phi**2, axis=0)
    keep = lam > 1e-9 * max(float(lam.max(initial=0.0)), 1e-300)
    phi, lam = phi[:, keep], lam[keep]
    mu = np.mean(D[:n, :n] ** 2, axis=1)
    psi = -0.5 * ((D[:n, :] ** 2) - mu[:, None]).T @ (phi / lam)
    return phi, psi


def _nearest_injective(tree: cKDTree, q: np.ndarray, n: int, m: int, free: np.ndarray,
                       landmarks: np.ndarray, k: int = 8) -> np.ndarray:
    """Greedy injective nearest-target map: free samples (closest first) take
    their nearest unused target among the ``k`` nearest; the rest go through
    :func:`repair`.  Landmarks are fixed."""
    k = min(k, m)
    dist, idx = tree.query(q[free], k=k)
    dist, idx = dist.reshape(free.size, k), idx.reshape(free.size, k)
    t = np.full(n, -1, dtype=np.int64)
    used = np.zeros(m, dtype=bool)
    used[landmarks] = True
    for r in np.argsort(dist[:, 0], kind="stable"):
        for y in idx[r]:
            if not used[y]:
                used[y] = True
                t[free[r]] = y
                break
    return repair(t, n, m, landmarks)


#: Samples used to rank the sign patterns of :func:`reflection_starts`.
RANK_PROBES = 96


def reflection_starts(D: np.ndarray, n: int, free: np.ndarray, landmarks: np.ndarray,
                      n_coords: int = 8, n_best: int = 3, iters: int = 3) -> list[np.ndarray]:
    """Reflection starts: maps X -> Y from sign patterns of MDS coordinates.

    An intrinsic symmetry T commutes with D, so on the MDS coordinates Φ of X
    it acts (for simple eigenvalues) as a diagonal ±1 matrix S; a mirror
    typically flips several coordinates, not one or two (measured:
    on an animal the antisymmetric vector was only 6th by |λ|).  Every pattern
    S ≠ I over the first ``n_coords`` coordinates is scored by the ratio

        Σ_x |Φ_x S − Ψ_{nn(x)}|² / Σ_x |Φ_x S − Φ_x|²,

    nn(x) the nearest point of Y in the extended embedding Ψ (a small value: S
    maps X onto Y while moving it far, the embedding analogue of σ).  The
    ``n_best`` patterns with the smallest ratio are refined by ``iters`` rounds
    of ICP: injective nearest targets, then the orthogonal R minimising
    |Φ R − Ψ_T|_F (Procrustes).  Returns maps into range(M) (M = D.shape[0]),
    landmarks fixed; the search polishes them.  Cost: 2^k KD-tree queries of
    at most ``RANK_PROBES`` samples each (0.1 s at N = 400, M = 3200, k = 8).
    """
    m = D.shape[0]
    if free.size < 2:
        return []
    phi, psi = _landmark_mds(D, n, max(n_coords, 2))
    k = phi.shape[1]
    kc = min(n_coords, k)
    if kc < 1:
        return []
    tree = cKDTree(psi)
    probe = free[:RANK_PROBES]  # FPS order: the first samples already cover X
    ranked = []
    for mask in range(1, 2**kc):
        sgn = np.ones(k)
        sgn[[i for i in range(kc) if mask >> i & 1]] = -1.0
        disp = 4.0 * float(np.sum(phi[probe][:, sgn < 0] ** 2))
        if disp <= 0.0:
            continue
        dist, _ = tree.query(phi[probe] * sgn)
        ranked.append((float(np.sum(dist**2)) / disp, mask, sgn))
    ranked.sort(key=lambda r: (r[0], r[1]))
    out, seen = [], set()
    for _, _, sgn in ranked[:n_best]:
        R = np.diag(sgn)
        for _ in range(iters):
            t = _nearest_injective(tree, phi @ R, n, m, free, landmarks)
            U, _, Vt = np.linalg.svd(phi.T @ psi[t])
            R = U @ Vt
        key = t.tobytes()
        if key not in seen and np.any(t != np.arange(n)):
            seen.add(key)
            out.append(t)
    return out

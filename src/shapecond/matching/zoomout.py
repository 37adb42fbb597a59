"""The dense stage: a vertex-to-vertex map refined by ZoomOut with the landmarks as anchors.

ZoomOut (Melzi, Ren, Rodolà, Sharma, Wonka, Ovsjanikov, "ZoomOut: spectral
upsampling for efficient shape correspondence", SIGGRAPH Asia 2019) alternates
two steps on the Laplace–Beltrami bases ``Φ_s``, ``Φ_t`` of the two shapes
(``shapes.laplace``), growing the number ``k`` of basis functions by ``step``
from ``k_start`` to the whole basis:

1. the functional map of the current pointwise map ``T`` (source vertex → target
   vertex): ``C = argmin ‖Φ_s C − Π_T Φ_t‖²`` in ``L²(M_s)``, the k × k matrix that
   pulls target functions back to the source;
2. the pointwise map of ``C``: every source vertex ``x`` goes to the target
   vertex ``y`` whose row of ``Φ_t Cᵀ`` is nearest to the row ``Φ_s[x]``
   (the form of the ZoomOut paper and of pyFM; the other form, ``Φ_s C`` against
   ``Φ_t``, contracts toward the embedding's centre when ``C`` is truncated and
   ends 3× worse on independently remeshed TOSCA pairs).

Two departures, each measured on independently remeshed TOSCA pairs (5–8k
vertices, ``.vts`` ground truth), are what make it a landmark-guided stage:

* **Landmark anchors.**  ZoomOut alone ignores the landmarks: its fixed point
  is the same whether it starts from the true map or from a rough one (cat0 →
  cat1: 0.029 sqrt(area) from both), and it drifts wherever the poses are less
  isometric than the spectra can tell.  Each landmark pair contributes one
  more coordinate to both embeddings, the Gaussian ``g(x) = exp(−d(x, l)² /
  2σ²) / (σ√π)`` of the geodesic distance to the landmark (``d`` in units of
  ``sqrt(area)``), which has unit ``L²`` norm on a flat area-1 surface, like one
  basis function (its weight: below).  ``σ = π / sqrt(λ_k)`` is the half-wavelength
  of the last basis function: the anchors act at the scale the basis no longer
  resolves and leave long distances, which real poses change by 5–20 %, out.
  (dog0 → dog1 with 6 landmarks: 0.052 → 0.022; no pair got worse by more than
  2 %.)  The landmark vertices themselves are mapped exactly.
* **Harmonic coordinates of the landmarks** (``harmonic``), which two bodies or two species keep
  where they change geodesic distances, are a further block of both embeddings.
* **Block weights measured, not set.**  At every level each block's residual under the current map
  (``Φ_s[x] − Φ_t Cᵀ[T x]`` for the spectra, ``a_s(x) − a_t(T x)`` for a block ``a``) is whitened to
  the spectral residual's variance per coordinate — the weighting under which the nearest neighbour
  is the most likely match if the residuals were Gaussian.  The blocks: the anchors (the Gaussians
  with the sides of the landmark pairs, ``Anchors.blocks``) and the harmonic coordinates.  Measured
  on the SMAL_r training split (the cow matched to its 31 other animals, 6 farthest-point landmarks,
  FAQ start; the project's benchmarks): mean error 0.040 → 0.033 sqrt(area) against the fixed
  weights without harmonic coordinates; three blocks (the sides on their own) 0.035.  Started from
  the *true* map the stage ended at 0.042 before, at 0.034 with the harmonic block alone.
* **Source subsample.**  Step 2 runs on ``10 k_end`` farthest source points
  (Euclidean farthest-point sampling, Voronoi masses for step 1) against every
  target vertex, as the accelerated ZoomOut of the paper does; only the final
  map is computed for every source vertex.  Same errors as the full iteration
  (0.0289 against 0.0288 on six pairs), 3× faster.
* **The final map searched near the subsample's.**  The last pass maps every source vertex, and a
  search among every target vertex costs ``n_s n_t k`` (15 of 60 s CPU for two 52k-vertex meshes).
  A vertex of the cell of subsample point ``s`` is searched only among the target vertices within
  ``r_s`` of ``T(s)``, where ``r_s`` is the largest distance from ``T(s)`` to the images of the
  subsample points nearest ``s`` (``CELL_NEIGHBOURS``: the mean number of neighbours of a point
  in a planar triangulation, 6, by Euler's formula): a map continuous at the subsample's scale sends
  the cell between those images, and where it tears the radius grows with the tear.  Against the
  full search, from the same starts (6 exact landmarks): 0.3 % of the images change between
  5k-vertex poses (TOSCA_r, 8 pairs) and 2.1 % between species (SMAL_r, 8 pairs), the mean error by
  less than 0.1 ×10⁻³ sqrt(area); the pass costs 4-7× less there (benchmark ``final-pass``).

**Known limit: the schedule's fixed point, not the start, sets the floor.**  Started from the *true*
map, one level at the whole basis keeps 0.020 sqrt(area) between species (SMAL_r, the cow to 4
animals, 5 landmark methods: 20 rows) and 0.008 between poses (TOSCA_r, one test pair per class, 40
rows), but the shipped schedule (k from 20) ends at 0.034 and 0.016 from the truth, near where it
ends from FAQ's start (0.043 and 0.017).  Its first level (k = 20) already moves the truth to about
0.05 between species, and the finer levels settle on the schedule's fixed point, not on the truth;
repeating the whole-basis level from the truth drifts too (TOSCA_r cat2 → cat3: 0.013 after one
step, 0.019 after 20, with or without the anchors, with a least-squares or an orthogonal C), while
the schedule's own output is a fixed point of that level.  From FAQ's start the shipped schedule
beats every shorter one tried on average (on every SMAL_r row), so a better start alone gains nothing unless the
schedule is shortened with it.  Tried and rejected, each on 4–12 SMAL_r rows: a mass-preserving
(Sinkhorn) pointwise step at the subsample levels (from the truth 0.055 → 0.156 on one pair); a
bidirectional step that also matches the reverse map's functional map (+2 to +12 ×10⁻³ on all
four rows); the coordinates aligned by a similarity fitted to the current map, as a further
whitened block (−1 to −2 ×10⁻³); a multi-scale heat-kernel-signature block (+1 to +12 ×10⁻³);
every level searching only near the current map (the final pass's regions): from the truth
0.036 → 0.035 on 8 rows, from FAQ unchanged, so the drift is local sliding, level by level;
hubness-corrected neighbours (CSLS, 10 nearest) at the subsample levels: 3 % lower on 12 rows
(TOSCA_r 0.0154 → 0.0150), one row 5 % higher, not validated further; the spectral block compared
by direction only (rows scaled to one norm, which removes a local change of area between the
shapes): from FAQ 3 rows better, 5 worse (SMAL_r, 8 rows); a rectangular functional map at the
coarse levels (the ``k`` target functions represented in 1.25–2× as many source functions, since a
band-limited function pulled back through a stretching map is not band-limited at the same ``k``):
SMAL_r 8 rows −2 % from FAQ (1.5×), but TOSCA_r 16 rows (one pair per class, FPS and PLS
landmarks) worse on 12, +17 % on the FPS rows (victoria12 → victoria23: 24.1 → 31.9 ×10⁻³); a
further whitened block of each point's distances to the landmarks divided by their mean (scale-free,
long-range, where the anchors and the harmonic coordinates are flat): every SMAL_r row within
±3 ×10⁻³ (muybridge_097_01, PLS: 106.0 → 103.5, from the truth 54.7 → 54.8).  **Why no optimiser of this stage
can reach the truth between species: its objective prefers the wrong map.**  On the same 8 SMAL_r
rows (the cow to 4 animals, FPS and PLS landmarks) the spectral residual
``min_C Σ_x m_x ‖Φ_s[x] C − Φ_t[T x]‖² / k`` at the whole basis is 0.14–0.24 at the shipped output
(error 0.021–0.106) and 0.16–0.53 at the map one whole-basis step from the truth (error
0.014–0.024), higher on every row; the anchor blocks' residual likewise (0.04–0.45 against
0.06–0.76).  Plain ZoomOut (no anchor, no harmonic block) started from the truth ends at
0.022–0.053.  A better start, schedule or search of the same objective cannot close that gap; a
different objective (one the true map between two bodies minimises) is what is missing.

**Known limit: a correct landmark can cost the stage accuracy.**  On TOSCA_r (one test pair per class,
FPS/PLS/HKS/CNBS landmarks, FAQ) 6 exact landmarks end more than 5 % worse than 3 on 5–8 of 32 rows, and
on each of the five worst (david1 → david6 HKS 35 → 46 ×10⁻³ sqrt(area), michael15 → michael4 HKS and PLS,
dog10 → dog6 PLS, wolf0 → wolf2 CNBS) the loss is this stage's: the sample maps extend equally well, and
the stage anchored by the first 3 landmarks beats the stage anchored by all 6 from either sample map
(michael PLS 7.7 against 8.9, dog PLS 21.0 against 22.6; even the Gaussians alone, without the sides or
the harmonic block, lose there).  Tried and not adopted: keeping the 3-anchor map when it already sends
the other landmarks within ``σ`` of their images (nesting, as the sample matchers do): 2 violations
instead of 8, but the mean 17.9 → 19.0, since consistent extra anchors still localise the map; the
blocks whitened by the median residual instead of the mean (a Gaussian anchor's residual is zero far from
its landmark, so its median is near zero and its weight explodes): david HKS 46 → 236.

Nearest neighbours are found by blocked products in float32 (a k-d tree is
slower than a brute-force product beyond about 20 dimensions); ties go to the
lowest target index, so the map is deterministic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numba
import numpy as np
from scipy.spatial import cKDTree

from shapecond.errors import InputError
from shapecond.matching.harmonic import harmonic_coordinates
from shapecond.matching.orientation import orientation_features
from shapecond.shapes.laplace import LaplaceBasis

#: Source rows per block of the nearest-neighbour products, at most.
BLOCK = 2048
#: Bytes of one block of scores (float32, a block of source rows × every target vertex): fewer rows
#: per block on large targets (79 at 210k vertices, where 2,048 rows took 1.7 GB); the same map.
SCORE_BYTES = 64 * 2**20
#: Subsample neighbours whose images bound a cell's search in the final pass (module docstring).
CELL_NEIGHBOURS = 6


@dataclass(frozen=True)
class ZoomOutOptions:
    """Knobs of the dense stage (module docstring).

    Attributes
    ----------
    k_start : basis functions of the first functional map (ZoomOut's usual 20).
    k_end : basis functions of the last one (None: the whole basis).
    step : growth of ``k`` per iteration (10: the same errors as 5 at half the cost).
    subsample_factor : source points per basis function in the iterations.
    sigma : width of the landmark anchors in units of sqrt(area) (None: π / sqrt(λ_k_end)).
    """

    k_start: int = 20
    k_end: int | None = None
    step: int = 10
    subsample_factor: int = 10
    sigma: float | None = None

    def levels(self, k_max: int) -> list[int]:
        """The basis sizes of the iterations, ending at ``k_end`` (or ``k_max``)."""
        end = k_max if self.k_end is None else min(self.k_end, k_max)
        start = min(self.k_start, end)
        if start < 1 or self.step < 1:
            raise InputError("ZoomOut needs k_start >= 1 and step >= 1")
        ks = list(range(start, end + 1, self.step))
        return ks if ks[-1] == end else ks + [end]


@dataclass(frozen=True, eq=False)
class Anchors:
    """Landmark pairs with their geodesic distance rows, in units of sqrt(area).

    Attributes
    ----------
    source, target : (L,) int64 internal vertex ids of corresponding landmarks.
    source_rows : (L, n_s) distances from each source landmark to every source vertex.
    target_rows : (L, n_t) likewise on the target.
    """

    source: np.ndarray
    target: np.ndarray
    source_rows: np.ndarray
    target_rows: np.ndarray
    source_sides: np.ndarray | None = None
    target_sides: np.ndarray | None = None
    source_harmonic: np.ndarray | None = None
    target_harmonic: np.ndarray | None = None

    def blocks(self, sigma: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """The anchor blocks ``(source (n_s, d), target (n_t, d))`` of both embeddings (module
        docstring): the Gaussian anchor coordinates with the sides of the landmark pairs where known
        (``oriented``) — two readings of the same distance rows, their values and their gradients,
        whose relative weight their construction fixes — then the harmonic coordinates where known
        (``harmonic``), another operator's reading and so a block of its own."""
        scale = 1.0 / (sigma * math.sqrt(math.pi))

        def g(rows):
            return (scale * np.exp(-np.square(rows.T, dtype=np.float64) / (2.0 * sigma * sigma))).astype(np.float32)

        fs, ft = g(self.source_rows), g(self.target_rows)
        if self.source_sides is not None and self.target_sides is not None:
            fs, ft = np.hstack([fs, self.source_sides]), np.hstack([ft, self.target_sides])
        out = [(fs, ft)]
        if self.source_harmonic is not None and self.target_harmonic is not None:
            out.append((self.source_harmonic, self.target_harmonic))
        return out

    def oriented(self, source_geometry, target_geometry) -> "Anchors":
        """The same anchors with the sides of every landmark pair on both meshes
        (``orientation.orientation_features``; unchanged for point clouds, and where the sides are
        known already: ``problem.MatchProblem`` gives those the sample matcher read)."""
        if self.source_sides is not None and self.target_sides is not None:
            return self
        fs = orientation_features(source_geometry, self.source_rows)
        ft = orientation_features(target_geometry, self.target_rows)
        if fs is None or ft is None:
            return self
        return replace(self, source_sides=fs, target_sides=ft)

    def harmonic(self, source_geometry, target_geometry, radius: float) -> "Anchors":
        """The same anchors with the landmarks' harmonic coordinates on both shapes (``harmonic``,
        disks of ``radius`` sqrt(area)); unchanged where either shape has none."""
        hs = harmonic_coordinates(source_geometry, self.source_rows, radius)
        ht = harmonic_coordinates(target_geometry, self.target_rows, radius)
        if hs is None or ht is None:
            return self
        return replace(self, source_harmonic=hs.astype(np.float32), target_harmonic=ht.astype(np.float32))


def nearest_rows(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """For every row of ``X`` the index of the nearest row of ``Y`` (Euclidean; ties: lowest index)."""
    X = np.ascontiguousarray(X, dtype=np.float32)
    Y = np.ascontiguousarray(Y, dtype=np.float32)
    return _nearest_blocked(X, Y, 0.5 * np.einsum("ij,ij->i", Y, Y), BLOCK)


def _nearest_blocked(X: np.ndarray, Y: np.ndarray, half_norms: np.ndarray, max_rows: int) -> np.ndarray:
    """Index of the nearest row of ``Y`` for every row of ``X`` (float32), ``half_norms`` = |y|²/2,
    the scores computed for at most ``max_rows`` rows of ``X`` and ``SCORE_BYTES`` at a time."""
    out = np.empty(X.shape[0], dtype=np.int64)
    step = int(np.clip(SCORE_BYTES // (4 * max(Y.shape[0], 1)), 1, max(max_rows, 1)))
    scores = np.empty(min(step, X.shape[0]) * Y.shape[0], dtype=np.float32)  # one block's, reused:
    for s in range(0, X.shape[0], step):  # a fresh 64 MB block is mapped anew, its page faults cost
        rows = X[s:s + step]  # as much as the product (0.38 against 0.17 s at 1,500 × 52,565 × 40)
        score = np.matmul(rows, Y.T, out=scores[:rows.shape[0] * Y.shape[0]].reshape(rows.shape[0], -1))
        score -= half_norms  # argmax of x·y − |y|²/2 is the argmin of |x − y|²
        out[s:s + step] = np.argmax(score, axis=1)
    return out


def farthest_points(points: np.ndarray, m: int) -> np.ndarray:
    """``m`` farthest points in R³ (from point 0; all of them when ``m >= n``)."""
    n = points.shape[0]
    if m >= n:
        return np.arange(n)
    return _farthest_kernel(np.ascontiguousarray(points, dtype=np.float64), int(m))


@numba.njit(cache=True, error_model="numpy")
def _farthest_kernel(points, m):  # pragma: no cover - compiled
    # the arithmetic of ``np.linalg.norm(points - p, axis=1)`` term by term (no fast-math: the same
    # roundings), so the same points as the vectorised loop, without its m passes of temporaries
    n = points.shape[0]
    out = np.empty(m, dtype=np.int64)
    d = np.empty(n)
    best = 0
    for i in range(m):
        out[i] = best
        x, y, z = points[best, 0], points[best, 1], points[best, 2]
        far, arg = -1.0, 0
        for j in range(n):
            dx, dy, dz = points[j, 0] - x, points[j, 1] - y, points[j, 2] - z
            r = np.sqrt(dx * dx + dy * dy + dz * dz)
            if i == 0 or r < d[j]:
                d[j] = r
            if d[j] > far:  # the first largest, as np.argmax
                far, arg = d[j], j
        best = arg
    return out


def functional_map(phi_s: np.ndarray, weights: np.ndarray, phi_t_of_map: np.ndarray, gram=None) -> np.ndarray:
    """``C = argmin Σ_x w_x ‖Φ_s[x] C − Φ_t[T x]‖²``: the k × k map pulling target functions back.

    ``gram``: ``Φ_sᵀ W Φ_s`` when already known (its leading k × k block serves every k).
    """
    A = phi_s * weights[:, None]
    k = phi_s.shape[1]
    G = phi_s.T @ A if gram is None else gram[:k, :k]
    return np.linalg.solve(G, A.T @ phi_t_of_map)


def anchor_width(source: LaplaceBasis, target: LaplaceBasis, options: ZoomOutOptions = ZoomOutOptions()) -> float:
    """``σ`` of the anchors in sqrt(area) units: ``options.sigma``, else the half-wavelength
    ``π / sqrt(λ_k)`` of the target's last basis function (module docstring)."""
    if options.sigma is not None:
        return float(options.sigma)
    k_end = options.levels(min(source.k, target.k))[-1]
    return math.pi / math.sqrt(max(float(target.evals[k_end - 1]), 1e-12))


def zoomout(source: LaplaceBasis, target: LaplaceBasis, points: tuple[np.ndarray, np.ndarray], initial: np.ndarray,
            anchors: Anchors | None = None, options: ZoomOutOptions = ZoomOutOptions()) -> np.ndarray:
    """Refine the vertex map ``initial`` (source → target) by landmark-anchored ZoomOut.

    Parameters
    ----------
    source, target : LaplaceBasis of the two shapes.
    points : (n_s, 3) source and (n_t, 3) target vertex positions (the subsample, the final pass's
        search regions).
    initial : (n_s,) int target vertex of every source vertex.
    anchors : landmark pairs with their distance rows (None: plain ZoomOut).
    options : ZoomOutOptions.

    Returns
    -------
    (n_s,) int64 target vertex of every source vertex; the landmarks map onto their pairs.
    """
    T = np.asarray(initial, dtype=np.int64)
    if T.shape != (source.n_vertices,) or T.min() < 0 or T.max() >= target.n_vertices:
        raise InputError("the initial map does not fit the two shapes")
    levels = options.levels(min(source.k, target.k))
    k_end = levels[-1]
    blocks = anchors.blocks(anchor_width(source, target, options)) if anchors is not None else []
    points, target_points = (np.asarray(p, dtype=np.float64) for p in points)
    S = farthest_points(points, options.subsample_factor * k_end)
    _, cell = cKDTree(points[S]).query(points)
    w = np.bincount(cell, weights=source.mass, minlength=S.size)
    phi_s = np.ascontiguousarray(source.evecs[S, :k_end])
    phi_t = np.ascontiguousarray(target.evecs[:, :k_end])
    gram = phi_s.T @ (phi_s * w[:, None])
    TS = T[S]
    for k in levels:
        C = functional_map(phi_s[:, :k], w, phi_t[TS, :k], gram)
        Y = phi_t[:, :k] @ C.T
        scales = _whitening(phi_s[:, :k], Y, TS, w, blocks, S)
        TS = _pointwise(phi_s[:, :k], Y, [(a[S], b) for a, b in blocks], scales)
    C = functional_map(phi_s, w, phi_t[TS], gram)
    Y = phi_t @ C.T
    regions = _search_regions(points[S], target_points, TS)
    T = _pointwise(source.evecs[:, :k_end], Y, blocks, _whitening(phi_s, Y, TS, w, blocks, S), (cell, regions))
    if anchors is not None:
        T[anchors.source] = anchors.target
    return T


def _whitening(X, Y, TS, w, blocks, S) -> list[float]:
    """Scale of every anchor block that whitens it against the spectral block (module docstring):
    the ratio of their residual RMS per coordinate under the current map ``S → TS`` (mass ``w``).
    Where either residual vanishes (a map that already agrees exactly) there is no ratio to measure,
    and the block keeps its own scale, 1."""
    spectral = float(w @ np.square(X - Y[TS]).sum(axis=1)) / X.shape[1]
    scales = []
    for a, b in blocks:
        residual = float(w @ np.square(a[S] - b[TS], dtype=np.float64).sum(axis=1)) / a.shape[1]
        scales.append(math.sqrt(spectral / residual) if residual > 0 and spectral > 0 else 1.0)
    return scales


def _pointwise(X: np.ndarray, Y: np.ndarray, blocks, scales, regions=None) -> np.ndarray:
    """Nearest rows of ``[X, c_1 a_1, ...]`` among ``[Y, c_1 b_1, ...]`` for the blocks ``(a_i, b_i)``
    at scales ``c_i``; ``regions``: (cell of every row of X, candidate rows of Y of every cell), or
    None to search every row of Y."""
    xs, ys = _embedding(X, [a for a, _ in blocks], scales), _embedding(Y, [b for _, b in blocks], scales)
    if regions is None:
        return nearest_rows(xs, ys)
    return _nearest_in_regions(xs, ys, *regions)


def _embedding(first: np.ndarray, blocks: list, scales) -> np.ndarray:
    """``[first, c_1 b_1, ...]`` rounded to float32, written into one array: no float32 copy of
    ``first`` before the stack (126 MB for each side at 210k vertices and k = 150).  Each block is
    scaled in its own precision and then rounded, the same values as a stack of the parts."""
    widths = [first.shape[1]] + [b.shape[1] for b in blocks]
    out = np.empty((first.shape[0], sum(widths)), dtype=np.float32)
    out[:, :widths[0]] = first
    at = widths[0]
    for b, c, width in zip(blocks, scales, widths[1:]):
        out[:, at:at + width] = np.float32(c) * b
        at += width
    return out


def _search_regions(subsample_points: np.ndarray, target_points: np.ndarray, images: np.ndarray) -> list:
    """Candidate target vertices of every subsample cell (module docstring): those within the
    largest distance from the cell's image to its ``CELL_NEIGHBOURS`` nearest cells' images, and at
    least the target vertices of as many cells' worth of area (where the images collapse), sorted."""
    m, n_t = subsample_points.shape[0], target_points.shape[0]
    k = min(CELL_NEIGHBOURS + 1, m)
    _, near = cKDTree(subsample_points).query(subsample_points, k=k)
    at = target_points[images]
    radius = np.linalg.norm(at[near.reshape(m, -1)] - at[:, None, :], axis=2).max(axis=1)
    tree = cKDTree(target_points)
    floor, _ = tree.query(at, k=min(n_t, -(-k * n_t // m)))
    radius = np.maximum(radius, floor.reshape(m, -1)[:, -1])
    return [np.sort(np.asarray(r, dtype=np.int64)) for r in tree.query_ball_point(at, radius)]


def _nearest_in_regions(X: np.ndarray, Y: np.ndarray, cell: np.ndarray, regions: list) -> np.ndarray:
    """``nearest_rows`` with the rows of cell ``c`` searched among ``regions[c]`` only."""
    X = np.ascontiguousarray(X, dtype=np.float32)
    Y = np.ascontiguousarray(Y, dtype=np.float32)
    half_norms = 0.5 * np.einsum("ij,ij->i", Y, Y)
    out = np.empty(X.shape[0], dtype=np.int64)
    order = np.argsort(cell, kind="stable")
    bounds = np.searchsorted(cell[order], np.arange(len(regions) + 1))
    for c, cand in enumerate(regions):
        rows = order[bounds[c]:bounds[c + 1]]
        if rows.size:  # in blocks: a cell of a non-uniform mesh took 595 MB of scores at 210k vertices
            out[rows] = cand[_nearest_blocked(X[rows], Y[cand], half_norms[cand], rows.size)]
    return out

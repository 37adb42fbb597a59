"""An error bar on every map, from the distortion level ε̂ read off the map itself (no ground truth).

The scale-aware score δ(ε) (``symmetry.scale``) is the RMS displacement of the
widest self-map of the source that fixes the landmarks and distorts distances
by at most ε.  It bounds a matcher's error when ε is the right level, and the
right level is the distortion of the true map, which a user never has.  What a
user has is the map the matcher found:

* **ε̂, the distortion of the found map** T̂:
  ``sqrt(Σ_{x,x'} (D_s[x, x'] − D_t[T̂x, T̂x'])²) / N`` over the source's N
  samples (the RMS distortion of δ's definition), both shapes' geodesic
  distances in units of their own sqrt(area) (isometries keep the area).  It
  includes the discretisation of the two meshes, which no map avoids.
* **the level, δ(ε̂)**: the found map T̂ and the true one T differ by the
  self-map S = T⁻¹∘T̂ of the source, which fixes the landmarks (both maps send
  them to their images), and the error of T̂ is the displacement of S.  Its
  distortion is exactly ‖E_T∘S − E_T̂‖_F / N, where E_T = D_t[T, T] − D_s is
  the true map's distortion matrix and E_T̂ the found map's.  The triangle
  inequality bounds it by ε + ε̂ (≈ 2ε̂, a matcher that minimises distortion
  finding ε̂ ≤ ε), a worst case in which the two maps' distortions point in
  opposite directions; two maps of the same pose change share most of their
  distortion (the pose's bending, seen through nearly the same points), and
  independent distortions of equal size would give sqrt(2)·ε̂.  The bar takes
  the level the sentence states, ε̂ itself: "a map that fits these landmarks
  and distorts no more than this one may be wrong by up to δ".  It is an
  estimate, not a bound; how often it holds the true error, and how tight it
  is, is measured, not assumed (the evaluation's calibration table).
* **off isometry, the landmarks' own distortion**: between two bodies or two
  species the true map distorts distances more than a wrong map a matcher can
  find (a leg folded onto the body shortens nothing that a longer leg did not
  lengthen), so ε̂ reads the level too low and the bar missed the grossest
  errors (SMAL_r, cow → dog, 3 landmarks: error 0.37, bar 0.09).  The landmark
  pairs are exact correspondences: the RMS distortion ε_L of the distances
  between them is the true map's own distortion at those points, known without
  any other ground truth.  The level is max(ε̂, ε_L); between two poses of one
  body ε_L is of the order of ε̂ and changes little.
* **the doubt field**: how far the witness of δ(ε̂) (the widest such map)
  moves each sample, carried to every vertex by its nearest sample: the region
  a next landmark should fix.
* **the bar, in the field's statistic**: matching errors are reported as the
  *mean* geodesic error (Melzi et al. 2019), and δ is an RMS.  A confusable map
  that carries one part of the shape (a fraction f of the points, by a distance
  L) has RMS displacement L·sqrt(f) but mean displacement L·f, so an RMS bar
  over-states such an error by 1/sqrt(f) (about 3× for a limb).  ``bar`` is the
  mean displacement of δ's witness, the same statistic as the error it is read
  against; the largest mean displacement over the same maps lies between
  ``bar`` and ``delta`` (mean ≤ RMS), and both are reported.

The search runs on the first ``BAR_SAMPLES`` of the matcher's own samples (the
landmarks, then the farthest-point order: a coarser farthest-point cover of
the same surface) over bijections of them, so the bar needs no geodesic beyond
the target's rows at the images of those samples.  Why fewer samples than the
matcher: the δ search costs about what a witness search costs, which grows
faster than N², and the bar must stay a fraction of the matching time; the
price is resolution, δ over bijections being resolved to about half a sample
spacing h (h grows as 1/sqrt(N): sqrt(2) coarser at 200 samples than at 400),
which is far below the errors a bar must catch (a part carried elsewhere).
Errors finer than that are not resolved, and the bar does not claim them: it
is at least the resolution h/2 of its samples (``symmetry.scale.resolution``),
so a bar at that floor reads "no confusable map moves points by more than the
sampling resolves", never "this map is exact".
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InputError
from ..symmetry.scale import resolution, scale_score
from .sampled import CachedSolver, SampledSurface, surface_unit

#: Samples named in ``ErrorBar.doubt_ids``: those the witness moves farthest.
DOUBT_IDS = 10
#: The bar's samples: the first this many of the matcher's (module docstring: cost against resolution).
BAR_SAMPLES = 200


@dataclass(frozen=True, eq=False)
class ErrorBar:
    """δ(ε̂) and the bar of a map (module docstring); lengths in units of the source's sqrt(area).

    Attributes
    ----------
    epsilon_hat : RMS distortion of the map on the source's samples.
    epsilon : the level δ is taken at: ε̂, or the landmarks' own distortion ε_L when larger (module
        docstring).
    delta : δ(ε), RMS displacement of the widest map within ε fixing the landmarks.
    delta_diameter : the same as a fraction of the source's geodesic diameter.
    bar : the bar: the mean displacement of δ's witness (the statistic of a mean geodesic error), at
        least ``resolution``.
    bar_diameter : the bar as a fraction of the source's geodesic diameter.
    resolution : half the median spacing of the bar's samples: the finest error the bar resolves.
    n_samples : the samples the bar is computed on (``BAR_SAMPLES`` or all, if fewer).
    moved : fraction of the samples the witness moves.
    doubt : (N,) how far the witness moves each sample.
    doubt_ids : input vertex ids of the samples the witness moves farthest (at most ``DOUBT_IDS``).
    seconds : time of the bar (ε̂ and the δ search).
    maps : the δ search's best maps on the samples (its witness first): the warm starts of the
        searches the next-landmark suggestion runs with one more sample fixed.
    """

    epsilon_hat: float
    epsilon: float
    delta: float
    delta_diameter: float
    bar: float
    bar_diameter: float
    resolution: float
    n_samples: int
    moved: float
    doubt: np.ndarray = field(repr=False)
    doubt_ids: tuple = ()
    seconds: float = 0.0
    maps: tuple = field(default=(), repr=False)

    def to_dict(self) -> dict:
        return {"epsilon_hat": self.epsilon_hat, "epsilon": self.epsilon,
                "epsilon_source": ("the map's own distortion" if self.epsilon <= self.epsilon_hat
                                   else "the landmarks' own distortion"), "delta": self.delta,
                "delta_diameter": self.delta_diameter, "bar": self.bar, "bar_diameter": self.bar_diameter,
                "resolution": self.resolution, "n_samples": self.n_samples, "unit": "sqrt(area)", "moved": self.moved,
                "doubt_ids": [int(v) for v in self.doubt_ids], "seconds": self.seconds, "text": self.sentence()}

    def sentence(self) -> str:
        """The bar in words."""
        level = ("this one" if self.epsilon <= self.epsilon_hat else "the landmarks themselves")
        return (f"a map that fits these landmarks and distorts distances no more than {level} (RMS {self.epsilon:.3g} "
                f"sqrt(area)) may be wrong by up to {self.bar:.3g} sqrt(area) on average "
                f"({100 * self.bar_diameter:.3g} % of the diameter; RMS {self.delta:.3g}"
                + ("; the sampling's resolution" if self.bar <= self.resolution else "") + ")")


def rms_distortion(D_source, D_images) -> float:
    """ε̂ = ||D_s − D_t[T̂, T̂]||_F / N: the RMS distortion of a map of N samples (module docstring),
    from the source's distances and the target's distances between the images of the samples."""
    return float(np.linalg.norm(np.asarray(D_source) - np.asarray(D_images)) / D_source.shape[0])


def landmark_distortion(D_source, D_images, n_landmarks: int) -> float:
    """ε_L: the RMS distortion of the distances between the first ``n_landmarks`` samples (the
    landmarks) and those between their images, over the pairs of distinct landmarks (0 with fewer than
    2).  The landmark pairs are exact correspondences, so this is the true map's own distortion on
    them (module docstring)."""
    L = int(n_landmarks)
    if L < 2:
        return 0.0
    E = np.asarray(D_source)[:L, :L] - np.asarray(D_images)[:L, :L]
    return float(np.sqrt(np.sum(E * E) / (L * (L - 1))))


def _sample_distances(source: SampledSurface, target_geometry, images, solver=None) -> np.ndarray:
    """The target's distances between the images of the samples of ``source``, sqrt(area) units."""
    images = np.asarray(images, dtype=np.int64)
    if images.shape != (source.n_samples,):
        raise InputError("one target vertex per source sample is needed")
    uniq, inv = np.unique(images, return_inverse=True)
    rows = (solver if solver is not None else CachedSolver(target_geometry, source.backend)).distances(uniq)
    Dt = rows[:, uniq].astype(np.float64)[np.ix_(inv, inv)]
    return 0.5 * (Dt + Dt.T) / surface_unit(target_geometry, float(rows.max()))


def map_distortion(source: SampledSurface, target_geometry, images, solver=None) -> float:
    """RMS distortion ε̂ of the map sending the samples of ``source`` to the target vertices ``images``.

    Parameters
    ----------
    source : SampledSurface (its N samples and their distances, sqrt(area) units).
    target_geometry : Geometry of the target.
    images : (N,) internal target vertex of each source sample.
    solver : a distance solver of the target (``sampled.CachedSolver``), to reuse its rows.

    Returns
    -------
    float, in units of sqrt(area) (each shape its own).
    """
    return rms_distortion(source.D, _sample_distances(source, target_geometry, images, solver))


def bar_surface(source: SampledSurface, n_landmarks: int) -> SampledSurface:
    """The first ``BAR_SAMPLES`` samples of ``source`` (all its landmarks kept): the bar's samples."""
    m = min(source.n_samples, max(BAR_SAMPLES, int(n_landmarks)))
    return replace(source, samples=source.samples[:m], rows=source.rows[:m])


def error_bar(source: SampledSurface, n_landmarks: int, epsilon_hat: float, seed: int = 0,
              effort: str = "quick", epsilon_landmarks: float = 0.0) -> ErrorBar:
    """δ(ε̂) and the bar on the samples of ``source`` with its first ``n_landmarks`` samples fixed.

    Parameters
    ----------
    source : SampledSurface whose first samples are the landmarks (``sampled.insert_landmarks``);
        the bar is computed on all its samples (``bar_surface`` makes the usual ones).
    n_landmarks : how many of its first samples are landmarks.
    epsilon_hat : the map's distortion on these samples (``map_distortion``), sqrt(area) units.
    seed, effort : of the δ search (``symmetry.scale.scale_score``).
    epsilon_landmarks : the landmarks' own distortion ε_L (``landmark_distortion``); the level is
        the larger of the two (module docstring).
    """
    for name, v in (("map's distortion", epsilon_hat), ("landmarks' distortion", epsilon_landmarks)):
        if not (math.isfinite(v) and v >= 0):
            raise InputError(f"the {name} must be a finite number >= 0, got {v}")
    t0 = time.perf_counter()
    eps = max(float(epsilon_hat), float(epsilon_landmarks))
    D, n = source.D, source.n_samples
    res = scale_score(D, n, list(range(int(n_landmarks))), eps, seed=seed, effort=effort)
    doubt = D[np.arange(n), res.witness[:n]]
    top = np.argsort(-doubt, kind="stable")[:DOUBT_IDS]
    top = top[doubt[top] > 0]
    ids = source.geometry.ids[source.samples[top]]
    diameter = float(D.max())
    floor = resolution(D, n)
    mean = max(float(doubt.mean()), floor)

    def share(x):
        return x / diameter if diameter > 0 else 0.0
    return ErrorBar(float(epsilon_hat), eps, res.displacement, share(res.displacement), mean, share(mean), floor,
                    n, res.moved, doubt, tuple(int(v) for v in ids), time.perf_counter() - t0, res.maps)


def sample_map_bar(source: SampledSurface, target: SampledSurface, sample_map, n_landmarks: int,
                   seed: int = 0) -> ErrorBar:
    """The error bar of a map between two sample sets (``sample_map[i]`` = target sample of source sample i),
    on the first ``BAR_SAMPLES`` source samples: ε̂ from the target's distances between their images."""
    coarse = bar_surface(source, n_landmarks)
    t = np.asarray(sample_map, dtype=np.int64)[:coarse.n_samples]
    Ds, Dt = coarse.D, target.D[np.ix_(t, t)]
    return error_bar(coarse, n_landmarks, rms_distortion(Ds, Dt), seed,
                     epsilon_landmarks=landmark_distortion(Ds, Dt, n_landmarks))


def bar_and_samples(source: SampledSurface, target_geometry, vertex_map, n_landmarks: int, seed: int = 0,
                    solver=None) -> tuple[ErrorBar, SampledSurface, np.ndarray]:
    """The error bar of a dense map, with the samples it was computed on and the target's distances between
    their images (what ``suggest`` reads the next landmark off, without a new geodesic).

    Parameters
    ----------
    source : the matcher's SampledSurface of the source (landmarks first); the bar uses its first
        ``BAR_SAMPLES`` samples (``bar_surface``).
    target_geometry : Geometry of the target.
    vertex_map : (n_source,) internal target vertex of every source vertex.
    n_landmarks : the landmarks among the first samples of ``source``.
    seed : of the δ search.
    solver : the target's distance solver, to reuse its rows.

    Returns
    -------
    (ErrorBar, the bar's SampledSurface, (n, n) the target's distances between the images of its samples,
    sqrt(area) units).  The doubt of a source vertex is that of its nearest bar sample,
    ``bar.doubt[coarse.nearest]`` (``problem.MatchProblem.doubt``).
    """
    t0 = time.perf_counter()
    coarse = bar_surface(source, n_landmarks)
    Ds, Dt = coarse.D, _sample_distances(coarse, target_geometry, np.asarray(vertex_map)[coarse.samples], solver)
    bar = replace(error_bar(coarse, n_landmarks, rms_distortion(Ds, Dt), seed,
                            epsilon_landmarks=landmark_distortion(Ds, Dt, n_landmarks)),
                  seconds=time.perf_counter() - t0)
    return bar, coarse, Dt

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
* **the bar, δ(2ε̂)**: the found map T̂ and the true one T differ by the
  self-map S = T⁻¹∘T̂ of the source, which fixes the landmarks (both maps send
  them to their images).  By the triangle inequality on the Frobenius norm,
  the distortion of S is at most D(T̂) + D(T) = ε̂ + ε, and the error of T̂ is
  the displacement of S.  A matcher that minimises distortion finds D(T̂) ≤
  D(T), so ε̂ reads ε from below; the bar takes the level at 2ε̂, which is the
  triangle inequality's bound when the true map is as isometric as the found
  one (ε = ε̂, the case of a map that is right), and says so: "a map that fits
  these landmarks and distorts no more than this one may be wrong by up to δ".
  How often the bar holds the true error, and how tight it is, is measured, not
  assumed (the evaluation's calibration table).
* **the doubt field**: how far the witness of δ(2ε̂) (the widest such map)
  moves each sample, carried to every vertex by its nearest sample: the region
  a next landmark should fix.

The search runs on the matcher's own samples (the sampled surface, landmarks
first) over bijections of them, so the bar needs no geodesic beyond the
target's rows at the images of the samples.  δ over bijections is resolved to
about a sample spacing: a bar near the spacing says that no confusable map
moves points by more than about one sample.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InputError
from ..symmetry.scale import scale_score
from .sampled import CachedSolver, SampledSurface, surface_unit

#: The bar is δ at this multiple of ε̂ (the triangle inequality, module docstring).
TRIANGLE_FACTOR = 2.0
#: Samples named in ``ErrorBar.doubt_ids``: those the witness moves farthest.
DOUBT_IDS = 10


@dataclass(frozen=True, eq=False)
class ErrorBar:
    """δ(2ε̂) of a map (module docstring); lengths in units of the source's sqrt(area).

    Attributes
    ----------
    epsilon_hat : RMS distortion of the map on the source's samples.
    epsilon : the level δ is taken at, ``TRIANGLE_FACTOR × epsilon_hat``.
    delta : the bar δ(ε), RMS displacement of the widest map within ε fixing the landmarks.
    delta_diameter : the same as a fraction of the source's geodesic diameter.
    moved : fraction of the samples the witness moves.
    doubt : (N,) how far the witness moves each sample.
    doubt_ids : input vertex ids of the samples the witness moves farthest (at most ``DOUBT_IDS``).
    seconds : time of the bar (ε̂ and the δ search).
    """

    epsilon_hat: float
    epsilon: float
    delta: float
    delta_diameter: float
    moved: float
    doubt: np.ndarray = field(repr=False)
    doubt_ids: tuple = ()
    seconds: float = 0.0

    def to_dict(self) -> dict:
        return {"epsilon_hat": self.epsilon_hat, "epsilon": self.epsilon,
                "epsilon_source": "the map's own distortion (x2)", "delta": self.delta,
                "delta_diameter": self.delta_diameter, "unit": "sqrt(area)", "moved": self.moved,
                "doubt_ids": [int(v) for v in self.doubt_ids], "seconds": self.seconds, "text": self.sentence()}

    def sentence(self) -> str:
        """The bar in words."""
        return (f"a map that fits these landmarks and distorts distances no more than this one (RMS {self.epsilon_hat:.3g} "
                f"sqrt(area)) may be wrong by up to {self.delta:.3g} sqrt(area) RMS "
                f"({100 * self.delta_diameter:.3g} % of the diameter)")


def rms_distortion(D_source, D_images) -> float:
    """ε̂ = ||D_s − D_t[T̂, T̂]||_F / N: the RMS distortion of a map of N samples (module docstring),
    from the source's distances and the target's distances between the images of the samples."""
    return float(np.linalg.norm(np.asarray(D_source) - np.asarray(D_images)) / D_source.shape[0])


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
    images = np.asarray(images, dtype=np.int64)
    if images.shape != (source.n_samples,):
        raise InputError("one target vertex per source sample is needed")
    uniq, inv = np.unique(images, return_inverse=True)
    rows = (solver if solver is not None else CachedSolver(target_geometry, source.backend)).distances(uniq)
    Dt = rows[:, uniq].astype(np.float64)[np.ix_(inv, inv)]
    Dt = 0.5 * (Dt + Dt.T) / surface_unit(target_geometry, float(rows.max()))
    return rms_distortion(source.D, Dt)


def error_bar(source: SampledSurface, n_landmarks: int, epsilon_hat: float, seed: int = 0,
              effort: str = "quick") -> ErrorBar:
    """δ(2ε̂) on the samples of ``source`` with its first ``n_landmarks`` samples fixed.

    Parameters
    ----------
    source : SampledSurface whose first samples are the landmarks (``sampled.insert_landmarks``).
    n_landmarks : how many of its first samples are landmarks.
    epsilon_hat : the map's distortion (``map_distortion``), sqrt(area) units.
    seed, effort : of the δ search (``symmetry.scale.scale_score``).
    """
    if not (math.isfinite(epsilon_hat) and epsilon_hat >= 0):
        raise InputError(f"the map's distortion must be a finite number >= 0, got {epsilon_hat}")
    t0 = time.perf_counter()
    eps = TRIANGLE_FACTOR * float(epsilon_hat)
    D, n = source.D, source.n_samples
    res = scale_score(D, n, list(range(int(n_landmarks))), eps, seed=seed, effort=effort)
    doubt = D[np.arange(n), res.witness[:n]]
    top = np.argsort(-doubt, kind="stable")[:DOUBT_IDS]
    top = top[doubt[top] > 0]
    ids = source.geometry.ids[source.samples[top]]
    diameter = float(D.max())
    return ErrorBar(float(epsilon_hat), eps, res.displacement, res.displacement / diameter if diameter > 0 else 0.0,
                    res.moved, doubt, tuple(int(v) for v in ids), time.perf_counter() - t0)


def dense_error_bar(source: SampledSurface, target_geometry, vertex_map, n_landmarks: int, seed: int = 0,
                    solver=None) -> tuple[ErrorBar, np.ndarray]:
    """The error bar of a dense map and its doubt field on every source vertex.

    Parameters
    ----------
    source : the matcher's SampledSurface of the source (landmarks first).
    target_geometry : Geometry of the target.
    vertex_map : (n_source,) internal target vertex of every source vertex.
    n_landmarks : the landmarks among the first samples of ``source``.
    solver : the target's distance solver, to reuse its rows.

    Returns
    -------
    (ErrorBar, (n_source,) doubt of every source vertex, sqrt(area) units)
    """
    t0 = time.perf_counter()
    eps_hat = map_distortion(source, target_geometry, np.asarray(vertex_map)[source.samples], solver)
    bar = replace(error_bar(source, n_landmarks, eps_hat, seed), seconds=time.perf_counter() - t0)
    return bar, bar.doubt[source.nearest]

"""The symmetry score at the scale of real deformations (beyond paper Eqs. 4-5).

The paper's score is a ratio: σ(X) = sup_T d(T, Id) / D(T) (Eq. 5), and the
condition number κ (Eq. 4) the worst ratio of the change of the optimal map to
the change of the shape.  A ratio is blind to size: once landmarks have broken
a shape's mirror, the sup is attained by swapping two neighbouring samples at
a thin tip, a map whose distortion is tiny and whose displacement is below one
sample spacing — harmless to a matcher.  A user meets perturbations of a
definite size, the non-isometry of real poses, and the error a matcher makes
at that size is bounded by how far the maps it cannot tell from the identity
move the points.  For a distortion level ε this module computes

    δ(ε) = max { d_rms(T) : T fixes the landmarks, D_rms(T) ≤ ε },

    d_rms(T) = sqrt(d²(T) / N) = sqrt(Σ_x D[x, Tx]² / N)            (Eq. 2, RMS),
    D_rms(T) = sqrt(Dist²(T)) / N = sqrt(Σ_{x,x'} (D[x,x'] − D[Tx,Tx'])²) / N   (Eq. 3, RMS):

the largest RMS displacement of a self-map whose RMS distortion stays within
ε — the error a distortion-minimising matcher may make, without any landmark
being wrong, when the shape is deformed by about ε (if X̃ distorts distances
by ε, a map T distorting X by D(T) ≤ 2ε can score no worse on X̃ than the
identity does, by the triangle inequality on ‖·‖_F).  Relation to the paper:
δ(ε) ≥ ε·σ_T for every map T with D_rms(T) = ε, and δ(ε)/ε plays the part of
κ at scale ε (``ScaleScore.amplification``).

Properties (tested against enumeration at N ≤ 9):

* δ is non-decreasing in ε and non-increasing as landmarks are added (the
  feasible set grows, resp. shrinks);
* an exact symmetry T (D(T) = 0) gives δ(ε) ≥ d_rms(T) for every ε ≥ 0, its full
  displacement: the largest value any map of that displacement can have;
  without a non-trivial isometry δ(0) = 0.

Computation: maximise d² subject to Dist² ≤ (εN)² by the witness search with a
budget (``search.witness_search(budget=...)``, the Lagrangian d² − s·Dist² of its
fixed-s ladder among its starts); the result is a certified lower bound of
δ(ε), attained by the returned witness (the map a matcher is most likely to
confuse with the identity at that scale).

Default ε (``default_epsilon``): the median distance from a sample to its
nearest other sample, h — measured from the input.  Distances cannot be
resolved below the sampling's spacing, and real poses deform that much: the
ground-truth maps between TOSCA poses distort the distances of N = 400
corresponding samples by 0.4-1.7 h RMS (median 1.0 h; benchmarks, section
"scale").  ``epsilon`` sets it explicitly (units of D; a metric shape has
diameter 1).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from shapecond.errors import InputError
from shapecond.symmetry import objective as obj
from shapecond.symmetry.search import prepare_instance, witness_search


def default_epsilon(D, n_samples=None) -> float:
    """The median distance from a sample to its nearest other sample (units of D)."""
    D = np.asarray(D, dtype=np.float64)
    n = D.shape[0] if n_samples is None else int(n_samples)
    X = D[:n, :n] + np.diag(np.full(n, np.inf))
    return float(np.median(X.min(axis=1)))


def resolution(D, n_samples=None) -> float:
    """Half the median sample spacing, h / 2 (units of D): how finely δ is resolved.

    A self-map of the continuous shape is seen on the samples through the nearest
    sample of each image, which moves every point by up to about h / 2; two maps
    whose RMS displacements differ by less than that are not told apart by the
    sampling.  CNBS on δ treats heat-map values this close to the smallest as a tie
    and breaks it by the distance to the landmarks so far (``cnbs.HeatMap.argmin``).
    """
    return 0.5 * default_epsilon(D, n_samples)


def budget_of(epsilon: float, n: int, D=None) -> float:
    """Dist² budget of an RMS distortion ε over N samples: (εN)².

    With ``D`` it is at least the round-off level of an isometry
    (``objective.isometry_floor``), so that ε = 0 admits the exact symmetries of
    stored (rounded) data.
    """
    b = (float(epsilon) * n) ** 2
    if D is not None:
        b = max(b, obj.isometry_floor(D, n))
    return b


@dataclass(frozen=True)
class ScaleScore:
    """δ(ε) (module docstring) with its witness.

    Attributes
    ----------
    displacement : δ(ε), lower bound: RMS displacement of the witness (units of D).
    epsilon : the RMS distortion budget ε.
    distortion : RMS distortion of the witness (≤ ε).
    witness : (N,) map attaining ``displacement`` (witness[i] = T(sample i)).
    moved : fraction of the samples the witness moves.
    isometry : True when the witness is an isometry (round-off distortion).
    n_points, n_targets, landmarks, seconds : as for ``SymmetryScore``.
    maps : distinct good maps found (warm starts for heat maps).
    """

    displacement: float
    epsilon: float
    distortion: float
    witness: np.ndarray
    moved: float
    isometry: bool
    n_points: int
    n_targets: int
    landmarks: tuple
    seconds: float
    maps: tuple = field(default=(), repr=False)

    def __repr__(self) -> str:
        kind = " (an isometry)" if self.isometry else ""
        return (f"ScaleScore(delta={self.displacement:.4g} at epsilon={self.epsilon:.4g} (x{self.amplification:.3g}), "
                f"distortion {self.distortion:.4g}, witness moves {self.moved:.0%} of the samples{kind}, "
                f"N={self.n_points}, M={self.n_targets}, {len(self.landmarks)} landmarks, {self.seconds:.2f} s)")

    @property
    def amplification(self) -> float:
        """δ(ε) / ε: how many times the distortion level the worst confusable map moves points."""
        return self.displacement / self.epsilon if self.epsilon > 0 else math.inf

    def to_dict(self) -> dict:
        return {"displacement": self.displacement, "epsilon": self.epsilon,
                "amplification": self.amplification, "distortion": self.distortion,
                "moved": self.moved, "isometry": self.isometry,
                "witness": [int(v) for v in self.witness], "n_points": self.n_points,
                "n_targets": self.n_targets, "landmarks": [int(v) for v in self.landmarks],
                "seconds": self.seconds}


def describe(D, n, t, epsilon, landmarks, seconds=0.0, maps=()) -> ScaleScore:
    """The ``ScaleScore`` of a given feasible map ``t``."""
    t = np.asarray(t, dtype=np.int64)
    d2, dist2 = obj.d2(D, t), obj.dist2(D, t)
    return ScaleScore(math.sqrt(d2 / n), float(epsilon), math.sqrt(dist2) / n, t,
                      float(np.mean(t != np.arange(n))), d2 > 0 and obj.is_isometry(D, dist2, n), n,
                      int(D.shape[0]), tuple(int(v) for v in landmarks), seconds, tuple(maps))


def scale_score(D, n_samples=None, landmarks=(), epsilon=None, seed=0, effort="default", starts=(),
                time_limit=None) -> ScaleScore:
    """Lower bound of δ(ε) with its witness (module docstring).

    Parameters
    ----------
    D : (M, M) distances; the samples X are the first ``n_samples`` points
        (M > N: maps may send samples to the denser targets, as for σ).
    landmarks : sample indices fixed by every map.
    epsilon : RMS distortion budget (units of D); default ``default_epsilon``.
    seed, effort, starts, time_limit : passed to ``witness_search``.
    """
    t0 = time.perf_counter()
    D, n, lm, _ = prepare_instance(D, n_samples, landmarks)
    eps = default_epsilon(D, n) if epsilon is None else float(epsilon)
    if not (eps >= 0 and math.isfinite(eps)):
        raise InputError(f"the distortion level epsilon must be a finite number >= 0, got {epsilon}")
    res = witness_search(D, n, lm, seed=seed, starts=starts, effort=effort, time_limit=time_limit,
                         budget=budget_of(eps, n, D))
    return describe(D, n, res.witness, eps, lm, time.perf_counter() - t0, res.maps)

"""What the symmetry score means for matching, in one line.

``verdict(score, ...)`` reads the bracket of σ (paper Eq. 5), the witness map
and, when known, the resolution report and the covering radius r of the
samples, and says in words what a matcher faces:

* **exact symmetry** (σ = ∞): a self-map moving k % of the samples preserves
  every distance: no matcher can tell a point from its image; landmarks must be
  placed off the map's fixed set;
* **symmetric within resolution**: σ keeps growing with the target density and
  the witness distorts distances by no more than the sampling noise r;
* **local swap only**: the witness is the best single swap (σ at the swap
  floor): no near-symmetry moving many points was found;
* **near-symmetry**: the witness moves k % of the samples by an RMS displacement
  d (in % of the diameter) while distorting distances by only e, so a matcher
  can confuse them where distortions of that size occur;
* **well-conditioned**: the upper end is finite (small N): every self-map far
  from the identity distorts distances by at least 1/σ_upper of how far it
  moves the points.

When the scale-aware score δ(ε) is given (``symmetry.scale``), the last two
cases are judged at the scale of real deformations instead: **ambiguous at
scale ε** when the widest self-map distorting distances by at most ε moves the
samples by more than ``LOCAL_AMPLIFICATION`` ε (RMS) — a matcher may confuse
them under a deformation of that size — and **no global ambiguity at scale ε**
otherwise (the maps within ε only shift samples by about a spacing or two).

Distances are in units of the diameter (``MetricShape.D`` has max 1).

Examples
--------
>>> import numpy as np
>>> from shapecond.symmetry.score import symmetry_score
>>> from shapecond.symmetry.verdict import verdict
>>> square = np.array([[0, 1, 1.4142, 1], [1, 0, 1, 1.4142], [1.4142, 1, 0, 1], [1, 1.4142, 1, 0]])
>>> verdict(symmetry_score(square / 1.4142)).split(":")[0]
'exact symmetry'
"""

from __future__ import annotations

import math

import numpy as np

from . import objective as obj


def witness_stats(D: np.ndarray, witness) -> dict:
    """Share of samples moved, RMS displacement sqrt(d²/N) and RMS distortion sqrt(Dist²)/N."""
    t = np.asarray(witness, dtype=np.int64)
    n = t.size
    return {"moved": float(np.mean(t != np.arange(n))) if n else 0.0,
            "displacement_rms": math.sqrt(obj.d2(D, t) / n) if n else 0.0,
            "distortion_rms": math.sqrt(obj.dist2(D, t)) / n if n else 0.0}


#: δ(ε) up to this many ε counts as local jitter (a shift by a sample spacing or two, the
#: plateau δ(ε) reaches on TOSCA once the global symmetries are broken: 2.0-2.3 ε).
LOCAL_AMPLIFICATION = 3.0


def farthest_moved(D: np.ndarray, witness, ids=None) -> int:
    """The sample a map moves farthest (``ids[i]`` when given: its input id): where a landmark fixes most."""
    t = np.asarray(witness, dtype=np.int64)
    n = t.size
    i = int(np.argmax(np.asarray(D)[np.arange(n), t]))
    return int(ids[i]) if ids is not None else i


def verdict(score, D=None, resolution=None, covering_radius: float | None = None, scale=None, ids=None) -> str:
    """One line saying what ``score`` (a ``SymmetryScore``) means for matching.

    Parameters
    ----------
    score : SymmetryScore
    D : the distance matrix the score was computed on (for the witness's
        displacement and distortion); without it only the bracket is used.
    resolution : ResolutionReport or None (dense targets on a mesh).
    covering_radius : the samples' covering radius, in units of the diameter.
    scale : ScaleScore or None: δ(ε) with its witness.
    ids : input ids of the samples: the verdict then names the region a landmark should fix (the
        sample the witness, or δ's witness when the verdict is read at scale ε, moves farthest).
    """
    lo, hi = score.sigma_lower, score.sigma_upper
    stats = witness_stats(D, score.witness) if D is not None else None
    moved = f"{100 * stats['moved']:.0f} %" if stats else "some"
    fix = "fix at least one landmark that this map moves"
    if D is not None and ids is not None:
        w = scale.witness if scale is not None and scale.epsilon > 0 and math.isfinite(lo) else score.witness
        fix += f", e.g. near vertex {farthest_moved(D, w[:len(score.witness)], ids)} (moved farthest)"
    if math.isinf(lo):
        return (f"exact symmetry: a self-map that moves {moved} of the samples preserves every distance, "
                f"so no matcher can tell them from their images; {fix}")
    if resolution is not None and resolution.flag in ("symmetric", "symmetric within resolution"):
        r = resolution.covering_radius
        noise = f" (covering radius {r:.3g} of the diameter)" if r else ""
        return (f"symmetric within resolution: a self-map that moves {moved} of the samples distorts distances "
                f"no more than sampling noise{noise}; {fix}")
    if math.isfinite(hi):
        return (f"well-conditioned: every self-map distorts distances by at least {1 / hi:.3g} times how far "
                f"it moves the points (σ <= {hi:.3g}, κ <= {2 * hi + 1:.3g})")
    if scale is not None and scale.epsilon > 0:
        at = (f"at the scale of real deformations (distances distorted by ε = {100 * scale.epsilon:.2g} % of "
              f"the diameter, RMS)")
        if scale.amplification > LOCAL_AMPLIFICATION:
            return (f"ambiguous {at}: a self-map that moves {100 * scale.moved:.0f} % of the samples by "
                    f"{100 * scale.displacement:.2g} % of the diameter ({scale.amplification:.2g} ε, RMS) stays within "
                    f"that distortion, so a matcher can confuse them; {fix}")
        return (f"no global ambiguity {at}: the widest self-map found within that distortion moves the samples "
                f"by {scale.amplification:.2g} ε (RMS), a shift of a sample spacing or two")
    if lo <= score.swap_floor * (1 + 1e-9) and stats and stats["moved"] * len(score.witness) <= 2:
        return (f"no near-symmetry found: the best self-map only swaps two nearby samples (σ >= {lo:.3g}, "
                "the single-swap floor); matching is limited by the sampling, not by an ambiguity")
    if stats is None:
        return f"near-symmetry: a self-map reaches σ >= {lo:.3g}; matching can confuse the points it moves"
    size = "" if covering_radius is None else f" ({stats['distortion_rms'] / covering_radius:.2g} covering radii)"
    return (f"near-symmetry: a self-map that moves {moved} of the samples by {100 * stats['displacement_rms']:.2g} % "
            f"of the diameter (RMS) distorts distances by only {100 * stats['distortion_rms']:.2g} %{size} "
            f"(σ >= {lo:.3g}); matching can confuse them, {fix}")

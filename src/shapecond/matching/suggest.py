"""The next landmark, read off a match: CNBS's greedy step run on the pair instead of the single shape.

CNBS (paper Section 5) fixes, before any matching, the points of one shape
whose fixing leaves its self-maps least confusable.  After a match the pair
says more, and three things of it are at hand when the error bar has been
computed (``error_bar``), on the bar's samples with no new geodesic:

* the level ε of this pair (the map's own distortion, or the landmarks' when
  larger), and at that level the **doubt** of every sample: how far the
  widest map that fits the landmarks and distorts no more moves it;
* where **the found map itself disagrees with the landmarks**: a part carried
  to the wrong place has the wrong distances to them,
  ``r(x) = sqrt(mean_l (D_s[x, l] − D_t[T x, T l])²)``, a lower bound of how far
  ``T x`` is from an image that keeps those distances (triangle inequality),
  inflated evenly where the two shapes differ;
* the **evidence** ``e(x) = max(r(x) − ε, 0)``: the disagreement beyond the
  pair's own level of distortion, where the map is visibly wrong.  ``r`` is a
  lower bound of the error (under isometry) and the doubt an upper estimate
  ("may be wrong by up to").

The suggested point is **the sample farthest from every landmark among those
the pair leaves in doubt** (evidence above zero, or doubt above the resolution
h/2 of the samples below which the bar claims nothing); when nothing is in
doubt, the farthest sample.  The δ search is then repeated with it fixed (one
search at the same level: the bar expected after it, and the doubt that ranks
the next point).  Why the farthest and not the most suspicious: a matcher
propagates a correspondence at an extremity, not at a wrong point.  Measured
on SMAL_r (cow → 8 species, FAQ, from 3 farthest-point landmarks, each
suggestion clicked at its true image): picking the point whose cell held the most
evidence (the first version) left the mean error at 58 → 60 → 57 → 58 ×10⁻³
sqrt(area) while the farthest point took it to 41; on cow → muybridge_097 the
worst-mapped sample (error 0.44) fixed left the map at 0.158, the farthest
one took it to 0.055.  Ranking the doubtful samples by the bar expected after
each (δ with the point fixed, warm-started from the bar's witness maps as CNBS's
heat map does: the paper's greedy step at the pair's level) was no better:
35/32/31 and 22/21/22 ×10⁻³ after +1/+2/+3 on the first two of those pairs,
against 34/31/31 and 21/20/20 for the farthest point; on TOSCA_r (8 test
pairs, from 3 PLS landmarks) the bar after each of the 8 farthest doubtful
samples chose among them no better than the farthest alone (19.1/18.0/15.6
against 19.1/18.1/15.7 ×10⁻³ sqrt(area) after +1/+2/+3; another candidate was
taken only where its bar after was lower by more than the samples'
resolution).  Where the doubt is broad (most maps between species) this is
farthest-point sampling continued; where it is local (a swapped limb), the tip
of the doubtful part.  Between species the
dense stage itself sets the floor: started from the *true* map with 9 landmarks
it ends at 0.031 sqrt(area) on those pairs, so no choice of 3 more points takes
a 6-landmark match (0.034) much lower.  ``gain`` reports what the point's cell
(the samples nearer to it than to every landmark) holds of the suspicion
``max(evidence, doubt)``, divided by N: the mean error its correspondence may
remove if it repairs its cell.

``CNBS-scale`` at the same ε is the source-only counterpart (``selection``):
it ranks points by the doubt alone and needs a heat map of searches; here one
search per suggested point, on the bar's ``BAR_SAMPLES`` samples.

**Each search continues the one before it** (``SEARCH``: the bar's δ search for
the first point, then the previous point's): its best maps, repaired to fix the
new point, are the starts, followed by the kicks of an iterated local search
(``symmetry.search`` effort ``warm``), not the structured starts a fresh
instance needs — the instance differs by one fixed sample.  Measured against
fresh ``quick`` searches, 3 suggestions from 3 farthest-point landmarks (the
project's benchmarks, 8 SMAL_r and 8 TOSCA_r pairs): CPU 127–130 % → 7–10 % of
a 5k-vertex match, the same three points in order on 13 of 16 pairs (the first
point on all: it is read off the bar), ``bar_after`` within 0.94–1.11 of the
fresh search's (median 1.00: as often the larger, i.e. the better, lower bound).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..symmetry.scale import resolution, scale_score

#: Effort of the δ search after each suggested point: continued from the previous search's maps.
SEARCH = "warm"


@dataclass(frozen=True)
class Suggestion:
    """One suggested landmark.

    Attributes
    ----------
    vertex : internal source vertex.
    source_id, image_id : the source's input id and its provisional image's input id under the found map.
    gain : what its cell holds of the suspicion, divided by N (sqrt(area) units; module docstring).
    suspicion : ``max(evidence, doubt)`` at the point.
    bar_after : the error bar with this point (and the ones before it) fixed, at the same level.
    """

    vertex: int
    source_id: int
    image_id: int
    gain: float
    suspicion: float
    bar_after: float

    def to_dict(self) -> dict:
        return {"source_id": self.source_id, "image_id": self.image_id, "gain": self.gain,
                "suspicion": self.suspicion, "bar_after": self.bar_after}


def landmark_disagreement(D_source, D_images, n_landmarks: int) -> np.ndarray:
    """``r(x)`` of every sample (module docstring): RMS over the landmarks of the difference between its
    distances to them and its image's distances to theirs."""
    L = int(n_landmarks)
    E = np.asarray(D_source)[:, :L] - np.asarray(D_images)[:, :L]
    return np.sqrt(np.mean(E * E, axis=1))


def cell_gains(D, fixed, suspicion) -> np.ndarray:
    """Expected gain of fixing each sample: the suspicion of the samples nearer to it than to every fixed
    sample, divided by the number of samples (module docstring); 0 for the fixed ones."""
    D = np.asarray(D)
    nearest_fixed = D[:, list(fixed)].min(axis=1)
    gains = (D < nearest_fixed[:, None]).T.astype(np.float64) @ np.asarray(suspicion, dtype=np.float64)
    gains /= D.shape[0]
    gains[list(fixed)] = 0.0
    return gains


def suggest_landmarks(coarse, D_images, bar, n_landmarks: int, vertex_map, target_ids, k: int = 1,
                      seed: int = 0) -> list[Suggestion]:
    """The ``k`` next landmarks of a match, in order (module docstring).

    Parameters
    ----------
    coarse : the bar's SampledSurface (landmarks first; ``error_bar.bar_surface``).
    D_images : (n, n) the target's distances between the images of its samples, sqrt(area) units.
    bar : the map's ``error_bar.ErrorBar`` on these samples (its level ``epsilon`` and ``doubt``).
    n_landmarks : landmarks among its first samples.
    vertex_map : (n_source,) internal target vertex of every source vertex (the found map).
    target_ids : input ids of the target's internal vertices.
    k : how many points; seed : of the δ searches.
    """
    if not (isinstance(k, (int, np.integer)) and not isinstance(k, bool) and k >= 1):
        raise InputError(f"the number of suggested landmarks must be a positive integer, got {k!r}")
    D, n = coarse.D, coarse.n_samples
    fixed = list(range(int(n_landmarks)))
    if not fixed:
        raise InputError("suggesting a next landmark needs at least one landmark")
    r = landmark_disagreement(D, D_images, n_landmarks)
    epsilon, doubt = bar.epsilon, np.asarray(bar.doubt, dtype=np.float64)
    floor = resolution(D, n)
    evidence = np.maximum(r - float(epsilon), 0.0)
    out, maps = [], tuple(bar.maps)
    for _ in range(min(int(k), n - len(fixed))):
        s = np.maximum(evidence, doubt)
        gains = cell_gains(D, fixed, np.maximum(s, floor))
        far = D[:, fixed].min(axis=1)
        doubtful = (far > 0) & ((evidence > 0) | (doubt > floor))
        x = int(np.argmax(np.where(doubtful if doubtful.any() else far > 0, far, -1.0)))
        if far[x] <= 0:
            break
        fixed.append(x)
        res = scale_score(D, n, fixed, epsilon, seed=seed, effort=SEARCH, starts=maps)
        maps = res.maps
        doubt = D[np.arange(n), res.witness[:n]]
        v = int(coarse.samples[x])
        out.append(Suggestion(v, int(coarse.geometry.ids[v]), int(target_ids[int(vertex_map[v])]), float(gains[x]),
                              float(s[x]), max(float(doubt.mean()), floor)))
    return out

"""The landmark sets of an evaluation: each method's landmarks on a null shape, and their scores.

Every method runs on the null shape's metric shape (N samples); the landmarks
are recorded as internal vertex ids of the null shape (``vertices``) and as the
file's ids (``ids``).  Cached on disk: CNBS at N = 400 takes minutes per class.

Beside the library's methods, ``cnbs-scale-hat`` is CNBS-scale at the class's
level read off its matched maps (``api.level.collection_level``: the null shape
matched to its first targets without landmarks or ground truth), where
``cnbs-scale`` takes the default ε: what a user with a collection runs.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

from .. import cache as disk
from ..api import landmarks, metric_shape
from ..errors import InputError
from ..limits import CostWarning
from ..selection import METHODS, monotone
from ..symmetry.scale import scale_score
from ..symmetry.score import ScoreOptions, symmetry_score
from ..symmetry.search import best_single_swap

#: Landmark counts of the paper's Figure 7 per TOSCA class (other classes: ``DEFAULT_LANDMARKS``).
PAPER_LANDMARKS = {"horse": 14, "victoria": 13, "michael": 16, "david": 15, "dog": 12,
                   "centaur": 7, "cat": 7, "wolf": 5}
DEFAULT_LANDMARKS = 10
#: bump when the landmark methods change, to invalidate cached selections
LANDMARK_CACHE_VERSION = "8"  # 8: HKS on the robust Laplace-Beltrami basis; 7: CNBS kicks of at most 12 swaps
#: Relative cost of the landmark methods on TOSCA at N = 400, for ordering the tasks only.
LANDMARK_COST = {"cnbs-scale": 4, "cnbs-scale-hat": 4, "cnbs": 3, "cnbs-local": 2, "hks": 1}
#: Evaluation-only methods: a library method run at the class's level read off its matched maps.
AT_CLASS_LEVEL = {"cnbs-scale-hat": "cnbs-scale"}


@dataclass(frozen=True)
class ShapeSetup:
    """How every shape of an evaluation is sampled: N, FPS seed, geodesic backend, cache."""

    n_points: int = 400
    seed: int = 0
    backend: str = "heat"
    cache: bool = True

    def metric_shape(self, x):
        """The null shape's metric shape (``sc.metric_shape``: the paper's N samples, bijections);
        the evaluation checked its whole cost up front, so nothing is refused here."""
        return metric_shape(x, self.n_points, backend=self.backend, seed=self.seed, cache=self.cache,
                            target="samples", force=True)


def check_method(name: str) -> None:
    """``InputError`` for an unknown landmark method (before any work)."""
    if name not in METHODS and name not in AT_CLASS_LEVEL:
        raise InputError(f"unknown landmark method {name!r} (choose from {', '.join([*METHODS, *AT_CLASS_LEVEL])})")


def sigma_lower_bound(D, n_samples, landmarks, seed=0, quick=False) -> float:
    """σ (Eq. 5) with the given sample indices fixed: the witness search's lower bound.

    At N = 400 only the lower bound with its witness is affordable (no exact solve,
    no LP); ``quick`` uses ``effort="quick"``.
    """
    res = symmetry_score(D, n_samples, list(landmarks),
                         options=ScoreOptions(exact=False, upper=False, seed=seed, effort="quick" if quick else "default"))
    return float(res.sigma_lower)


def swap_floor(D, n_samples, landmarks) -> float:
    """σ of the best single swap avoiding the landmarks."""
    return float(best_single_swap(D, n_samples, list(landmarks))[0])


def _scores(shape, idx, seed) -> dict:
    """σ, its swap floor and δ(ε) after 1, 3 and all landmarks (δ made non-increasing)."""
    scores, floor, scale = {}, {}, {}
    counts = sorted({1, min(3, len(idx)), len(idx)})
    for c in counts:
        scores[c] = sigma_lower_bound(shape.D, shape.n_samples, idx[:c], seed, True)
        floor[c] = swap_floor(shape.D, shape.n_samples, idx[:c])
        scale[c] = scale_score(shape.D, shape.n_samples, idx[:c], seed=seed, effort="quick").displacement
    return dict(scores=scores, floor=floor, scale=dict(zip(counts, monotone([scale[c] for c in counts]))))


def landmark_task(cls: str, null_path, method: str, k: int, setup: ShapeSetup, quick: bool = False,
                  epsilon: float | None = None, scores: bool = True) -> dict:
    """Landmarks of one method on the null shape and the scores after 1, 3 and k of them.

    Scores: the quick witness search's σ for every method alike, so that Figure 7a
    compares one estimator (CNBS's own heat-map values are lower bounds from warm
    starts and would not be comparable with the baselines'); ``floor``: the best
    single swap with the same landmarks, to show when a score is only that;
    ``scale``: δ(ε) at the default ε (``symmetry.scale``), non-increasing in the count.
    ``epsilon``: the class's level, for the methods of ``AT_CLASS_LEVEL``.  ``scores=False`` leaves the
    scores out (empty tables): a pairs list makes one landmark set per source, where they cost more than
    the matchings.
    """
    import warnings

    st = Path(null_path).stat()
    key = disk.key_of(LANDMARK_CACHE_VERSION, str(Path(null_path).resolve()), st.st_size, st.st_mtime_ns,
                      method, k, setup.n_points, setup.seed, setup.backend, quick,
                      *([epsilon] if method in AT_CLASS_LEVEL else []), *([] if scores else ["no scores"]))
    d = disk.load_json("landmarks", key, _check_entry) if setup.cache else None
    if d is not None:
        for name in ("scores", "floor", "scale"):
            d[name] = {int(c): float(v) for c, v in d[name].items()}
        return d
    t0 = time.perf_counter()
    shape = setup.metric_shape(null_path)
    with warnings.catch_warnings():  # the evaluation announced its whole cost up front
        warnings.simplefilter("ignore", CostWarning)
        level = {"epsilon": epsilon} if method in AT_CLASS_LEVEL else {}
        idx = [int(i) for i in landmarks(shape, k, AT_CLASS_LEVEL.get(method, method), seed=setup.seed, force=True,
                                         **level).sample_indices][:k]
    seconds = time.perf_counter() - t0
    out = dict(cls=cls, method=method, vertices=[int(shape.samples[i]) for i in idx],
               ids=[int(v) for v in shape.sample_ids[idx]],
               **(_scores(shape, idx, setup.seed) if scores else dict(scores={}, floor={}, scale={})),
               seconds=seconds, score_source="search")
    if setup.cache:
        disk.save_json("landmarks", key, {**out, "scores": {c: _json_float(v) for c, v in out["scores"].items()},
                                          "floor": {c: _json_float(v) for c, v in out["floor"].items()}})
    return out


def _json_float(v: float):
    return "inf" if v == math.inf else v


def _check_entry(d) -> None:
    """Refuse a cached landmark selection that does not have the expected fields."""
    for name in ("cls", "method", "vertices", "ids", "scores", "floor", "scale", "seconds"):
        if name not in d:
            raise InputError(f"field {name!r} is missing")
    if len(d["vertices"]) != len(d["ids"]) or not all(isinstance(v, int) and v >= 0 for v in d["vertices"]):
        raise InputError("its landmark vertices are not vertex indices")

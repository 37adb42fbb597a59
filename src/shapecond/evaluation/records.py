"""What an evaluation measured: one record per matching, and the whole run."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..jsonable import jsonable


@dataclass(frozen=True)
class MatchRecord:
    """One matching of a class's null shape to a target (one row of the evaluation).

    Attributes
    ----------
    cls, target, method, n_landmarks, matcher, protocol : what was matched, and how.
    error : mean error, % of half the target's geodesic diameter.
    error_area : mean error / sqrt(target area) (the field's unit; NaN for point clouds).
    sample_error : mean error of the sample map, % of half the diameter (NaN: no sample map).
    seconds : time of the matching (the error measurement excluded).
    errors : per-evaluation-point errors (% of half the diameter), float32; at most
        ``MAX_CURVE_POINTS`` of them, evenly spaced over the evaluation points (curves only).
    exact, recall, objective_ratio : corresponding protocol (module ``protocols``).
    flipped : remeshed protocol with a reference symmetry: 1.0 when the mean error exceeds half
        the mean distance between mirror images (a left–right flip), else 0.0; NaN otherwise.
    epsilon_hat : RMS distortion of the map itself on the null shape's first samples, sqrt(area)
        units (``matching.error_bar``: read without ground truth; NaN without error bars).
    bar : the map's error bar in units of sqrt(area): the mean displacement of the witness of
        δ(ε̂) (``matching.error_bar``), the statistic of ``error_area``.
    """

    cls: str
    target: str
    method: str
    n_landmarks: int
    matcher: str
    error: float
    error_area: float
    sample_error: float
    seconds: float
    errors: np.ndarray = field(repr=False)
    protocol: str = "independent"
    exact: float = math.nan
    recall: float = math.nan
    objective_ratio: float = math.nan
    flipped: float = math.nan
    epsilon_hat: float = math.nan
    bar: float = math.nan

    FIELDS = ("cls", "target", "method", "n_landmarks", "matcher", "protocol", "error", "error_area",
              "sample_error", "exact", "recall", "objective_ratio", "flipped", "epsilon_hat", "bar", "seconds")

    def to_dict(self) -> dict:
        return jsonable({k: getattr(self, k) for k in self.FIELDS})


#: Per-point errors kept per record for the cumulative curves.
MAX_CURVE_POINTS = 4096


def curve_points(errors: np.ndarray) -> np.ndarray:
    """At most ``MAX_CURVE_POINTS`` evenly spaced entries of ``errors``, as float32."""
    e = np.asarray(errors)
    step = max(1, math.ceil(e.size / MAX_CURVE_POINTS))
    return e[::step].astype(np.float32)


@dataclass
class Evaluation:
    """Everything ``evaluate_dataset`` measured (``report`` turns it into Markdown and HTML)."""

    landmarks: list            # dicts of landmark_sets.landmark_task
    records: list              # MatchRecord
    settings: dict
    seconds: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Settings, timings, landmarks and one row per matching, as JSON-ready values."""
        return jsonable(dict(settings=self.settings, seconds=self.seconds, landmarks=self.landmarks,
                             records=[r.to_dict() for r in self.records]))

    def __repr__(self) -> str:
        return (f"Evaluation({len(self.settings.get('classes', []))} classes, {len(self.records)} matchings, "
                f"methods {self.settings.get('methods')}, matchers {self.settings.get('matchers')})")

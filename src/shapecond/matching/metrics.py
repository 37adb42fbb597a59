"""Matching errors (paper Section 7, Figure 7b; Princeton benchmark protocol).

The error of a predicted correspondence ``v -> p`` whose true image is ``g``
is the geodesic distance ``d_t(p, g)`` on the **target**.  Two normalisations:

* ``"half_diameter"`` (the paper): in % of half the target's geodesic diameter,
  ``100 · d_t(p, g) / (diam_t / 2)``;
* ``"sqrt_area"`` (Kim, Lipman, Funkhouser 2011, the Princeton benchmark):
  ``d_t(p, g) / sqrt(area_t)``.

Distances come from target distance rows (``rows[i]`` = distances from the
``i``-th evaluation point to every target vertex): the geodesic distance is
symmetric, so ``d_t(p, g)`` is read in the row of whichever of the two points
has one.  Curves are the benchmark's cumulative form: the fraction of
correspondences with error at most each threshold.
"""

from __future__ import annotations

import numpy as np

from shapecond.errors import InputError

NORMALISATIONS = ("half_diameter", "sqrt_area")


def errors_from_rows(rows: np.ndarray, predicted) -> np.ndarray:
    """``rows[i, predicted[i]]``: raw geodesic error of each evaluation point.

    Parameters
    ----------
    rows : (E, n) array
        Row ``i`` holds target distances from the true image of point ``i``.
    predicted : (E,) int array
        Predicted target vertex of point ``i``.
    """
    predicted = np.asarray(predicted, dtype=np.int64)
    if predicted.shape != (rows.shape[0],):
        raise InputError("one predicted vertex per error row is needed")
    if predicted.size and (predicted.min() < 0 or predicted.max() >= rows.shape[1]):
        raise InputError("predicted vertex out of range")
    return rows[np.arange(predicted.size), predicted].astype(np.float64)


def normalise(raw_errors, diameter: float, area: float | None = None,
              normalisation: str = "half_diameter") -> np.ndarray:
    """Raw errors in the chosen unit (module docstring)."""
    raw = np.asarray(raw_errors, dtype=np.float64)
    if normalisation == "half_diameter":
        if not diameter > 0:
            raise InputError("the target diameter must be positive")
        return 100.0 * raw / (0.5 * diameter)
    if normalisation == "sqrt_area":
        if area is None or not area > 0:
            raise InputError("the sqrt_area normalisation needs a mesh with positive area")
        return raw / np.sqrt(area)
    raise InputError(f"unknown normalisation {normalisation!r} ({', '.join(NORMALISATIONS)})")


def cumulative_curve(errors, thresholds) -> np.ndarray:
    """Fraction of errors ``<= threshold`` for every threshold (non-decreasing)."""
    e = np.sort(np.asarray(errors, dtype=np.float64))
    if e.size == 0:
        raise InputError("no errors to summarise")
    return np.searchsorted(e, np.asarray(thresholds, dtype=np.float64), side="right") / e.size


def summary(errors) -> dict:
    """Mean, median, 90th percentile and max of an error sample."""
    e = np.asarray(errors, dtype=np.float64)
    if e.size == 0:
        raise InputError("no errors to summarise")
    return dict(mean=float(e.mean()), median=float(np.median(e)),
                p90=float(np.quantile(e, 0.9)), max=float(e.max()))

"""The settings of a score, checked in one place for ``score`` and ``SymmetryProblem.score``."""

from __future__ import annotations

import numpy as np

from ..checks import check_choice, check_flag, check_float
from ..errors import InputError
from ..symmetry.report import ScoreSettings
from .options import EFFORTS


def check_exact(exact):
    """``exact`` if it is "auto", True or False (a numpy bool too); ``InputError`` otherwise."""
    if isinstance(exact, (bool, np.bool_)) or (isinstance(exact, str) and exact == "auto"):
        return exact
    raise InputError(f"exact must be 'auto', True or False, got {exact!r}")


def score_settings(*, exact="auto", upper=False, time_limit=None, effort="default", epsilon=None, seed=0,
                   force=False) -> ScoreSettings:
    """``ScoreSettings`` from the keyword arguments of a score, each checked (``InputError`` naming it).

    ``seed`` and ``force`` arrive checked (``options.ShapeOptions``, ``SymmetryProblem``).

    Examples
    --------
    >>> from shapecond.api.settings import score_settings
    >>> score_settings(upper=True, time_limit=5).time_limit
    5.0
    >>> score_settings(upper="no")
    Traceback (most recent call last):
    ...
    shapecond.errors.InputError: upper must be True or False, got 'no'
    """
    return ScoreSettings(exact=check_exact(exact), upper=check_flag(upper, "upper"),
                         time_limit=None if time_limit is None else check_float(time_limit, "time_limit", lo=0.0,
                                                                                lo_open=True),
                         seed=seed, effort=check_choice(effort, "effort", EFFORTS), force=force,
                         epsilon=None if epsilon is None else check_float(epsilon, "epsilon", lo=0.0))

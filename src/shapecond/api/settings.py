"""The settings of a score, checked in one place for ``score`` and ``SymmetryProblem.score``."""

from __future__ import annotations

from ..checks import check_choice, check_flag, check_float
from ..symmetry.report import ScoreSettings
from ..symmetry.score import check_exact
from .options import EFFORTS


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

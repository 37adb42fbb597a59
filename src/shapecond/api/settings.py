"""The settings of a score, checked in one place for ``score`` and ``SymmetryProblem.score``."""

from __future__ import annotations

from ..symmetry.report import ScoreSettings
from .params import EFFORT, EPSILON, FloatRange, Flag, FlagOr, Param

#: The options of a score itself (``symmetry.report.ScoreSettings``), in the table of ``score``
#: (``scores.SCORE_PARAMS``) and checked here for ``SymmetryProblem.score`` too.
EXACT = Param("exact", FlagOr("auto"), "auto", "Compute σ exactly (enumeration or branch and bound within "
              "--time-limit); by default only when enumeration is quick (N <= 9).", cli=("--exact",))
UPPER = Param("upper", Flag(), False, "LP upper bound when σ is not known exactly (small N only).", cli=("--upper",))
TIME_LIMIT = Param("time_limit", FloatRange(0, lo_open=True, none=True), None,
                   "Seconds for the whole score once the distances are known: the witness search, the exact and LP "
                   "solves and delta(eps) stop at what they have when it is reached, and the JSON's time_limited is "
                   "true (computing geodesics or compiling the kernels the first time is not bounded; they warn when "
                   "long).", cli=("--time-limit",), cli_default="none: the searches run in full, each solve gets 10 s")


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
    return ScoreSettings(exact=EXACT.check(exact), upper=UPPER.check(upper), time_limit=TIME_LIMIT.check(time_limit),
                         seed=seed, effort=EFFORT.check(effort), force=force, epsilon=EPSILON.check(epsilon))

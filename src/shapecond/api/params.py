"""Public options declared once: a name, a constraint, a default, a help text and where the value goes.

A :class:`Param` is one keyword of a public function (in the spirit of scikit-learn's parameter
validation): the constraint checks a value with the checks of ``shapecond.checks`` (the one
validator), ``feeds`` names the field of the frozen options object the maths take (or ``"call"``:
a setting of the call itself, such as ``force``), and ``cli`` the command-line option it is.  A
function's table (e.g. ``matching.MATCH_PARAMS``) is read three ways:

* :func:`check_keywords`: every keyword checked before any work, an unknown one refused, one
  ``InputError`` line naming the parameter;
* :func:`grouped`: the checked values sorted into the options objects they feed;
* ``cli.common.param_option``: the command's click option, whose values are checked by the same
  constraint (the message names the option, ``--points`` rather than ``n_points``).

The parameters several functions share (``SEED``, ``BACKEND``, ``CACHE``, ...) are declared here.

Examples
--------
>>> from shapecond.api.params import IntRange, Param, check_keywords
>>> table = (Param("k", IntRange(1, 10), 5, "Neighbours."),)
>>> check_keywords(table, {"k": 3}, "f")
{'k': 3}
>>> check_keywords(table, {"kk": 3}, "f")
Traceback (most recent call last):
...
shapecond.errors.InputError: f() got unknown option 'kk' (did you mean 'k'?)
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

from ..checks import MAX_SEED, check_choice, check_flag, check_float, check_int
from ..errors import InputError

#: Largest number of samples N any option accepts (the memory and time guards refuse far less).
MAX_POINTS = 100_000
#: Geodesic backends a user may ask for (``shapes.geodesics``; "euclidean" comes with ``metric``).
BACKENDS = ("heat", "fmm", "exact")


@dataclass(frozen=True)
class Choice:
    """One of ``choices`` (``checks.check_choice``)."""

    choices: tuple

    def check(self, value, name: str):
        return check_choice(value, name, self.choices)


@dataclass(frozen=True)
class IntRange:
    """An integer in ``[lo, hi]`` (``checks.check_int``); ``none``: None is allowed too (not set)."""

    lo: int | None = None
    hi: int | None = None
    none: bool = False

    def check(self, value, name: str):
        return None if value is None and self.none else check_int(value, name, lo=self.lo, hi=self.hi)


@dataclass(frozen=True)
class FloatRange:
    """A finite number in the range (``checks.check_float``); ``none``: None is allowed too (not set)."""

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    none: bool = False

    def check(self, value, name: str):
        if value is None and self.none:
            return None
        return check_float(value, name, lo=self.lo, hi=self.hi, lo_open=self.lo_open, hi_open=self.hi_open)


@dataclass(frozen=True)
class Flag:
    """True or False (``checks.check_flag``)."""

    def check(self, value, name: str):
        return check_flag(value, name)


@dataclass(frozen=True)
class Param:
    """One public option.

    Attributes
    ----------
    name : the keyword of the Python function.
    constraint : ``Choice``, ``IntRange``, ``FloatRange`` or ``Flag``.
    default : the value when not given (for an option that feeds an options object, that object's own
        default: a test holds them equal).
    help : the command line's help text.
    feeds : (object, field): the options object and field the value goes to (the table's function
        says which object each name is); object ``"call"``: a setting of the call itself.  An option
        that feeds a sample matcher's options ("lh05", "faq") applies to that matcher only.
    cli : the command-line declarations (``("--points", "-n")``, ``("--refine/--no-refine",)``; a
        lone ``--no-X`` flag sets False); () for an option of the Python function only.
    cli_default : the ``[default: ...]`` text of an option whose default is None.
    """

    name: str
    constraint: Choice | IntRange | FloatRange | Flag
    default: object
    help: str
    feeds: tuple = ("call", None)
    cli: tuple = ()
    cli_default: str | None = None

    def __post_init__(self):
        if self.feeds[1] is None:
            object.__setattr__(self, "feeds", (self.feeds[0], self.name))

    def check(self, value, name: str | None = None):
        """``value`` checked by the constraint; ``InputError`` naming ``name`` (default: the keyword)."""
        return self.constraint.check(value, name or self.name)


# --- options several functions share ------------------------------------------------------------------

SEED = Param("seed", IntRange(0, MAX_SEED), 0, "Seed of every random choice.", ("match", "seed"), ("--seed",))
BACKEND = Param("backend", Choice(BACKENDS), "heat", "Geodesic solver (exact needs the 'exact' extra).",
                ("match", "backend"), ("--geodesic-backend",))
CACHE = Param("cache", Flag(), True, "Do not read or write the distance cache.", ("match", "cache"), ("--no-cache",))
LARGEST_COMPONENT = Param("largest_component", Flag(), False, "Keep only the largest connected component.",
                          cli=("--largest-component",))
FORCE = Param("force", Flag(), False, "Run even when the estimated time or memory is beyond the limits.",
              cli=("--force",))


def check_keywords(table, given: dict, caller: str, off=(), context: str = "") -> dict:
    """Every option of ``table`` that applies, checked, with its default when not ``given``.

    Parameters
    ----------
    table : sequence of Param.
    given : keyword -> value, as the caller received them.
    caller : the function's name, for the messages.
    off : the ``feeds`` objects whose options do not apply to this call (with matcher "faq": "lh05");
        such an option is refused as unknown, ``context`` (" for matcher 'faq'") saying why.

    Returns
    -------
    dict : name -> checked value, for every option that applies.
    """
    live = [p for p in table if p.feeds[0] not in off]
    names = {p.name for p in live}
    for key in given:
        if key not in names:
            raise InputError(_unknown(key, caller + "()", names, {p.name: p.feeds[0] for p in table}, context))
    return {p.name: p.check(given[p.name]) if p.name in given else p.default for p in live}


def _unknown(key, caller: str, names: set, owner: dict, context: str) -> str:
    """The one line refusing keyword ``key``: an option of what does not apply, or a near name."""
    if key in owner:
        return f"{caller} got unknown option {key!r}{context} ({key} is an option of {owner[key]})"
    close = difflib.get_close_matches(str(key), sorted(names), n=1)
    return f"{caller} got unknown option {key!r}" + (f" (did you mean {close[0]!r}?)" if close else "")


def grouped(table, values: dict) -> dict:
    """The checked ``values`` (``check_keywords``) sorted by the object they feed: object -> {field: value}."""
    out: dict = {}
    for p in table:
        if p.name in values:
            out.setdefault(p.feeds[0], {})[p.feeds[1]] = values[p.name]
    return out


__all__ = ["BACKENDS", "CACHE", "Choice", "FORCE", "FloatRange", "Flag", "IntRange", "LARGEST_COMPONENT",
           "MAX_POINTS", "Param", "SEED", "check_keywords", "grouped"]

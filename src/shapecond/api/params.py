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

The parameters several functions share (``POINTS``, ``SEED``, ``BACKEND``, ``CACHE``, the shape options
``SHAPE_PARAMS``, ...) are declared here, once: every table that has one holds that ``Param`` (a
function that always sets a value, like ``match``'s ``n_points``, holds ``POINTS.with_default(400)``).
The commands that predate the tables, and batch's stored options, name a value as the command line
does (``cli_key``: ``points``, ``geodesic_backend``, ``no_cache``); ``from_cli_keys`` and
``cli_defaults`` read and write that form from the same rows.

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
from dataclasses import dataclass, replace

from ..checks import MAX_SEED, check_choice, check_flag, check_float, check_int, parse_ids
from ..errors import InputError

#: Largest number of samples N any option accepts (the memory and time guards refuse far less).
MAX_POINTS = 100_000
#: N when ``n_points`` is not given (the paper's): 400, or every vertex of a smaller shape.
DEFAULT_POINTS = 400
#: Geodesic backends a user may ask for (``shapes.geodesics``; "euclidean" comes with ``metric``).
BACKENDS = ("heat", "fmm", "exact")
#: Work spent by the witness searches (``symmetry.search``).
EFFORTS = ("quick", "default", "thorough")
#: How vertex ids are given, for the help of every ids option (``checks.parse_ids``, ``checks.read_ids``).
IDS_HELP = ("comma- or space-separated (12,405,877) or a file of ids: every id on every line (1 2 3, 1,2,3 "
            "or one per line; # comments); a BIM .pid line 'ID 0 0 0' gives ID; fractional ids are refused")


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: The default of a parameter that has none: the caller must give it (a command line's required option).
REQUIRED = _Required()


@dataclass(frozen=True)
class Choice:
    """One of ``choices`` (``checks.check_choice``); ``none``: None is allowed too (not set)."""

    choices: tuple
    none: bool = False

    def check(self, value, name: str):
        return None if value is None and self.none else check_choice(value, name, self.choices)


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
    """True or False (``checks.check_flag``); ``none``: None is allowed too (not set)."""

    none: bool = False

    def check(self, value, name: str):
        return None if value is None and self.none else check_flag(value, name)


@dataclass(frozen=True)
class FlagOr:
    """True, False or the word ``word`` (``"auto"``: the function decides); on the command line a lone
    flag that gives True."""

    word: str

    def check(self, value, name: str):
        if isinstance(value, str) and value == self.word:
            return value
        try:
            return check_flag(value, name)
        except InputError:
            raise InputError(f"{name} must be {self.word!r}, True or False, got {value!r}") from None


@dataclass(frozen=True)
class Ids:
    """Vertex ids (``checks.parse_ids``: a list, ``"3,5,9"`` or a file of ids; None: none).  On the
    command line the text is kept as given and read by the command (``cli.common.table_values``), after
    its outputs were checked against its inputs."""

    def check(self, value, name: str):
        return parse_ids(value, name)


@dataclass(frozen=True)
class File:
    """A file the function reads, or what it would read from it (e.g. an array); checked where it is
    read.  On the command line a file name (not a folder)."""

    def check(self, value, name: str):
        return value


@dataclass(frozen=True)
class Param:
    """One public option.

    Attributes
    ----------
    name : the keyword of the Python function.
    constraint : ``Choice``, ``IntRange``, ``FloatRange``, ``Flag``, ``FlagOr``, ``Ids`` or ``File``.
    default : the value when not given (for an option that feeds an options object, that object's own
        default: a test holds them equal); ``REQUIRED``: none, the caller gives it.
    help : the command line's help text.
    feeds : (object, field): the options object and field the value goes to (the table's function
        says which object each name is); object ``"call"``: a setting of the call itself.  An option
        that feeds a sample matcher's options ("lh05", "faq") applies to that matcher only.
    cli : the command-line declarations (``("--points", "-n")``, ``("--refine/--no-refine",)``; a
        lone ``--no-X`` flag sets False); () for an option of the Python function only.
    cli_default : the ``[default: ...]`` text of an option whose default is None.
    """

    name: str
    constraint: Choice | IntRange | FloatRange | Flag | FlagOr | Ids | File
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

    def with_default(self, default):
        """This option where a function always sets it: ``default`` in place of None (not allowed any
        more); the same name, help and command line."""
        return replace(self, default=default, constraint=replace(self.constraint, none=False), cli_default=None)

    def in_context(self, prefix: str):
        """This option with its help prefixed by when it applies (``"--score scale: "``)."""
        return replace(self, help=prefix + self.help)


# --- options several functions share ------------------------------------------------------------------

POINTS = Param("n_points", IntRange(3, MAX_POINTS, none=True), None, "Number of farthest-point samples N.",
               ("match", "n_points"), ("--points", "-n"), str(DEFAULT_POINTS))
SEED = Param("seed", IntRange(0, MAX_SEED), 0, "Seed of every random choice.", ("match", "seed"), ("--seed",))
BACKEND = Param("backend", Choice(BACKENDS), "heat", "Geodesic solver (exact needs the 'exact' extra).",
                ("match", "backend"), ("--geodesic-backend",))
CACHE = Param("cache", Flag(), True, "Do not read or write the distance cache.", ("match", "cache"), ("--no-cache",))
LARGEST_COMPONENT = Param("largest_component", Flag(), False, "Keep only the largest connected component.",
                          cli=("--largest-component",))
FORCE = Param("force", Flag(), False, "Run even when the estimated time or memory is beyond the limits.",
              cli=("--force",))
METRIC = Param("metric", Choice(("geodesic", "euclidean")), "geodesic", "Distance between points.", cli=("--metric",))
TARGET = Param("target", Choice(("samples", "dense"), none=True), None,
               "Where maps may send samples: other samples (the paper) or a denser FPS set.", cli=("--target",),
               cli_default="dense for meshes, samples for a distance matrix")
TARGET_FACTOR = Param("target_factor", IntRange(1, 1000), 8, "Dense targets: M = factor x N points.",
                      cli=("--target-factor",))
SYMMETRY_MAP = Param("symmetry_map", File(), None, "A .sym file (line i = 1-based id of the mirror of vertex i): "
                     "sample in mirror pairs.", cli=("--symmetry-map",))
PROGRESS = Param("progress", Flag(), False, "Progress bars on stderr (the command line: when it is a terminal).")
#: How an input becomes a metric shape: the fields of ``options.ShapeOptions``, in the commands' order.
SHAPE_PARAMS = (METRIC, BACKEND, SEED, LARGEST_COMPONENT, CACHE, TARGET, TARGET_FACTOR, SYMMETRY_MAP, FORCE, PROGRESS)
#: The shape options of the command line, in its order: ``--points`` and the rows of ``SHAPE_PARAMS`` it has.
SHAPE_OPTIONS = (POINTS, *[p for p in SHAPE_PARAMS if p.cli])
EFFORT = Param("effort", Choice(EFFORTS), "default", "Work spent by the witness searches.", cli=("--effort",))
#: Landmarks every map fixes (``score``, ``kappa``).
FIXED_LANDMARKS = Param("landmarks", Ids(), (), "Input vertex ids (row indices for a matrix) fixed by every map: "
                        + IDS_HELP + ".", cli=("--landmarks",))
#: Landmarks sampled first, to be fixed later (``metric_shape``, ``SymmetryProblem``).
FIRST_LANDMARKS = Param("landmarks", Ids(), (), "Input vertex ids (row indices for a matrix) placed first among the "
                        "samples: " + IDS_HELP + ".", cli=("--landmarks",))
EPSILON = Param("epsilon", FloatRange(0, none=True), None, "Distortion level ε of δ(ε), RMS, in diameters.",
                cli=("--epsilon",), cli_default="the median sample spacing")


def check_keywords(table, given: dict, caller: str, off=(), context: str = "", others=()) -> dict:
    """Every option of ``table`` that applies, checked, with its default when not ``given``.

    Parameters
    ----------
    table : sequence of Param.
    given : keyword -> value, as the caller received them.
    caller : the function's name, for the messages.
    off : the ``feeds`` objects whose options do not apply to this call (with matcher "faq": "lh05");
        such an option is refused as unknown, ``context`` (" for matcher 'faq'") saying why.
    others : the names of keywords the function takes besides the table's, checked elsewhere (a landmark
        method's own options): let through, not returned.

    Returns
    -------
    dict : name -> checked value, for every option that applies.
    """
    live = [p for p in table if p.feeds[0] not in off]
    names = {p.name for p in live}
    for key in given:
        if key not in names and key not in others:
            raise InputError(_unknown(key, caller + "()", names | set(others), {p.name: p.feeds[0] for p in table},
                                      context))
    missing = [p.name for p in live if p.default is REQUIRED and p.name not in given]
    if missing:
        raise InputError(f"{caller}() needs {missing[0]!r}")
    return {p.name: p.check(given[p.name]) if p.name in given else p.default for p in live}


def _unknown(key, caller: str, names: set, owner: dict, context: str) -> str:
    """The one line refusing keyword ``key``: an option of what does not apply, or a near name."""
    if key in owner:
        return f"{caller} got unknown option {key!r}{context} ({key} is an option of {owner[key]})"
    close = difflib.get_close_matches(str(key), sorted(names), n=1)
    return f"{caller} got unknown option {key!r}{context}" + (f" (did you mean {close[0]!r}?)" if close else "")


def grouped(table, values: dict) -> dict:
    """The checked ``values`` (``check_keywords``) sorted by the object they feed: object -> {field: value}."""
    out: dict = {}
    for p in table:
        if p.name in values:
            out.setdefault(p.feeds[0], {})[p.feeds[1]] = values[p.name]
    return out


# --- the command line's names of the values (the commands that predate the tables, batch's stored options) ---

def cli_key(p: Param) -> str:
    """The name under which the command line holds ``p``'s value when not told otherwise (click's:
    ``--geodesic-backend`` -> ``geodesic_backend``; a lone ``--no-cache`` -> ``no_cache``, True when
    given).  Batch stores its options under these names."""
    return p.cli[0].split("/")[0].lstrip("-").replace("-", "_")


def _negated(p: Param) -> bool:
    """A lone ``--no-x`` flag: its command-line value is the opposite of the Python one."""
    return isinstance(p.constraint, Flag) and p.cli[0].startswith("--no-") and "/" not in p.cli[0]


def cli_defaults(table) -> dict:
    """``cli_key`` -> default of every row of ``table`` that has a command-line form (a lone ``--no-x``:
    False, not given)."""
    return {cli_key(p): (not p.default) if _negated(p) else p.default for p in table if p.cli}


def from_cli_keys(table, values: dict) -> dict:
    """The Python keywords of the rows of ``table`` that have a command-line form, from ``values`` held
    under their ``cli_key`` (missing or None: the row's default; a lone ``--no-x`` flag inverted)."""
    out = {}
    for p in table:
        if p.cli:
            v = values.get(cli_key(p))
            out[p.name] = p.default if v is None else (not v) if _negated(p) else v
    return out


__all__ = ["BACKENDS", "CACHE", "Choice", "DEFAULT_POINTS", "EFFORT", "EFFORTS", "EPSILON", "FIRST_LANDMARKS",
           "FIXED_LANDMARKS", "FORCE", "File", "FloatRange", "Flag", "FlagOr", "IDS_HELP", "Ids", "IntRange",
           "LARGEST_COMPONENT", "MAX_POINTS", "METRIC", "POINTS", "PROGRESS", "Param", "REQUIRED", "SEED", "SHAPE_OPTIONS", "SHAPE_PARAMS", "SYMMETRY_MAP",
           "TARGET", "TARGET_FACTOR", "check_keywords", "cli_defaults", "cli_key", "from_cli_keys", "grouped"]

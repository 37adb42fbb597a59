"""Options and helpers shared by the sub-commands.

``shape_options`` adds the options that turn an INPUT into a metric shape under the command
line's names (batch stores them so; ``params.from_cli_keys`` reads them back); ``emit_json`` prints the one JSON object of ``--json``
(infinite values as the string "inf", missing ones as null).  Numeric options
use the parameter types ``Int``, ``Float`` and ``SEED``, which call the checks
of ``shapecond.checks``: a bad value gets the same one-line message as from
the Python functions.  An option declared in a parameter table (``api.params``:
``match``'s, ``score``'s, ``landmarks``'s, ``heatmap``'s, ``kappa``'s, ``metric_shape``'s, and the shared ``--points``, ``--seed``,
``--geodesic-backend``, ...) is made by ``param_option`` (a whole table:
``table_options``, read back by ``table_values``), with its name, default,
help and check from the table.  Every sub-command is a :class:`Command`: before
it runs, the files it writes (options of type :class:`OutputFile`) are checked
against the files it reads and against each other (``output.check_distinct``).
"""

from __future__ import annotations

import sys

import click

from ..api.params import (BACKEND, CACHE, DEFAULT_POINTS, FORCE, POINTS, REQUIRED, SHAPE_OPTIONS,
                          Choice, File, Flag, FlagOr, Ids, IntRange, Param, cli_key)
from ..api.params import SEED as SEED_PARAM
from ..checks import check_float, check_int, check_seed
from ..errors import InputError
from ..jsonable import dumps
from ..output import check_distinct


def _option_name(param) -> str:
    return param.opts[0] if param is not None and getattr(param, "opts", None) else "value"


class Int(click.ParamType):
    """An integer option checked by ``checks.check_int`` (range in the message)."""

    name = "integer"

    def __init__(self, lo=None, hi=None):
        self.lo, self.hi = lo, hi

    def convert(self, value, param, ctx):
        return check_int(value, _option_name(param), lo=self.lo, hi=self.hi)


class Float(click.ParamType):
    """A finite float option checked by ``checks.check_float``."""

    name = "number"

    def __init__(self, lo=None, hi=None, lo_open=False, hi_open=False):
        self.kw = dict(lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)

    def convert(self, value, param, ctx):
        return check_float(value, _option_name(param), **self.kw)


class Seed(click.ParamType):
    """A seed: an integer in [0, 2**63 - 1]."""

    name = "integer"

    def convert(self, value, param, ctx):
        return check_seed(value, _option_name(param))


SEED = Seed()


class OutputFile(click.Path):
    """A file a command writes: a non-empty name, not a folder; checked by :class:`Command`."""

    def __init__(self):
        super().__init__(dir_okay=False)

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not value.strip():
            self.fail("an empty file name", param, ctx)
        return super().convert(value, param, ctx)


def _param_label(param) -> str:
    return param.opts[0] if isinstance(param, click.Option) else param.human_readable_name


def _named_files(value):
    """The names a parameter value may read: itself, its comma-separated parts, or those of each value."""
    if isinstance(value, (tuple, list)):
        return [n for v in value for n in _named_files(v)]
    if not isinstance(value, str) or not value or value.startswith("demo:"):
        return []
    names = [value] + ([v for v in value.split(",") if v] if "," in value else [])
    return names + [n[:-5] + ".tri" for n in names if n.lower().endswith(".vert")]  # a TOSCA pair


class Command(click.Command):
    """A sub-command whose outputs are checked before it runs: none may be one of its inputs or another
    of its outputs (``output.check_distinct``)."""

    def invoke(self, ctx):
        outputs, inputs = [], []
        for param in self.params:
            value = ctx.params.get(param.name)
            if isinstance(param.type, OutputFile):
                outputs += [(_param_label(param), v) for v in (value if isinstance(value, tuple) else [value])
                            if v is not None]
            else:
                inputs += [(_param_label(param), name) for name in _named_files(value)]
        check_distinct(outputs, inputs)
        return super().invoke(ctx)


def info(message: str) -> None:
    """A diagnostic line on stderr (stdout is kept for results)."""
    click.echo(message, err=True)


def progress_enabled() -> bool:
    return sys.stderr.isatty()


def param_option(param: Param, dest: str | None = None):
    """The click option of ``param`` (``api.params``), its value checked by the same constraint.

    ``dest``: the name the command reads the value under (default: the Python keyword).  A flag
    ``--x/--no-x`` gives True or False (or None, not given, when that is the default); a lone flag gives
    its Python value when given (``--no-cache``: False; ``--exact``: True), except under another ``dest``
    (``no_cache``: the commands not made from a table read the flag itself, ``params.cli_key``).  An
    option whose default is None shows ``param.cli_default`` as its default; one whose default is
    ``REQUIRED`` is required.
    """
    dest, c = dest or param.name, param.constraint
    if isinstance(c, (Flag, FlagOr)):
        if "/" in param.cli[0]:
            return click.option(*param.cli, dest, default=param.default, show_default=True, help=param.help)
        if dest != param.name:
            return click.option(*param.cli, dest, is_flag=True, help=param.help)
        given = (not param.default) if param.cli[0].startswith("--no-") else True
        kind = click.UNPROCESSED if isinstance(c, FlagOr) else click.BOOL  # "auto" is no boolean
        return click.option(*param.cli, dest, flag_value=given, default=param.default, type=kind, help=param.help)
    kind = (click.Choice(c.choices) if isinstance(c, Choice) else Int(c.lo, c.hi) if isinstance(c, IntRange)
            else click.STRING if isinstance(c, Ids) else click.Path(dir_okay=False) if isinstance(c, File)
            else Float(c.lo, c.hi, c.lo_open, c.hi_open))
    if param.default is REQUIRED:
        return click.option(*param.cli, dest, type=kind, required=True, help=param.help)
    if param.default is None or isinstance(c, Ids):
        shown = f" [default: {param.cli_default}]" if param.cli_default else ""
        return click.option(*param.cli, dest, type=kind, default=None, help=param.help + shown)
    return click.option(*param.cli, dest, type=kind, default=param.default, show_default=True, help=param.help)


def table_options(table):
    """The click options of every row of ``table`` (a sequence of ``Param``) that has a command-line
    form, in the table's order (the first is the first in ``--help``)."""
    def add(f):
        return apply(f, [param_option(p) for p in table if p.cli])
    return add


def table_values(table, o: dict) -> dict:
    """The values of the options ``table_options(table)`` made, popped from a command's keyword arguments
    ``o``, under their Python names.  Vertex ids (``params.Ids``, which may name a file) are read here,
    after ``Command`` checked the outputs against the inputs, the message naming the option."""
    out = {}
    for p in table:
        if p.cli:
            value = o.pop(p.name)
            out[p.name] = p.check(value, p.cli[0]) if isinstance(p.constraint, Ids) else value
    return out


#: The options several commands share, each declared once (``api.params``).
POINTS_OPTION = param_option(POINTS, cli_key(POINTS))
SEED_OPTION = param_option(SEED_PARAM)
BACKEND_OPTION = param_option(BACKEND, cli_key(BACKEND))
NO_CACHE_OPTION = param_option(CACHE, cli_key(CACHE))


def apply(f, options):
    """``f`` decorated by ``options`` in the order listed (the first is the first in ``--help``)."""
    for option in reversed(options):
        f = option(f)
    return f


#: The names under which the commands not made from a table (sample, kappa, heatmap, batch) read the shape
#: options (``params.cli_key``: ``points``, ``geodesic_backend``, ``no_cache``, ...).
SHAPE_OPTION_NAMES = tuple(cli_key(p) for p in SHAPE_OPTIONS)


def shape_options(f):
    """Options that build the metric shape: --points, --metric, --geodesic-backend, ... (``params.SHAPE_OPTIONS``)."""
    return apply(f, [param_option(p, cli_key(p)) for p in SHAPE_OPTIONS])


def force_option(f):
    """``--force``: run work estimated beyond the time or memory limits (``shapecond.limits``)."""
    return param_option(FORCE)(f)


#: ``--epsilon-from``: ε read off matched maps (``resolve_epsilon``; the command line's own).
EPSILON_FROM_OPTION = click.option(
    "--epsilon-from", "epsilon_from", multiple=True, type=click.Path(dir_okay=False),
    help="Read ε off the maps from INPUT to this shape (repeat for several: their median), found without ground "
         "truth (api.level): δ at your shapes' own deformation level.")


def resolve_epsilon(input_spec, o: dict, n_points, options: dict) -> tuple[float | None, dict]:
    """(ε to pass on, the JSON fields saying where it comes from) from ``--epsilon`` (a table's ``EPSILON`` row)
    and ``EPSILON_FROM_OPTION``."""
    if o.get("epsilon_from") and o.get("epsilon") is not None:
        raise InputError("give --epsilon or --epsilon-from, not both")
    if not o.get("epsilon_from"):
        return o.get("epsilon"), {"epsilon_source": "given (--epsilon)" if o.get("epsilon") is not None
                                  else "the median sample spacing (default)"}
    from ..api import deformation_level

    keep = ("seed", "backend", "cache", "force", "largest_component")
    level = deformation_level(input_spec, list(o["epsilon_from"]), n_points=n_points or DEFAULT_POINTS,
                              **{k: options[k] for k in keep if k in options})
    info(f"epsilon {level.epsilon:.4g} diameters, {level.sentence()}")
    return level.epsilon, {"epsilon_source": level.sentence(), "deformation_level": level.to_dict()}


def pop_shape_options(kwargs: dict) -> dict:
    """Split the shape options out of a command's keyword arguments."""
    return {k: kwargs.pop(k) for k in SHAPE_OPTION_NAMES if k in kwargs}


def emit_json(obj) -> None:
    """Print one JSON object on stdout and nothing else."""
    click.echo(dumps(obj))


def json_option(f):
    return click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")(f)

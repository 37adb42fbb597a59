"""The ``shapecond`` command: one group, one module per sub-command.

Sub-commands live in ``shapecond/cli/cmd_*.py``, each exporting a click command
named ``command``; they are discovered here and imported when used.  Every user error (``InputError``,
a bad option) becomes one ``error: ...`` line on stderr and exit status 2; any
other failure is internal (exit status 1; set ``SHAPECOND_DEBUG=1`` for the
traceback).  Standard output carries what the commands print and nothing else:
while a command runs, file descriptor 1 points at stderr and only Python's
``sys.stdout`` keeps the real standard output (``output.stdout_fd_diverted``),
so what a compiled library prints on its own can never corrupt ``--json``.
"""

from __future__ import annotations

import difflib
import importlib
import os
import pkgutil
import sys
import warnings

import click

from .._version import __version__
from ..errors import ShapecondError
from ..output import stdout_fd_diverted


class _LazyGroup(click.Group):
    """The sub-commands, each imported only when it runs (or help lists it).

    ``shapecond score`` needs neither the matchers nor the evaluation's
    statistics; importing every ``cmd_*`` module up front cost about 0.8 s of a
    warm score's start-up.  A command ``NAME`` lives in ``cmd_NAME.py``.
    """

    def list_commands(self, ctx):
        return sorted(m.name[4:] for m in pkgutil.iter_modules(__path__) if m.name.startswith("cmd_"))

    def get_command(self, ctx, name):
        if name not in self.list_commands(ctx):
            return None
        return importlib.import_module(f"{__name__}.cmd_{name}").command


@click.group(cls=_LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="shapecond")
def cli():
    """How hard is a shape to match, why, and where to put landmarks.

    INPUT is a mesh (OFF, OBJ, PLY, STL, TOSCA .vert/.tri), a point cloud (.xyz,
    .txt, .npy of shape (n, 3), PLY without faces), an N x N distance matrix
    (.npy) or a generated shape demo:NAME (animal, sphere, torus, cylinder, blob,
    plane), e.g. demo:animal:delta=0.05.
    """


def _fail(message: str, status: int) -> None:
    click.echo(f"error: {message}", err=True)
    sys.exit(status)


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings (cache skipped, long run ahead, ...) as one ``warning: ...`` line on stderr."""
    text = str(message).splitlines()[0] if str(message) else category.__name__
    print(f"warning: {text}", file=sys.stderr)


def _usage_message(exc: click.UsageError) -> str:
    """The first line of a usage error; a misspelt option is worded here, not by click.

    click's wording and its suggestions changed between the versions we allow
    (8.2 said ``No such option: --refin`` and offered ``--target-factor`` for
    ``--resolve-fractio``), so the closest of the command's own option names
    (``difflib``, the same matcher click uses) are offered here.
    """
    if not isinstance(exc, click.NoSuchOption) or exc.ctx is None:
        return exc.format_message().splitlines()[0]
    names = [n for p in exc.ctx.command.params for n in p.opts + p.secondary_opts if n.startswith("-")]
    close = difflib.get_close_matches(exc.option_name, names, n=3)
    return f"No such option '{exc.option_name}'" + (f"; did you mean {', '.join(close)}?" if close else "")


def main(argv=None) -> None:
    """Console-script entry point."""
    warnings.showwarning = _one_line_warning
    try:
        with stdout_fd_diverted(keep_python_stdout=True):  # a compiled library's prints go to stderr
            status = cli.main(args=argv, prog_name="shapecond", standalone_mode=False)
    except click.exceptions.NoArgsIsHelpError as exc:  # bare `shapecond` or `shapecond CMD`: show help
        click.echo(exc.ctx.get_help() if exc.ctx else str(exc))
        sys.exit(0)
    except click.UsageError as exc:
        hint = f" (see: shapecond {exc.ctx.info_name} --help)" if exc.ctx and exc.ctx.parent else ""
        _fail(_usage_message(exc) + hint, 2)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.Abort:
        _fail("aborted", 130)
    except ShapecondError as exc:  # bad input, or an output that cannot be written
        _fail(str(exc).splitlines()[0] if str(exc) else "bad input", 2)
    except MemoryError:
        _fail("out of memory; try fewer --points", 1)
    except BrokenPipeError:
        sys.exit(1)
    except Exception as exc:  # internal failure: one line unless debugging
        if os.environ.get("SHAPECOND_DEBUG"):
            raise
        _fail(f"internal failure: {exc.__class__.__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
              " (set SHAPECOND_DEBUG=1 for details)", 1)
    sys.exit(status if isinstance(status, int) else 0)

"""``shapecond batch INPUT... --out FILE``: one row per shape, for whole collections.

See ``shapecond.batch`` for the table, resuming and where the work runs.
"""

from __future__ import annotations

from dataclasses import replace

import click

from ..api.params import EFFORT, EPSILON
from ..batch import format_summary, run_batch
from ..batch.run import BatchRun
from ..errors import InputError
from ..matching.pipeline import MATCHERS
from .common import (Command, OutputFile, emit_json, json_option, param_option, pop_shape_options, progress_enabled,
                     shape_options)

#: Exit status when some shapes failed (their rows hold the error).
EXIT_SOME_FAILED = 3


@click.command("batch", cls=Command)
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@click.option("--out", "-o", "out", required=True, type=OutputFile(),
              help="Output table: .parquet (needs pyarrow), .csv or .jsonl; a regular file (not a link) "
                   "that is missing, empty or a batch table.")
@shape_options
@param_option(EFFORT)
@click.option("--what", "what", multiple=True, default=("score",), show_default=True,
              help="What to compute besides info, repeatable or comma-separated: score, local, "
                   "landmarks:K:METHOD (e.g. landmarks:5:fps), match:TEMPLATE (the template, a file or the name of one "
                   "of the inputs, matched to every shape with the landmarks of NAME.lmk files or --landmarks; maps in maps/ and report.html "
                   "beside --out).")
@click.option("--matcher", type=click.Choice(MATCHERS), default=None,
              help="match:TEMPLATE: the sample matcher of shapecond match [default: lh05].")
@click.option("--landmarks", "landmark_table", type=click.Path(dir_okay=False), default=None,
              help="match:TEMPLATE: a CSV file with columns shape,label,vertex (0-based ids) instead of a "
                   "NAME.lmk file (lines 'LABEL VERTEX_ID') beside each shape.")
@click.option("--pairs", "pairs_file", type=click.Path(dir_okay=False), default=None,
              help="Match the pairs this file lists (two shape names a line, the first matched to the second, "
                   "'#' comments) instead of a template to every shape (--what match, the default with --pairs).")
@click.option("--both-directions", "both_directions", is_flag=True,
              help="Matching: each map both ways (template -> shape and shape -> template, or both ways of "
                   "each pair), both in maps/ with names saying the direction, and their cycle_error.")
@param_option(replace(EPSILON, help="Distortion level ε of δ(ε) for every shape, RMS, in diameters.",
                      cli_default="each shape's median sample spacing"))
@click.option("--epsilon-from-collection", "epsilon_collection", is_flag=True,
              help="Read ε off the collection itself: its first shape matched to the next few "
                   "(api.level.collection_level), the median distortion of the maps, no ground truth.")
@click.option("--jobs", "-j", type=int, default=1, show_default=True, help="Local worker processes (joblib).")
@click.option("--scheduler", default=None,
              help="Run on Dask: tcp://HOST:PORT of a running scheduler, or local:W to start a "
                   "LocalCluster with W workers.")
@click.option("--resume", is_flag=True, help="Keep the rows in --out; score only the shapes without one.")
@click.option("--overwrite", is_flag=True, help="Start --out afresh even if it holds rows (only a batch table "
              "is emptied; any other file is refused).")
@json_option
def command(inputs, out, what, as_json, **kw):
    """Score every shape in INPUT... (files, folders, glob patterns) into one table.

    One row per shape with info's counts and problems, the global score, and on
    request the local score and landmarks, or the map from a template (match:TEMPLATE:
    template -> shape, landmarks paired by label, the error bar and the next landmark
    to annotate), or of the pairs --pairs lists, one row per map; a shape that fails
    gets an error row and the batch goes on.  Exit
    status 0 when every shape was scored, 3 when some failed.
    """
    if kw["resume"] and kw["overwrite"]:
        raise InputError("--resume and --overwrite exclude each other")
    if kw["epsilon"] is not None and kw["epsilon_collection"]:
        raise InputError("give --epsilon or --epsilon-from-collection, not both")
    options = pop_shape_options(kw)
    options.update(effort=kw["effort"], matcher=kw["matcher"], landmark_table=kw["landmark_table"],
                   pairs=kw["pairs_file"], both_directions=kw["both_directions"])
    source = click.get_current_context().get_parameter_source("what")
    if kw["pairs_file"] is not None and source == click.core.ParameterSource.DEFAULT:  # --pairs says what to do
        what = ("match",)
    options["epsilon"] = "collection" if kw["epsilon_collection"] else kw["epsilon"]
    how = BatchRun(n_jobs=kw["jobs"], scheduler=kw["scheduler"], resume=kw["resume"], overwrite=kw["overwrite"],
                   progress=progress_enabled())
    summary = run_batch(inputs, out, options, what=what, how=how)
    if as_json:
        emit_json(summary)
    else:
        click.echo(format_summary(summary))
    return EXIT_SOME_FAILED if summary.failed else 0

"""Scoring a collection: plan, skip what is done, run the rest where asked, append rows, summarise.

``run_batch`` expands the inputs (``inputs.expand_inputs``), hashes them, opens
the output table (one writer at a time; ``table.Table``), drops the shapes
whose (file, content hash, parameters) already have a row when resuming, runs
one ``rows.shape_row`` task per remaining shape through ``parallel.runner``
(this process, local processes or a Dask cluster), and appends each row as it
arrives.  With ``match:TEMPLATE`` or ``--pairs`` (``matches``) a task is a shape with its
reference (the template, or a pair's first shape) and gives a row per direction, each row's
map written (atomically) before it, and ``report.html`` is written beside the table.
A shape that fails, or whose worker dies, becomes an error row; the batch goes on.
"""

from __future__ import annotations

import math
import os
import statistics
import time
from dataclasses import dataclass, field, replace

from .._version import __version__
from ..api import DEFAULT_POINTS
from ..api.level import collection_level
from ..parallel import check_where, runner, worker_name
from . import schema
from .inputs import content_hashes, expand_inputs
from .matches import MatchPlan, plan_matching
from .report import annotate_more, collection_landmark, write_report
from .rows import COLLECTION, params_key, shape_keywords, shape_row, with_defaults
from .table import Table, table_format

#: How many of the most symmetric shapes and of the failures the summary lists.
SUMMARY_TOP = 5


@dataclass(frozen=True)
class BatchSummary:
    """What a batch did: counts, timing, the most symmetric shapes, the failures."""

    output: str
    shapes: int            # rows of the batch: one per shape (per map when matching)
    scored: int            # rows computed by this run
    resumed: int           # rows skipped because they were already in the table
    failed: int            # shapes of this batch whose row holds an error (new or resumed)
    seconds: float
    median_seconds: float | None
    where: str
    most_symmetric: list = field(default_factory=list)   # dicts file, sigma_hat, resolution
    failures: list = field(default_factory=list)         # dicts file, error
    epsilon: float | None = None                         # the level of δ (None: each shape's sample spacing)
    epsilon_source: str = "the median sample spacing of each shape (default)"
    annotate_more: list = field(default_factory=list)    # match: dicts file, bar, suggested landmark
    collection_landmark: dict | None = None              # match: report.collection_landmark
    report: str | None = None                            # match: the report page

    @property
    def shapes_per_minute(self) -> float | None:
        return 60.0 * self.scored / self.seconds if self.scored and self.seconds > 0 else None

    def to_dict(self) -> dict:
        return {"output": self.output, "shapes": self.shapes, "scored": self.scored, "resumed": self.resumed,
                "failed": self.failed, "seconds": self.seconds, "median_seconds": self.median_seconds,
                "shapes_per_minute": self.shapes_per_minute, "where": self.where,
                "most_symmetric": self.most_symmetric, "failures": self.failures, "epsilon": self.epsilon,
                "epsilon_source": self.epsilon_source, "annotate_more": self.annotate_more, "report": self.report,
                "collection_landmark": self.collection_landmark}


def _failed_row(spec, digest, params, error) -> dict:
    row = schema.empty_row()
    text = str(error).splitlines()[0] if str(error) else ""
    row.update(file=spec, content_hash=digest, params=params,
               error=f"{error.__class__.__name__}: {text}".strip(": "))
    return row


def _unreadable_row(spec, digest, params, reason) -> dict:
    """The error row of a shape file that this process cannot read (missing, a FIFO, no permission), or
    whose landmarks it cannot read (``matches``)."""
    row = schema.empty_row()
    row.update(file=spec, content_hash=digest, params=params, version=__version__, worker=worker_name(), error=reason)
    return row


@dataclass(frozen=True)
class BatchRun:
    """Where and how a batch runs (``run_batch``).

    Attributes
    ----------
    n_jobs, scheduler : where the shapes are scored (``parallel.runner``).
    resume : keep the rows already in ``out`` and score only the shapes without one;
        without it an ``out`` holding rows is refused unless ``overwrite``.
    overwrite : start ``out`` afresh (only a batch table is emptied).
    progress : a progress bar on stderr.
    """

    n_jobs: int = 1
    scheduler: object = None
    resume: bool = False
    overwrite: bool = False
    progress: bool = False

    @property
    def mode(self) -> str:
        """``Table``'s mode: "overwrite", "resume" or "new"."""
        return "overwrite" if self.overwrite else ("resume" if self.resume else "new")


def run_batch(inputs, out, options=None, what=("score",), how: BatchRun = BatchRun()) -> BatchSummary:
    """Score every shape named by ``inputs`` into the table ``out`` (see module docstring).

    Parameters
    ----------
    inputs : files, folders (walked recursively) and glob patterns; ``demo:`` specifications too.
    out : output table, ``.parquet``, ``.csv`` or ``.jsonl``.
    options : the shape options of ``shapecond score`` (``points``, ``metric``,
        ``geodesic_backend``, ``seed``, ``largest_component``, ``no_cache``,
        ``target``, ``target_factor``, ``symmetry_map``), ``effort`` and ``epsilon`` (the level of
        δ for every shape in diameters, or "collection": read off the collection, ``api.level.collection_level``);
        when matching, ``matcher``, ``landmark_table`` (a CSV file ``shape,label,vertex``) and
        ``both_directions``; ``pairs``: the pairs list of ``what`` ``match``.
    what : ``score``, ``local``, ``landmarks:K:METHOD``, ``match:TEMPLATE``, ``match`` (``rows.parse_what``).
    how : BatchRun (``n_jobs``, ``scheduler``, ``resume``, ``overwrite``, ``progress``).
    """
    t0 = time.perf_counter()
    options = with_defaults({**(options or {}), "what": what})
    table_format(out)
    check_where(how.n_jobs, how.scheduler)
    specs = expand_inputs(inputs)
    plan = plan_matching(specs, options, out)
    options = plan.with_template(options)
    units = plan.units(specs)
    with Table(out, how.mode) as table:
        hashes = dict(zip(specs, content_hashes(specs)))
        options, source = _level(options, [s for s in specs if not hashes[s][1]])
        base = params_key(options)
        params = [plan.params(base, u, {s: h for s, (h, _) in hashes.items()}) for u in units]
        keys = [[(u[0], hashes[u[0]][0], p) for p in ps] for u, ps in zip(units, params)]
        have = {schema.row_key(r) for r in table.rows}
        unreadable = plan.errors | {s: why for s, (_, why) in hashes.items() if why}
        todo = [i for i, ks in enumerate(keys) if any(k not in have for k in ks)]
        readable = []
        for i in todo:  # the client cannot read it either: no worker would do better
            why = plan.unit_error(units[i], unreadable)
            if why is None:
                readable.append(i)
                continue
            for key in keys[i]:
                if key not in have:
                    table.append(_unreadable_row(*key, why))
        where = (_score(table, [(units[i], keys[i]) for i in readable], options, how, plan) if readable
                 else "this process" if todo else "nothing to do")
        done = {schema.row_key(r): r for r in table.rows}
        batch_rows = [done[k] for ks in keys for k in ks]
    new = sum(k not in have for ks in keys for k in ks)
    summary = _summary(str(out), batch_rows, new, len(batch_rows) - new, time.perf_counter() - t0, where)
    if plan.active:
        summary = replace(summary, annotate_more=_annotate_more(batch_rows), collection_landmark=collection_landmark(
            batch_rows), report=_short(str(write_report(out, batch_rows))))
    return replace(summary, epsilon=options["epsilon"], epsilon_source=source or summary.epsilon_source)


def _annotate_more(rows) -> list[dict]:
    """The matched shapes whose bar says "annotate more" (``report.annotate_more``), worst first."""
    bad = annotate_more(rows)
    return [{"file": _short(r["file"]), "bar": r["bar"], "source_id": r["suggest_source_id"],
             "image_id": r["suggest_image_id"], "bar_after": r["suggest_bar_after"],
             "direction": r["match_direction"], "source": _short(r["match_source"] or r["file"]),
             "cycle_error": r["cycle_error"]} for r in bad]


def _level(options: dict, readable: list) -> tuple[dict, str | None]:
    """``options`` with ``epsilon="collection"`` replaced by the level read off the collection
    (``api.level.collection_level``), and where the level comes from."""
    if options["epsilon"] is None:
        return options, None
    if options["epsilon"] != COLLECTION:
        return options, "given (--epsilon)"
    level = _collection_level(readable, options)
    return {**options, "epsilon": level.epsilon}, f"the collection's level, {level.sentence()}"


def _collection_level(specs: list, options: dict):
    """The collection's level (``api.level.collection_level``) with the batch's shape options."""
    kw = shape_keywords(options)
    return collection_level(specs, n_points=options["points"] or DEFAULT_POINTS,
                            **{k: kw[k] for k in ("seed", "backend", "cache", "force", "largest_component")})


def _score(table, todo, options, how: BatchRun, plan: MatchPlan) -> str:
    """Run the tasks ``todo`` ((unit, its row keys)) and append their rows; the runner's label."""
    from tqdm import tqdm

    tasks = [(shape_row, (unit[0], keys[0][1], options, keys[0][2]), plan.task_kwargs(unit)) for unit, keys in todo]
    failed = 0
    have = {schema.row_key(r) for r in table.rows}
    with runner(how.n_jobs, how.scheduler) as run, \
            tqdm(total=len(tasks), desc="scoring", unit="shape", disable=not how.progress) as bar:
        for i, row, error in run.iter_tasks(tasks):
            unit, keys = todo[i]
            rows = ([_failed_row(*key, error) for key in keys] if error is not None
                    else plan.rows_of(row, unit, [key[2] for key in keys]))
            for r in rows:
                if schema.row_key(r) not in have:  # a task rerun after a kill between its rows
                    table.append(r)
                failed += r["error"] is not None
            bar.set_postfix(failed=failed, refresh=False)
            bar.update(1)
        return run.label


def _summary(out, rows, scored, resumed, seconds, where) -> BatchSummary:
    ok = [r for r in rows if r["error"] is None]
    bad = [r for r in rows if r["error"] is not None]
    times = [r["seconds"] for r in ok if r["seconds"] is not None]
    ranked = sorted((r for r in ok if r["sigma_hat"] is not None), key=lambda r: (-r["sigma_hat"], r["file"]))
    top = [{"file": _short(r["file"]), "sigma_hat": r["sigma_hat"], "resolution": r["resolution"]}
           for r in ranked[:SUMMARY_TOP]]
    failures = [{"file": _short(r["file"]), "error": r["error"]} for r in bad[:SUMMARY_TOP]]
    return BatchSummary(out, len(rows), scored, resumed, len(bad), seconds,
                        statistics.median(times) if times else None, where, top, failures)


def _short(path: str) -> str:
    """A path relative to the working folder when it lies below it."""
    if path.startswith("demo:"):
        return path
    rel = os.path.relpath(path)
    return path if rel.startswith("..") else rel


def format_summary(s: BatchSummary) -> str:
    """The one-screen text summary of ``shapecond batch``."""
    def num(v):
        return "inf" if v == math.inf else f"{v:.4g}"

    lines = [f"shapes      {s.shapes}: {s.scored} scored now, {s.resumed} already in {s.output}, {s.failed} failed",
             f"where       {s.where}",
             f"time        {s.seconds:.1f} s"
             + (f", {s.shapes_per_minute:.2f} shapes/min" if s.shapes_per_minute else "")
             + (f", median {s.median_seconds:.2f} s per shape" if s.median_seconds is not None else ""),
             f"epsilon     " + (f"{s.epsilon:.4g} diameters, " if s.epsilon is not None else "") + s.epsilon_source]
    if s.most_symmetric:
        lines.append("most symmetric (sigma_hat, resolution flag):")
        lines += [f"  {num(r['sigma_hat']):>8}  {r['resolution'] or '-':28s} {r['file']}" for r in s.most_symmetric]
    if s.report:
        lines.append(f"report      {s.report}: {len(s.annotate_more)} maps say annotate more (bar > 0.05 sqrt(area))")
        lines += [f"  {num(r['bar']):>8}  {r['file']}" + ("" if r["direction"] == "template to shape"
                                                       else f" ({r['direction']}, from {r['source']})")
                  + f": next source vertex {r['source_id']} (image {r['image_id']}), bar after {num(r['bar_after'])}"
                  for r in s.annotate_more[:SUMMARY_TOP]]
    if s.collection_landmark:
        c = s.collection_landmark
        lines.append(f"collection  template vertex {c['template_vertex']} is the next landmark of {c['maps']} of the "
                     f"{c['listed']} maps listed: one new label there, on the template and every shape")
    if s.failures:
        lines.append(f"failed ({s.failed}; the first {len(s.failures)}):" if s.failed > len(s.failures)
                     else "failed:")
        lines += [f"  {r['file']}: {r['error']}" for r in s.failures]
    return "\n".join(lines)

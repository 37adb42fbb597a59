"""``shapecond evaluate DATASET_DIR``: the paper's Figure 7 evaluation on class folders.

Each sub-folder of DATASET_DIR is a class: shapes with the same vertex count and
order (ground truth = identity on vertex ids), or ``shapes/`` and ``corres/``
folders of differently meshed shapes with ``.vts`` ground truth; DATASET_DIR may
also be one such class, or a release as it ships (``DIR/NAME.off`` +
``DIR/corres/``, or ``shapes_train/`` + ``shapes_test/`` + ``corres/``; see
``shapecond.evaluation.datasets``).  ``--pairs FILE`` matches exactly the listed pairs.  See ``shapecond.evaluation``
for the protocols and ``shapecond.evaluation.report`` for the output.

Running on a Dask cluster: start a scheduler and workers that can read
DATASET_DIR (and, ideally, share ``$SHAPECOND_CACHE``), then pass
``--scheduler tcp://HOST:8786``, or ``--scheduler local:W`` for a LocalCluster of
W workers on this machine; the per-shape tasks go to the workers
(``shapecond.parallel``; needs ``pip install 'shapecond[dask]'``).
"""

from __future__ import annotations

import time
from pathlib import Path

import click

from ..api.matching import FAQ_OBJECTIVE
from ..errors import InputError
from ..evaluation import evaluate
from ..evaluation.report import by_protocol, correlations, protocols, write_report
from ..evaluation.run import DEFAULT_MATCHERS, DEFAULT_METHODS, PROTOCOL_CHOICES
from ..matching.pipeline import DENSE_STAGES, MATCHERS
from ..parallel import runner
from .common import (BACKEND_OPTION, NO_CACHE_OPTION, POINTS_OPTION, SEED_OPTION, Command, Int, emit_json,
                     force_option, info, json_option, param_option, progress_enabled)


def _names(text, allowed=None, what="name"):
    names = [t.strip() for t in str(text).split(",") if t.strip()] if text else []
    if allowed is not None:
        bad = [n for n in names if n not in allowed]
        if bad:
            raise InputError(f"unknown {what} {bad[0]!r} (choose from {', '.join(allowed)})")
    if text is not None and not names:
        raise InputError(f"empty list of {what}s")
    return names


def _counts(text) -> list[int]:
    out = []
    for tok in _names(text, what="landmark count"):
        if not tok.isdigit() or int(tok) < 1:
            raise InputError(f"--counts: {tok!r} is not a positive landmark count")
        out.append(int(tok))
    return out


@click.command("evaluate", cls=Command)
@click.argument("dataset_dir", type=click.Path(file_okay=False))
@click.option("--classes", default=None, help="Comma-separated class folders [default: all].")
@click.option("--methods", default=",".join(DEFAULT_METHODS), show_default=True,
              help="Landmark methods (shapecond.selection), and cnbs-scale-hat: CNBS-scale at each class's level "
                   "read off its matched maps (no ground truth).")
@click.option("--matchers", default=",".join(DEFAULT_MATCHERS), show_default=True,
              help="Matchers: lh05, faq (on samples, then the dense stage), zoomout (from the landmarks alone; "
                   "not in the corresponding protocol, which matches samples).")
@click.option("--counts", default="3", show_default=True,
              help="Landmark counts matched besides all of the class's landmarks (e.g. 3,6).")
@click.option("--dense", type=click.Choice(DENSE_STAGES), default="zoomout", show_default=True,
              help="How maps reach every vertex: landmark-anchored ZoomOut, or the plain extensions.")
@param_option(FAQ_OBJECTIVE, "faq_objective")
@click.option("--jobs", "-j", type=Int(1, 1024), default=1, show_default=True,
              help="Parallel processes for the per-shape work (joblib; at most one per task and core).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="evaluation",
              show_default=True, help="Folder for report.md, results.json and the PNG plots.")
@click.option("--quick", is_flag=True,
              help="A small run: wolf and centaur (or the first two classes), 2 targets each, N = 200.")
@POINTS_OPTION
@click.option("--max-targets", type=Int(1), default=None, help="Match at most this many shapes per class.")
@SEED_OPTION
@BACKEND_OPTION
@NO_CACHE_OPTION
@click.option("--protocol", type=click.Choice(PROTOCOL_CHOICES), default="auto", show_default=True,
              help="auto: remeshed for classes with corres/*.vts, corresponding otherwise; corresponding: "
                   "targets sampled at the null shape's sample vertices (the κ setting); independent: each "
                   "target sampled by its own FPS; both: corresponding and independent; remeshed: dense maps "
                   "between differently meshed shapes measured at the .vts reference points.")
@click.option("--scheduler", default=None,
              help="Run on Dask: tcp://HOST:PORT of a running scheduler, or local:W to start a "
                   "LocalCluster with W workers.")
@click.option("--pairs", "pairs_file", type=click.Path(dir_okay=False), default=None,
              help="Match exactly the pairs listed in this file (two shape names a line, as a release's "
                   "test_pairs.txt), across classes too; each source gets its own landmarks. Default: each "
                   "class's null shape to the rest of its class.")
@click.option("--landmark-count", type=Int(1, 10_000), default=None,
              help="Landmarks per source, the largest count matched [default: the paper's count for its TOSCA "
                   "classes, 10 otherwise].")
@click.option("--scores/--no-scores", default=True, show_default=True,
              help="Score every landmark set (σ and δ after 1, 3 and all landmarks, δ at each class's levels); "
                   "--no-scores: the matchings alone, for a release's pairs list (a landmark set per source).")
@click.option("--error-bars/--no-error-bars", default=True, show_default=True,
              help="Give every matching its error bar (from δ(ε̂)) read off the map itself (one δ search each) and "
                   "report how the bars hold the true errors.")
@force_option
@json_option
def command(dataset_dir, **o):
    """Landmarks on each null shape, matched to the rest of its class; a Markdown and HTML report.

    N defaults to 400 samples per shape, 200 with --quick.
    """
    t0 = time.perf_counter()
    lists = dict(classes=tuple(_names(o["classes"], what="class")) or None,
                 methods=tuple(_names(o["methods"], what="method")),
                 matchers=tuple(_names(o["matchers"], MATCHERS, "matcher")), counts=tuple(_counts(o["counts"])))
    with runner(o["jobs"], o["scheduler"]) as run:  # one cluster for every stage of the evaluation
        ev = evaluate(Path(dataset_dir), **lists, dense=o["dense"], n_jobs=o["jobs"], scheduler=run.client, quick=o["quick"],
                      n_points=o["points"], seed=o["seed"], backend=o["geodesic_backend"], cache=not o["no_cache"],
                      progress=progress_enabled(), max_targets=o["max_targets"], protocol=o["protocol"],
                      force=o["force"], error_bars=o["error_bars"], pairs=o["pairs_file"],
                      n_landmarks=o["landmark_count"], scores=o["scores"], faq_objective=o["faq_objective"])
    report = write_report(ev, o["out_dir"])
    summary = {"report": str(report), "seconds": time.perf_counter() - t0,
               "classes": ev.settings["classes"], "matchings": len(ev.records),
               "protocols": protocols(ev),
               "correlation": correlations(by_protocol(ev, protocols(ev)[0])),
               "correlation_by_protocol": {p: correlations(by_protocol(ev, p)) for p in protocols(ev)}}
    if o["as_json"]:
        emit_json(summary)
    else:
        info(f"wrote {report} ({len(ev.records)} matchings, {summary['seconds']:.0f} s)")

"""``shapecond match SOURCE TARGET --landmarks-source IDS --landmarks-target IDS -o MAP.txt``.

Landmark-guided matching of one pair, **source to target**.
"""

from __future__ import annotations

import time
from pathlib import Path

import click
import numpy as np

from ..matching.pipeline import DENSE_STAGES, MATCHERS, SAMPLINGS
from ..checks import parse_ids
from ..errors import InputError
from ..output import atomic_open
from .common import (BACKEND_OPTION, LARGEST_COMPONENT_OPTION, NO_CACHE_OPTION, SEED_OPTION, Command, Int, OutputFile,
                     emit_json, force_option, info, json_option, points_option)


@click.command("match", cls=Command)
@click.argument("source", metavar="SOURCE")
@click.argument("target", metavar="TARGET")
@click.option("--landmarks-source", required=True,
              help="Landmark vertex ids on SOURCE (comma-separated, or a file of ids).")
@click.option("--landmarks-target", required=True,
              help="The corresponding vertex ids on TARGET, in the same order.")
@click.option("--matcher", type=click.Choice(MATCHERS), default="lh05", show_default=True,
              help="lh05: Leordeanu-Hebert spectral matching of the samples (the paper); faq: seeded graph "
                   "matching of the samples; zoomout: from the landmarks alone (at least 3), by the dense stage.")
@points_option(400)
@SEED_OPTION
@BACKEND_OPTION
@click.option("--k", "k", type=Int(1, 10_000), default=20, show_default=True,
              help="lh05: candidate target samples per source sample.")
@click.option("--rounding", type=click.Choice(["greedy", "assignment"]), default="assignment",
              show_default=True, help="lh05: a linear assignment or the paper's greedy discretisation.")
@click.option("--refine/--no-refine", default=True, show_default=True,
              help="lh05: refine the rounded map on its own objective, with spectral rounds on candidates "
                   "iterated from it (--no-refine --rounding greedy: the paper's plain LH05).")
@click.option("--samples", type=click.Choice(SAMPLINGS), default="fps", show_default=True,
              help="fps: each shape gets its own farthest-point samples; same-ids: the target is sampled "
                   "at the source's sample vertices (shapes with a common vertex order; the evaluation's "
                   "corresponding protocol) and the summary reports the sample map's error.")
@click.option("--dense", type=click.Choice(DENSE_STAGES), default="zoomout", show_default=True,
              help="How the map reaches every source vertex: zoomout (the sample map extended, then refined by "
                   "ZoomOut on the Laplace-Beltrami bases with the landmarks as anchors), or the plain "
                   "extensions of the sample map (distances: local distance matching; nearest: nearest sample).")
@click.option("--error-bar/--no-error-bar", default=True, show_default=True,
              help="Estimate the map's error without ground truth: δ(ε̂) on SOURCE with the landmarks fixed, ε̂ "
                   "the map's own RMS distortion (in the summary; the doubt field with --doubt-ply, --doubt-png).")
@click.option("--doubt-png", type=OutputFile(), default=None,
              help="Picture of SOURCE coloured by the error bar's doubt field (PNG), landmarks ringed.")
@click.option("--doubt-ply", type=OutputFile(), default=None,
              help="SOURCE coloured by the error bar's doubt field: how far the widest map as distorted as this "
                   "one moves each point (PLY).")
@LARGEST_COMPONENT_OPTION
@NO_CACHE_OPTION
@click.option("-o", "--output", required=True, type=OutputFile(),
              help="Map file: line i holds the TARGET vertex id matched to SOURCE vertex i.")
@click.option("--suggest", type=Int(0, 1000), default=0, show_default=True,
              help="Suggest this many next landmarks, read off the map and its error bar (each with its provisional "
                   "image and the bar expected after it): click them, add them to the landmarks, re-run.")
@click.option("--html", type=OutputFile(), default=None,
              help="Self-contained HTML page of the map: colours carried source -> target, linked landmarks.")
@click.option("--truth", default=None,
              help="--html: the ground truth, to show the error field: a map file like -o's (line i: the true "
                   "TARGET id of SOURCE vertex i; -1, and only -1, for none), 'same-ids' (shapes with a common "
                   "vertex order), or SOURCE.vts,TARGET.vts, the two shapes' reference files of a remeshed "
                   "release (the error is then known at the source's reference vertices). Read and checked "
                   "before matching.")
@force_option
@json_option
def command(source, target, landmarks_source, landmarks_target, output, **o):
    """Match SOURCE to TARGET with corresponding landmarks fixed; write the dense map.

    The map file has one line per SOURCE vertex id (0 .. largest id): the id of
    the TARGET vertex it is matched to, or -1 for a vertex dropped on loading
    (unreferenced by any face).  For two N x N distance matrices (.npy) the map
    is between their rows.  With --json a summary goes to stdout.
    """
    from ..api import match

    if o["truth"] is not None and not o["html"]:
        raise InputError("--truth is shown by --html; give --html FILE too")
    if (o["doubt_ply"] or o["doubt_png"] or o["suggest"]) and not o["error_bar"]:
        raise InputError("--doubt-ply, --doubt-png and --suggest read the error bar: drop --no-error-bar")
    t0 = time.perf_counter()
    lh05 = {k: o[k] for k in ("k", "rounding", "refine")} if o["matcher"] == "lh05" else {}
    ids_s, ids_t = parse_ids(landmarks_source, "--landmarks-source"), parse_ids(landmarks_target, "--landmarks-target")
    truth_text = o["truth"]
    shapes = _surfaces_up_front(source, target, o)
    result = match(*shapes, ids_s, ids_t, matcher=o["matcher"], n_points=o["points"],
                   seed=o["seed"], backend=o["geodesic_backend"], dense=o["dense"], samples=o["samples"],
                   cache=not o["no_cache"], force=o["force"], largest_component=o["largest_component"],
                   error_bar=o["error_bar"], suggest=o["suggest"], **lh05)
    out = Path(output)
    with atomic_open(out) as fh:
        np.savetxt(fh, result.map, fmt="%d")
    if o["doubt_ply"]:
        _write_doubt(result, o["doubt_ply"])
    if o["doubt_png"]:
        info(f"wrote {result.plot(path=o['doubt_png'])}")
    if o["html"]:
        paths = dict(source=source, target=target, output=output, html=o["html"],  # for the page's command
                     options=_repeated_options(o, truth_text))
        info(f"wrote {result.to_html(o['html'], truth=o['truth'], command=paths)}")
    summary = dict(result.summary, source=str(source), target=str(target), output=str(out),
                   seconds=time.perf_counter() - t0)
    if o["as_json"]:
        emit_json(summary)
    else:
        info(f"wrote {out}: {result.map.size} source vertices matched to {target} ({o['matcher']}, "
             f"{summary['n_landmarks']} landmarks, {summary['seconds']:.1f} s)")
        if "error_bar" in summary:
            info("error bar: " + summary["error_bar"]["text"])
        for i, s in enumerate(summary.get("suggestions", []), 1):
            info(f"next landmark {i}: source {s['source_id']} (provisional image {s['image_id']}), "
                 f"bar after it {s['bar_after']:.3g} sqrt(area)")


def _repeated_options(o: dict, truth_text) -> list:
    """The options of this run that the page's command repeats (those that change the map or the page)."""
    words = []
    for name, flag, default in (("matcher", "--matcher", "lh05"), ("points", "--points", 400),
                                ("dense", "--dense", "zoomout"), ("samples", "--samples", "fps"),
                                ("suggest", "--suggest", 0), ("seed", "--seed", 0)):
        if o.get(name) != default:
            words += [flag, o[name]]
    return words + (["--truth", truth_text] if truth_text is not None else [])


def _surfaces_up_front(source, target, o: dict) -> tuple:
    """SOURCE and TARGET, loaded here when an output draws them: a distance matrix is refused and
    ``--truth`` read and checked against both shapes (``o["truth"]`` becomes what it holds) before the
    matching; otherwise the names, loaded by ``match``."""
    drawn = [name for name in ("html", "doubt_ply", "doubt_png") if o[name]]
    if not drawn:
        return source, target
    from ..api import load
    from ..viz.truth import read_truth, truth_map

    truth = read_truth(o["truth"])
    shapes = tuple(load(x, largest_component=o["largest_component"], force=o["force"]) for x in (source, target))
    if any(isinstance(x, np.ndarray) for x in shapes):
        raise InputError(f"--{drawn[0].replace('_', '-')} draws the shapes, but a distance matrix has no surface")
    if truth is not None:
        truth_map(truth, *shapes)
    o["truth"] = truth
    return shapes


def _write_doubt(result, path) -> None:
    from ..viz.ply import write_ply
    from ..viz.scene import Colouring

    src = result.drawing[0]  # the doubt field in the source's internal vertex order, landmarks ringed
    write_ply(path, src.vertices, src.faces, values=result.doubt[src.ids], landmarks=result.drawing[2],
              colouring=Colouring("turbo"))
    info(f"wrote {path}")

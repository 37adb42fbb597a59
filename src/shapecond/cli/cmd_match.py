"""``shapecond match SOURCE TARGET --landmarks-source IDS --landmarks-target IDS -o MAP.txt``.

Landmark-guided matching of one pair, **source to target**.
"""

from __future__ import annotations

import time
from pathlib import Path

import click
import numpy as np

from ..api import load, match
from ..api.matching import MATCH_PARAMS, inapplicable
from ..checks import parse_ids
from ..errors import InputError
from ..output import atomic_open
from .common import Command, OutputFile, emit_json, info, json_option, table_options

@click.command("match", cls=Command)
@click.argument("source", metavar="SOURCE")
@click.argument("target", metavar="TARGET")
@click.option("--landmarks-source", required=True,
              help="Landmark vertex ids on SOURCE (comma-separated, or a file of ids).")
@click.option("--landmarks-target", required=True,
              help="The corresponding vertex ids on TARGET, in the same order.")
@table_options(MATCH_PARAMS)
@click.option("-o", "--output", required=True, type=OutputFile(),
              help="Map file: line i holds the TARGET vertex id matched to SOURCE vertex i.")
@click.option("--doubt-png", type=OutputFile(), default=None,
              help="Picture of SOURCE coloured by the error bar's doubt field (PNG), landmarks ringed.")
@click.option("--doubt-ply", type=OutputFile(), default=None,
              help="SOURCE coloured by the error bar's doubt field: how far the widest map as distorted as this "
                   "one moves each point (PLY).")
@click.option("--html", type=OutputFile(), default=None,
              help="Self-contained HTML page of the map: colours carried source -> target, linked landmarks.")
@click.option("--truth", default=None,
              help="The ground truth, to measure the map's error (the summary's \"truth\": mean, median and worst "
                   "geodesic error in sqrt(area) of TARGET, at up to 200 samples) and, with --html, to show the "
                   "error field: a map file like -o's (line i: the true "
                   "TARGET id of SOURCE vertex i; -1, and only -1, for none), 'same-ids' (shapes with a common "
                   "vertex order), or SOURCE.vts,TARGET.vts, the two shapes' reference files of a remeshed "
                   "release (the error is then known at the source's reference vertices). Read and checked "
                   "before matching.")
@json_option
def command(source, target, landmarks_source, landmarks_target, output, **o):
    """Match SOURCE to TARGET with corresponding landmarks fixed; write the dense map.

    The map file has one line per SOURCE vertex id (0 .. largest id): the id of
    the TARGET vertex it is matched to, or -1 for a vertex dropped on loading
    (unreferenced by any face).  For two N x N distance matrices (.npy) the map
    is between their rows.  With --json a summary goes to stdout.
    """
    if (o["doubt_ply"] or o["doubt_png"] or o["suggest"]) and not o["error_bar"]:
        raise InputError("--doubt-ply, --doubt-png and --suggest read the error bar: drop --no-error-bar")
    t0 = time.perf_counter()
    ids_s, ids_t = parse_ids(landmarks_source, "--landmarks-source"), parse_ids(landmarks_target, "--landmarks-target")
    truth_text = o["truth"]
    shapes = _surfaces_up_front(source, target, o)
    result = match(*shapes, ids_s, ids_t, **{p.name: o[p.name] for p in _passed(o["matcher"])})
    out = Path(output)
    with atomic_open(out) as fh:
        np.savetxt(fh, result.map, fmt="%d")
    if o["truth"] is not None:
        result.truth_errors(o["truth"])  # in the summary; the page draws the same errors
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
        if "truth" in summary:
            t = summary["truth"]
            info(f"error against the truth: mean {t['mean']:.3g} {t['unit']} ({t['mean_percent_half_diameter']:.3g} % "
                 f"of half the diameter), median {t['median']:.3g}, worst {t['worst']:.3g}, at {t['n_points']} points")
        for i, s in enumerate(summary.get("suggestions", []), 1):
            info(f"next landmark {i}: source {s['source_id']} (provisional image {s['image_id']}), "
                 f"bar after it {s['bar_after']:.3g} sqrt(area)")


def _passed(matcher: str) -> list:
    """The rows of ``MATCH_PARAMS`` on the command line that apply with ``matcher`` (an option of another
    sample matcher, e.g. --k with --matcher faq, is not passed on)."""
    off = inapplicable(matcher)
    return [p for p in MATCH_PARAMS if p.cli and p.feeds[0] not in off]


def _repeated_options(o: dict, truth_text) -> list:
    """The options of this run that the page's command repeats: those that differ from their defaults."""
    words = []
    for p in _passed(o["matcher"]):
        value = o[p.name]
        if value == p.default:
            continue
        if isinstance(value, bool):  # a flag: its form for this value (--no-refine, --no-cache, --force)
            words.append(next(w for d in p.cli for w in d.split("/") if w.startswith("--no-") != value))
        else:
            words += [p.cli[0], value]
    return words + (["--truth", truth_text] if truth_text is not None else [])


def _surfaces_up_front(source, target, o: dict) -> tuple:
    """SOURCE and TARGET, loaded here when an output draws them or ``--truth`` measures on them: a distance
    matrix is refused and ``--truth`` read and checked against both shapes (``o["truth"]`` becomes what it
    holds) before the matching; otherwise the names, loaded by ``match``."""
    drawn = [name for name in ("html", "doubt_ply", "doubt_png", "truth") if o[name] is not None]
    if not drawn:
        return source, target
    from ..viz.truth import read_truth, truth_map

    truth = read_truth(o["truth"])
    shapes = tuple(load(x, largest_component=o["largest_component"], force=o["force"]) for x in (source, target))
    if any(isinstance(x, np.ndarray) for x in shapes):
        raise InputError(f"--{drawn[0].replace('_', '-')} needs the shapes' surfaces, but a distance matrix has none")
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

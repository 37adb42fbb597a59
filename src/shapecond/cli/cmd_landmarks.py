"""``shapecond landmarks INPUT -k K --method ...``: where to put landmarks (paper Sections 6-7)."""

from __future__ import annotations

import click

from ..api import landmarks
from ..checks import parse_ids
from ..jsonable import fmt
from ..selection import METHODS, SCORES
from .common import (IDS_HELP, Command, Int, OutputFile, api_options, emit_json, epsilon_options, info,
                     json_option, pop_shape_options, resolve_epsilon, shape_options)


@click.command("landmarks", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@shape_options
@click.option("-k", "k", type=Int(0, 100_000), required=True, help="Number of landmarks (method user: 0 = all given).")
@click.option("--method", type=click.Choice(METHODS), default="cnbs", show_default=True,
              help="cnbs: condition number based sampling (the paper's σ); cnbs-scale: CNBS on the "
                   "scale-aware score δ(ε); fps; pls (Tevs et al., reimplemented); hks (heat kernel "
                   "signature extrema); user (--user-landmarks); cnbs-local.")
@click.option("--user-landmarks", default=None, help="For --method user: vertex ids, " + IDS_HELP + ".")
@click.option("--scores/--no-scores", default=None,
              help="Compute the symmetry score after each landmark (always on for cnbs; for the "
                   "baselines it costs one witness search per landmark).")
@click.option("--effort", type=click.Choice(["quick", "default", "thorough"]), default="default",
              show_default=True, help="Effort of the witness searches.")
@click.option("--score", "score", type=click.Choice(SCORES), default=None,
              help="Score after each landmark: sigma (the paper's) or scale (δ(ε)) "
                   "[default: scale for cnbs-scale, sigma otherwise].")
@epsilon_options("--method cnbs-scale or --score scale: ")
@click.option("--png", type=OutputFile(), default=None, help="Picture of the landmarks (PNG).")
@click.option("--ply", type=OutputFile(), default=None, help="Mesh with landmarks painted (PLY).")
@click.option("--html", type=OutputFile(), default=None,
              help="Self-contained HTML page of the landmarks in order with their scores.")
@click.option("--up", type=click.Choice(["x", "y", "z"]), default=None, help="Vertical axis of the pictures.")
@json_option
def command(input_spec, k, method, **o):
    """Choose K landmarks and report the symmetry score after each one.

    Landmarks are vertex ids of INPUT (rows for a distance matrix), in order; scores
    are the global symmetry score (lower bound with witness) with the first 1, 2, ...
    landmarks fixed: the paper's "vector of symmetry scores".
    """
    n_points, options = api_options(pop_shape_options(o))
    user_ids = parse_ids(o["user_landmarks"], "--user-landmarks") if o["user_landmarks"] else []
    if method == "user" and not user_ids:
        raise click.UsageError("--method user needs --user-landmarks")
    epsilon, source = resolve_epsilon(input_spec, o, n_points, options)
    result = landmarks(input_spec, k, method, n_points, user_landmarks=user_ids, scores=o["scores"],
                       effort=o["effort"], score=o["score"], epsilon=epsilon, **options)
    _pictures(result, o, title=f"{method}: " + ", ".join(f"{v}" for v in result.landmarks))
    d = result.to_dict()
    if o["as_json"]:
        emit_json({**{key: d[key] for key in ("landmarks", "scores", "method", "seconds", "score")},
                   **(source if method == "cnbs-scale" or result.score == "scale" else {})})
        return
    name = "delta" if result.score == "scale" else "sigma"
    if result.initial_score is not None:
        click.echo(f"{name} without landmarks: {fmt(result.initial_score)}")
    for i, (v, s) in enumerate(zip(result.landmarks, result.scores), 1):
        click.echo(f"{i:3d}  vertex {v:>8d}  {name} after: {fmt(s)}")
    click.echo(f"{method}, {result.shape.n_samples} samples, {result.seconds:.2f} s")


def _pictures(result, o: dict, title: str) -> None:
    up = o["up"] or _up(result.shape)
    if o["png"]:
        result.plot(path=o["png"], up=up, title=title)
        info(f"wrote {o['png']}")
    if o["ply"]:
        _ply(result, o["ply"])
    if o["html"]:
        info(f"wrote {result.to_html(o['html'], up=up, title=title)}")


def _up(shape) -> str:
    from ..viz.scene import guess_up

    return guess_up(shape.geometry)


def _ply(result, path) -> None:
    """The shape with its landmarks painted (PLY; a distance matrix by classical MDS)."""
    from ..symmetry.starts import classical_mds
    from ..viz.ply import write_ply

    shape = result.shape
    if shape.geometry is not None:
        write_ply(path, shape.geometry.vertices, shape.geometry.faces, None, list(result.vertices))
    else:
        write_ply(path, classical_mds(shape.D), None, None, list(result.sample_indices))
    info(f"wrote {path}")

"""``shapecond landmarks INPUT -k K --method ...``: where to put landmarks (paper Sections 6-7)."""

from __future__ import annotations

import click

from ..api.scores import LANDMARK_PARAMS, landmarks
from ..jsonable import fmt
from ..symmetry.starts import classical_mds
from .common import (EPSILON_FROM_OPTION, Command, OutputFile, emit_json, info, json_option, progress_enabled,
                     resolve_epsilon, table_options, table_values)


@click.command("landmarks", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@table_options(LANDMARK_PARAMS)
@EPSILON_FROM_OPTION
@click.option("--png", type=OutputFile(), default=None, help="Picture of the landmarks (PNG).")
@click.option("--ply", type=OutputFile(), default=None, help="Mesh with landmarks painted (PLY).")
@click.option("--html", type=OutputFile(), default=None,
              help="Self-contained HTML page of the landmarks in order with their scores.")
@click.option("--up", type=click.Choice(["x", "y", "z"]), default=None, help="Vertical axis of the pictures.")
@json_option
def command(input_spec, **o):
    """Choose K landmarks and report the symmetry score after each one.

    Landmarks are vertex ids of INPUT (rows for a distance matrix), in order; scores
    are the global symmetry score (lower bound with witness) with the first 1, 2, ...
    landmarks fixed: the paper's "vector of symmetry scores".
    """
    kw = table_values(LANDMARK_PARAMS, o)  # the options of sc.landmarks (api.scores.LANDMARK_PARAMS)
    method = kw["method"]
    if method == "user" and not kw["user_landmarks"]:
        raise click.UsageError("--method user needs --user-landmarks")
    epsilon, source = resolve_epsilon(input_spec, {**o, "epsilon": kw.pop("epsilon")}, kw["n_points"], kw)
    result = landmarks(input_spec, **kw, epsilon=epsilon, progress=progress_enabled())
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
    from ..viz.ply import write_ply

    shape = result.shape
    if shape.geometry is not None:
        write_ply(path, shape.geometry.vertices, shape.geometry.faces, None, list(result.vertices))
    else:
        write_ply(path, classical_mds(shape.D), None, None, list(result.sample_indices))
    info(f"wrote {path}")

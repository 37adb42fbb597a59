"""``shapecond heatmap INPUT --png FILE``: the CNBS heat map (paper Figures 1 and 4)."""

from __future__ import annotations

import click

from ..api import heatmap
from ..api.params import IDS_HELP
from ..checks import parse_ids
from ..errors import InputError
from ..jsonable import fmt
from ..selection.cnbs import RESOLVE_FRACTION
from .cmd_landmarks import _up
from .common import (Command, Float, OutputFile, api_options, emit_json, epsilon_options, info,
                     json_option, pop_shape_options, resolve_epsilon, shape_options)


@click.command("heatmap", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@shape_options
@click.option("--landmarks", default=None, help="Vertex ids already fixed: " + IDS_HELP + ".")
@click.option("--png", type=OutputFile(), default=None, help="Picture of the heat map (PNG).")
@click.option("--html", type=OutputFile(), default=None,
              help="Self-contained HTML page of the heat map (turn it, hover a vertex for its id and value).")
@click.option("--ply", type=OutputFile(), default=None, help="Mesh coloured by the heat map (PLY).")
@click.option("--effort", type=click.Choice(["quick", "default", "thorough"]), default="default",
              show_default=True, help="Effort of the witness searches.")
@click.option("--resolve-fraction", type=Float(0.0, 1.0), default=RESOLVE_FRACTION, show_default=True,
              help="Share of candidates (those the witness maps move farthest) searched again.")
@click.option("--score", "score", type=click.Choice(["sigma", "scale"]), default="sigma", show_default=True,
              help="sigma: the paper's σ with each point fixed; scale: the scale-aware δ(ε) "
                   "(the CNBS heat map of --method cnbs-scale).")
@epsilon_options("--score scale: ")
@click.option("--up", type=click.Choice(["x", "y", "z"]), default=None, help="Vertical axis of the pictures.")
@json_option
def command(input_spec, **o):
    """The symmetry score with each sample fixed as a landmark, drawn on the shape.

    Low values (blue) are good landmarks: fixing them breaks the near-symmetries.
    Samples a witness map already fixes (e.g. on a mirror plane) do not lower it.
    """
    png, html, ply = o["png"], o["html"], o["ply"]
    if not (png or html):
        raise InputError("give --png FILE or --html FILE (or both) for the heat map")
    n_points, options = api_options(pop_shape_options(o))
    epsilon, source = resolve_epsilon(input_spec, o, n_points, options)
    result = heatmap(input_spec, parse_ids(o["landmarks"]), n_points, effort=o["effort"],
                     resolve_fraction=o["resolve_fraction"], score=o["score"], epsilon=epsilon, **options)
    up = o["up"] or _up(result.shape)
    if png:
        result.plot(path=png, up=up, ply=ply, cmap="turbo")
        info(f"wrote {png}" + (f" and {ply}" if ply else ""))
    if html:
        info(f"wrote {result.to_html(html, up=up, title=result.title())}")
    out = {**result.to_dict(), **(source if o["score"] == "scale" else {})}
    if o["as_json"]:
        emit_json(out)
    else:
        name = "delta" if o["score"] == "scale" else "sigma"
        click.echo(f"{name} before: {fmt(out['sigma_before'])}; best landmark: vertex {out['best']} "
                   f"({name} {fmt(out['best_value'])}); {out['seconds']:.1f} s")

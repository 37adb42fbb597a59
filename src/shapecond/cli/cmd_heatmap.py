"""``shapecond heatmap INPUT --png FILE``: the CNBS heat map (paper Figures 1 and 4)."""

from __future__ import annotations

import click

from ..api.scores import HEATMAP_PARAMS, heatmap
from ..errors import InputError
from ..jsonable import fmt
from .cmd_landmarks import _up
from .common import (EPSILON_FROM_OPTION, Command, OutputFile, emit_json, info, json_option, progress_enabled,
                     resolve_epsilon, table_options, table_values)


@click.command("heatmap", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@table_options(HEATMAP_PARAMS)
@EPSILON_FROM_OPTION
@click.option("--png", type=OutputFile(), default=None, help="Picture of the heat map (PNG).")
@click.option("--html", type=OutputFile(), default=None,
              help="Self-contained HTML page of the heat map (turn it, hover a vertex for its id and value).")
@click.option("--ply", type=OutputFile(), default=None, help="Mesh coloured by the heat map (PLY).")
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
    kw = table_values(HEATMAP_PARAMS, o)  # the options of sc.heatmap (api.scores.HEATMAP_PARAMS)
    epsilon, source = resolve_epsilon(input_spec, {**o, "epsilon": kw.pop("epsilon")}, kw["n_points"], kw)
    result = heatmap(input_spec, **kw, epsilon=epsilon, progress=progress_enabled())
    up = o["up"] or _up(result.shape)
    if png:
        result.plot(path=png, up=up, ply=ply, cmap="turbo")
        info(f"wrote {png}" + (f" and {ply}" if ply else ""))
    if html:
        info(f"wrote {result.to_html(html, up=up, title=result.title())}")
    out = {**result.to_dict(), **(source if kw["score"] == "scale" else {})}
    if o["as_json"]:
        emit_json(out)
    else:
        name = "delta" if kw["score"] == "scale" else "sigma"
        click.echo(f"{name} before: {fmt(out['sigma_before'])}; best landmark: vertex {out['best']} "
                   f"({name} {fmt(out['best_value'])}); {out['seconds']:.1f} s")

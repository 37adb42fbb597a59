"""``shapecond heatmap INPUT --png FILE``: the CNBS heat map (paper Figures 1 and 4)."""

from __future__ import annotations

import math
import time

import click
import numpy as np

from ..landmarks.cnbs import RESOLVE_FRACTION, heat_map
from .cmd_landmarks import guess_up
from ..limits import check_cost, search_seconds
from ..errors import InputError
from .common import (IDS_HELP, Float, build_shape, emit_json, fmt, info, json_option, load_geometry_or_matrix,
                     parse_ids, pop_shape_options, shape_options)


@click.command("heatmap")
@click.argument("input_spec", metavar="INPUT")
@shape_options
@click.option("--landmarks", default=None, help="Vertex ids already fixed: " + IDS_HELP + ".")
@click.option("--png", type=click.Path(dir_okay=False), default=None, help="Picture of the heat map (PNG).")
@click.option("--html", type=click.Path(dir_okay=False), default=None,
              help="Self-contained HTML page of the heat map (turn it, hover a vertex for its id and value).")
@click.option("--ply", type=click.Path(dir_okay=False), default=None, help="Mesh coloured by the heat map (PLY).")
@click.option("--effort", type=click.Choice(["quick", "default", "thorough"]), default="default",
              show_default=True, help="Effort of the witness searches.")
@click.option("--resolve-fraction", type=Float(0.0, 1.0), default=RESOLVE_FRACTION, show_default=True,
              help="Share of candidates (those the witness maps move farthest) searched again.")
@click.option("--score", "score", type=click.Choice(["sigma", "scale"]), default="sigma", show_default=True,
              help="sigma: the paper's σ with each point fixed; scale: the scale-aware δ(ε) "
                   "(the CNBS heat map of --method cnbs-scale).")
@click.option("--epsilon", type=Float(0.0), default=None,
              help="--score scale: distortion level ε [default: the median sample spacing].")
@click.option("--up", type=click.Choice(["x", "y", "z"]), default=None, help="Vertical axis of the pictures.")
@json_option
def command(input_spec, landmarks, png, html, ply, effort, resolve_fraction, score, epsilon, up, as_json, **kwargs):
    """The symmetry score with each sample fixed as a landmark, drawn on the shape.

    Low values (blue) are good landmarks: fixing them breaks the near-symmetries.
    Samples a witness map already fixes (e.g. on a mirror plane) do not lower it.
    """
    from ..viz.heatmap import render_heatmap_png

    if not (png or html):
        raise InputError("give --png FILE or --html FILE (or both) for the heat map")
    t0 = time.perf_counter()
    shape_kw = pop_shape_options(kwargs)
    ids = parse_ids(landmarks)
    loaded = load_geometry_or_matrix(input_spec, shape_kw.get("largest_component", False),
                                     shape_kw.get("symmetry_map"), shape_kw.get("force", False))
    shape = build_shape(input_spec, landmarks=ids, loaded=loaded, **shape_kw)
    check_cost(f"the heat map at N = {shape.n_samples}",  # about 4 searches' worth (measured on TOSCA)
               search_seconds(shape.n_samples, shape.n_targets, 4), force=shape_kw.get("force", False))
    L = list(range(len(ids)))  # build_shape puts the landmarks first
    n = shape.n_samples
    budget, unit, name = None, 1.0, "sigma"
    if score == "scale":
        from ..symmetry.scale import budget_of, default_epsilon

        epsilon = default_epsilon(shape.D, n) if epsilon is None else epsilon
        budget, unit, name = budget_of(epsilon, n, shape.D), 1.0 / math.sqrt(n), "delta"
    hm = heat_map(shape.D, n, landmarks=L, seed=shape_kw.get("seed", 0), effort=effort,
                  resolve_fraction=resolve_fraction, budget=budget)
    best = hm.argmin()
    values, before = hm.values * unit, hm.sigma_before * unit  # δ = sqrt(d²) / sqrt(N)
    vals = values.copy()
    vals[L] = before if math.isfinite(before) else np.nan
    plot_vals = np.where(np.isnan(vals), np.nanmax(np.where(np.isfinite(vals), vals, np.nan)), vals)
    title = (f"{name} with each point fixed (before: {fmt(before)}; "
             f"best: {fmt(float(values[best]))} at vertex {int(shape.sample_ids[best])})")
    if png:
        render_heatmap_png(shape, plot_vals, png, landmarks=L, up=guess_up(shape, up), title=title, ply=ply,
                           cmap="turbo")
        info(f"wrote {png}" + (f" and {ply}" if ply else ""))
    if html:
        from ..output import write_text
        from ..viz.pages import heatmap_page

        write_text(html, heatmap_page(shape, plot_vals, landmarks=L, up=guess_up(shape, up), title=title))
        info(f"wrote {html}")
    out = {
        "landmarks": [int(v) for v in shape.sample_ids[L]],
        "score": score,
        "epsilon": epsilon if score == "scale" else None,
        "sigma_before": before,
        "samples": shape.sample_ids,
        "values": [None if np.isnan(v) else float(v) for v in values],
        "best": int(shape.sample_ids[best]),
        "best_value": float(values[best]),
        "seconds": time.perf_counter() - t0,
    }
    if as_json:
        emit_json(out)
    else:
        click.echo(f"{name} before: {fmt(before)}; best landmark: vertex {out['best']} "
                   f"({name} {fmt(out['best_value'])}); {out['seconds']:.1f} s")

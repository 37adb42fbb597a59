"""``shapecond kappa INPUT --trials K``: empirical probes of the condition number κ.

Paper Section 4, Eq. 4 and Theorem 4.1 (``shapecond.symmetry.condition``):
perturbed copies of the shape's distance matrix, the exact optimal matching of
each, and the ratio d(T_opt, Id) / d(X, X̃).  Exact matching enumerates every
map, so N is small (at most ``MAX_PROBE_POINTS`` free samples).
"""

from __future__ import annotations

import click

from ..api import kappa
from ..api.params import IDS_HELP
from ..checks import parse_ids
from ..jsonable import fmt
from .common import (Command, Float, Int, api_options, emit_json, info, json_option,
                     pop_shape_options, shape_options)


@click.command("kappa", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@shape_options
@click.option("--landmarks", default=None, help="Vertex ids (row indices for a matrix) fixed by every map: "
              + IDS_HELP + ".")
@click.option("--trials", type=Int(1), default=20, show_default=True, help="Number of perturbed copies probed.")
@click.option("--scale", type=Float(0.0, 10.0, lo_open=True), default=0.05, show_default=True,
              help="Random perturbation size, relative to the RMS distance.")
@click.option("--time-limit", type=Float(0.0, lo_open=True), default=None,
              help="Stop probing after this many seconds (the probes so far are reported).")
@json_option
def command(input_spec, landmarks, trials, scale, time_limit, as_json, **kwargs):
    """Probe κ (Eq. 4) with exact matchings of perturbed copies; report σ <= κ <= 2σ + 1.

    For meshes N defaults to 8 samples; at most 9 samples may be free of landmarks.
    """
    n_points, options = api_options(pop_shape_options(kwargs))
    res = kappa(input_spec, n_points, landmarks=parse_ids(landmarks), trials=trials, scale=scale,
                time_limit=time_limit, **options)
    if as_json:
        emit_json(res.to_dict())
        return
    lo, hi = res.kappa
    click.echo(f"points             {res.shape.n_points} ({len(res.landmark_ids)} landmarks)")
    click.echo(f"sigma (exact)      {fmt(res.sigma)}")
    click.echo(f"kappa bracket      [{fmt(lo)}, {fmt(hi)}]   (Theorem 4.1: sigma <= kappa <= 2 sigma + 1)")
    click.echo(f"probes             {len(res.ratios)}, max {fmt(res.kappa_probe_max)}")
    for note in res.notes:
        info(f"note: {note}")
    info(f"{res.seconds:.2f} s")

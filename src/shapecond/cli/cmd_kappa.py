"""``shapecond kappa INPUT --trials K``: empirical probes of the condition number κ.

Paper Section 4, Eq. 4 and Theorem 4.1 (``shapecond.symmetry.condition``):
perturbed copies of the shape's distance matrix, the exact optimal matching of
each, and the ratio d(T_opt, Id) / d(X, X̃).  Exact matching enumerates every
map, so N is small (at most ``MAX_PROBE_POINTS`` free samples).
"""

from __future__ import annotations

import click

from ..api.scores import KAPPA_PARAMS, kappa
from ..jsonable import fmt
from .common import Command, emit_json, info, json_option, progress_enabled, table_options, table_values


@click.command("kappa", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@table_options(KAPPA_PARAMS)
@json_option
def command(input_spec, as_json, **o):
    """Probe κ (Eq. 4) with exact matchings of perturbed copies; report σ <= κ <= 2σ + 1.

    For meshes N defaults to 8 samples; at most 9 samples may be free of landmarks.
    """
    res = kappa(input_spec, **table_values(KAPPA_PARAMS, o), progress=progress_enabled())
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

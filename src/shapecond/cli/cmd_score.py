"""``shapecond score INPUT``: the global symmetry score σ (paper Eq. 5) as a bracket.

Prints σ lower/upper/exact, the size-free σ̂ = σ√N, the condition-number
bracket σ ≤ κ ≤ 2σ + 1 (Theorem 4.1), the witness map (the near-isometry that
makes the shape hard to match), for dense targets on a mesh whether the witness
is a symmetry within sampling resolution, the scale-aware score δ(ε) with its
own witness (``symmetry.scale``: the widest self-map within the distortion of
real deformations), and a one-line verdict of what the numbers mean for
matching (``symmetry.verdict``).
"""

from __future__ import annotations

import time

import click
import numpy as np

from ..api import score
from ..checks import parse_ids
from ..jsonable import fmt
from .common import (IDS_HELP, Command, Float, OutputFile, api_options, emit_json, epsilon_options, info,
                     json_option, pop_shape_options, resolve_epsilon, shape_options)


@click.command("score", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@shape_options
@click.option("--landmarks", default=None, help="Input vertex ids (row indices for a matrix) fixed by every "
              "map: " + IDS_HELP + ".")
@click.option("--exact", "exact", is_flag=True, help="Compute σ exactly (enumeration or branch and bound "
              "within --time-limit); by default only when enumeration is quick (N <= 9).")
@click.option("--upper", is_flag=True, help="LP upper bound when σ is not known exactly (small N only).")
@click.option("--time-limit", type=Float(0.0, lo_open=True), default=None,
              help="Seconds for the whole score once the distances are known: the witness search, "
              "the exact and LP solves and delta(eps) stop at what they have when it is reached, and "
              "the JSON's time_limited is true (computing geodesics or compiling the kernels the first "
              "time is not bounded; they warn when long).  [default: none: the searches run in full, "
              "each solve gets 10 s]")
@click.option("--effort", type=click.Choice(["quick", "default", "thorough"]), default="default",
              show_default=True, help="Work spent by the witness search.")
@click.option("--witness-png", type=OutputFile(), default=None,
              help="Write a picture of the witness map (meshes and point clouds).")
@epsilon_options("")
@click.option("--scale-witness-png", type=OutputFile(), default=None,
              help="Write a picture of the scale-aware witness (the widest self-map within ε).")
@click.option("--html", type=OutputFile(), default=None,
              help="Write a self-contained HTML page of the witness maps (turn the shape, hover vertex ids).")
@json_option
def command(input_spec, **o):
    """How hard is INPUT to match: σ bracket, κ bracket and the witness map."""
    t0 = time.perf_counter()
    n_points, options = api_options(pop_shape_options(o))
    epsilon, source = resolve_epsilon(input_spec, o, n_points, options)
    result = score(input_spec, n_points, landmarks=parse_ids(o["landmarks"]), exact=True if o["exact"] else "auto",
                   upper=o["upper"], time_limit=o["time_limit"], effort=o["effort"], epsilon=epsilon, **options)
    _pictures(result, o["witness_png"], o["scale_witness_png"], o["html"])
    report = {**result.to_dict(), **source}
    report["seconds"] = time.perf_counter() - t0  # everything, geodesics included
    if o["as_json"]:
        emit_json(report)
    else:
        _print(report, result.score)


def _pictures(result, witness_png, scale_witness_png, html) -> None:
    for png, scale in ((witness_png, False), (scale_witness_png, True)):
        if not png:
            continue
        if result.shape.geometry is None:
            info("a witness picture needs a mesh or point cloud; no picture written")
        else:
            result.plot(path=png, scale=scale)
    if html:
        info(f"wrote {result.to_html(html)}")


def _print(report: dict, sc) -> None:
    s, h, k = report["sigma"], report["sigma_hat"], report["kappa"]
    click.echo(f"samples N         {report['n_points']}  (targets M = {report['n_targets']}, {report['target']})")
    click.echo(f"sigma             [{fmt(s['lower'])}, {fmt(s['upper'])}]  exact {fmt(s['exact'])}")
    click.echo(f"sigma_hat         [{fmt(h['lower'])}, {fmt(h['upper'])}]  (sigma * sqrt(N))")
    click.echo(f"kappa             [{fmt(k['lower'])}, {fmt(k['upper'])}]  (Theorem 4.1)")
    click.echo(f"best single swap  {fmt(report['swap_floor'])}")
    moved = int(np.sum(sc.witness != np.arange(sc.n_points)))
    click.echo(f"witness           moves {moved} of {sc.n_points} samples")
    if report["resolution"] is not None:
        r = report["resolution"]
        click.echo(f"resolution        {r['flag']} (sigma {fmt(r['sigma_lo'])} at M={r['n_targets_lo']}, "
                   f"{fmt(r['sigma_hi'])} at M={r['n_targets_hi']}; covering radius {fmt(r['covering_radius'])})")
    d = report["scale"]
    click.echo(f"delta(eps)        {fmt(d['displacement'])} at eps {fmt(d['epsilon'])} (x{fmt(d['amplification'])}): "
               f"the widest self-map distorting distances by at most eps moves the samples "
               f"{fmt(d['displacement'])} RMS ({100 * d['moved']:.0f} % of them"
               + (", an exact isometry)" if d["isometry"] else ")"))
    click.echo(f"eps from          {report['epsilon_source']}")
    click.echo(f"verdict           {report['verdict']}")
    for note in report["notes"]:
        info(f"note: {note}")
    click.echo(f"seconds           {report['seconds']:.2f}")

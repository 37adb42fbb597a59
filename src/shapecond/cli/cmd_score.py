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

from ..api.scores import SCORE_PARAMS, score
from ..jsonable import fmt
from .common import (EPSILON_FROM_OPTION, Command, OutputFile, emit_json, info, json_option, progress_enabled,
                     resolve_epsilon, table_options, table_values)


@click.command("score", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@table_options(SCORE_PARAMS)
@EPSILON_FROM_OPTION
@click.option("--witness-png", type=OutputFile(), default=None,
              help="Write a picture of the witness map (meshes and point clouds).")
@click.option("--scale-witness-png", type=OutputFile(), default=None,
              help="Write a picture of the scale-aware witness (the widest self-map within ε).")
@click.option("--html", type=OutputFile(), default=None,
              help="Write a self-contained HTML page of the witness maps (turn the shape, hover vertex ids).")
@json_option
def command(input_spec, **o):
    """How hard is INPUT to match: σ bracket, κ bracket and the witness map."""
    t0 = time.perf_counter()
    kw = table_values(SCORE_PARAMS, o)  # the options of sc.score (api.scores.SCORE_PARAMS)
    epsilon, source = resolve_epsilon(input_spec, {**o, "epsilon": kw.pop("epsilon")}, kw["n_points"], kw)
    result = score(input_spec, **kw, epsilon=epsilon, progress=progress_enabled())
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

"""``shapecond local INPUT``: local symmetry score sigma_inf for deformation-based matching.

Paper Section 5; ``shapecond.deformation``.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import replace

import click

from ..api import load, local_score
from ..api.guards import guard_local
from ..api.inputs import require_mesh
from ..api.params import IDS_HELP
from ..limits import CostWarning
from ..checks import parse_ids
from ..deformation.energy import ALPHA_RANGE, DEFAULT_ALPHA, ENERGIES
from ..deformation.local_score import ZERO_TOL
from .common import Command, Float, OutputFile, emit_json, force_option, info, json_option


@click.command("local", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@click.option("--landmarks", "-l", default=None,
              help="Vertex ids (the file's own) to fix: " + IDS_HELP + ".")
@click.option("--alpha", type=Float(*ALPHA_RANGE), default=DEFAULT_ALPHA, show_default=True,
              help="Weight of the stretching term against point-to-plane proximity (unit-area mesh).")
@click.option("--energy", type=click.Choice(ENERGIES), default="springs", show_default=True,
              help="Stretching term: edge springs or as-rigid-as-possible.")
@click.option("--zero-tol", type=Float(0.0, 1.0, lo_open=True, hi_open=True), default=ZERO_TOL, show_default=True,
              help="Eigenvalues below zero_tol x 2 count as zero modes (score inf).")
@click.option("--heatmap-png", type=OutputFile(), default=None,
              help="Also draw the local score with each vertex fixed (modal approximation) to this PNG.")
@click.option("--html", type=OutputFile(), default=None,
              help="Self-contained HTML page of the local score with each vertex fixed (the doubt field).")
@force_option
@json_option
def command(input_spec, landmarks, html, heatmap_png, as_json, **o):
    """Local symmetry score sqrt(2 / lambda_min) of the energy Hessian, with its zero modes."""
    t0 = time.perf_counter()
    g = require_mesh(load(input_spec, force=o["force"]))
    guard_local(g.n_vertices, o["force"], doubt=bool(html or heatmap_png), html=bool(html))  # all of it, up front
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CostWarning)  # the parts' own estimates: said above already
        result = local_score(g, parse_ids(landmarks), **o)  # alpha, energy, zero_tol, force
        if html or heatmap_png:
            result.doubt()
    if html:
        info(f"wrote {result.to_html(html)}")
    if heatmap_png:
        result.plot(path=heatmap_png)
        info(f"wrote {heatmap_png}")
    result = replace(result, seconds=time.perf_counter() - t0)  # everything, the doubt field included
    if as_json:
        emit_json(result.to_dict())
        return
    click.echo(f"local score (sigma_inf)  {result.score:.6g}")
    click.echo(f"lambda_min               {result.lambda_min:.6g}")
    click.echo(f"vertices                 {result.n_vertices}")
    click.echo(f"landmarks                {', '.join(map(str, result.landmarks)) or 'none'}")
    for name in result.zero_modes:
        click.echo(f"zero mode                {name}")
    click.echo(f"seconds                  {result.seconds:.2f}")

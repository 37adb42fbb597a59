"""``shapecond demo``: the whole pipeline on the built-in four-legged animal."""

from __future__ import annotations

import time
from pathlib import Path

import click

from ..shapes.metric import metric_shape
from ..shapes.synthetic import animal
from .common import emit_json, fmt, info, json_option, progress_enabled


@click.command("demo")
@click.option("--points", "-n", type=int, default=400, show_default=True, help="Number of samples N.")
@click.option("--delta", type=float, default=0.0, show_default=True,
              help="Asymmetry of the generated animal (0 = exactly mirror-symmetric).")
@click.option("--out", type=click.Path(file_okay=False), default="shapecond-demo", show_default=True,
              help="Folder for the pictures.")
@click.option("--seed", type=int, default=0, show_default=True)
@json_option
def command(points, delta, out, seed, as_json):
    """Sample the generated animal and report its metric shape."""
    t0 = time.perf_counter()
    geometry = animal(delta=delta)
    shape = metric_shape(geometry, n_points=points, seed=seed, progress=progress_enabled())
    summary = {
        "shape": f"demo:animal:delta={delta}",
        "n_vertices": geometry.n_vertices,
        "n_faces": int(geometry.faces.shape[0]),
        "n_points": shape.n_points,
        "metric": shape.metric,
        "backend": shape.backend,
        "diameter": shape.scale,
        "covering_radius": shape.covering_radius,
    }
    summary["seconds"] = time.perf_counter() - t0
    if as_json:
        emit_json(summary)
        return
    click.echo(f"shape            {summary['shape']} ({summary['n_vertices']} vertices, {summary['n_faces']} faces)")
    click.echo(f"samples          N = {shape.n_points}, {shape.metric} distances ({shape.backend} method)")
    click.echo(f"diameter         {fmt(shape.scale)} (distances scaled to 1); covering radius {fmt(shape.covering_radius)}")
    info(f"done in {summary['seconds']:.1f} s")

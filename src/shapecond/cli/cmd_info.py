"""``shapecond info INPUT``: what is in a file, and what is wrong with it."""

from __future__ import annotations

import click

from ..api import info as describe
from .common import Command, emit_json, json_option


@click.command("info", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@json_option
def command(input_spec, as_json):
    """Counts, bounding box, components, boundary edges, isolated vertices, problems."""
    report = describe(input_spec)
    if as_json:
        emit_json(report)
        return
    for key in ("input", "kind", "n_vertices", "n_faces", "components", "boundary_edges", "isolated_vertices"):
        if report.get(key) is not None:
            click.echo(f"{key:18s} {report[key]}")
    if report.get("bounding_box"):
        lo, hi = report["bounding_box"]["min"], report["bounding_box"]["max"]
        click.echo(f"{'bounding_box':18s} [{', '.join(f'{v:.4g}' for v in lo)}] .. [{', '.join(f'{v:.4g}' for v in hi)}]")
    if report["problems"]:
        for p in report["problems"]:
            click.echo(f"problem            {p}")
    else:
        click.echo("problems           none")

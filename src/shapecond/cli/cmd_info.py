"""``shapecond info INPUT``: what is in a file, and what is wrong with it."""

from __future__ import annotations

from pathlib import Path

import click

from ..shapes.geometry import Geometry
from ..shapes.io import MESH_SUFFIXES, load_input, read_mesh_arrays
from ..shapes.validate import inspect_mesh
from .common import emit_json, json_option


def _report(input_spec: str) -> dict:
    path = Path(input_spec)
    if input_spec.startswith("demo:") or path.suffix.lower() not in MESH_SUFFIXES:
        loaded = load_input(input_spec)
        if not isinstance(loaded, Geometry):
            n = loaded.shape[0]
            return {"input": input_spec, "kind": "distance matrix", "n_vertices": n, "n_faces": None,
                    "bounding_box": None, "components": None, "boundary_edges": None,
                    "isolated_vertices": None, "diameter": float(loaded.max()), "problems": []}
        report = inspect_mesh(loaded.vertices, loaded.faces)
    else:  # read raw so that problems are reported instead of raised
        vertices, faces = read_mesh_arrays(path)
        report = inspect_mesh(vertices, faces)
    return {"input": input_spec, **report}


@click.command("info")
@click.argument("input_spec", metavar="INPUT")
@json_option
def command(input_spec, as_json):
    """Counts, bounding box, components, boundary edges, isolated vertices, problems."""
    report = _report(input_spec)
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

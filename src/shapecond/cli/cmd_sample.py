"""``shapecond sample INPUT --points N -o OUT.npz``: the metric shape of the paper."""

from __future__ import annotations

import io
from pathlib import Path

import click
import numpy as np

from ..api.inputs import METRIC_SHAPE_PARAMS, metric_shape
from ..errors import InputError
from ..output import write_bytes
from .common import Command, OutputFile, emit_json, info, json_option, progress_enabled, table_options, table_values


@click.command("sample", cls=Command)
@click.argument("input_spec", metavar="INPUT")
@table_options(METRIC_SHAPE_PARAMS)
@click.option("-o", "--output", required=True, type=OutputFile(), help="Output .npz file.")
@json_option
def command(input_spec, output, as_json, **o):
    """Farthest-point samples and their distance matrix (diameter 1) into an .npz file.

    The file holds D (N x N), samples (the input's vertex ids, in FPS order),
    scale (the raw diameter), metric and backend; every command (and
    ``shapecond.load``) reads it back as a distance-matrix input.
    """
    if o["target"] == "dense":
        raise InputError("sample writes the N samples only; --target dense does not apply")
    if not str(output).endswith(".npz"):
        raise InputError(f"{output}: the output must be an .npz file")
    kw = table_values(METRIC_SHAPE_PARAMS, o)  # the options of sc.metric_shape (api.inputs.METRIC_SHAPE_PARAMS)
    shape = metric_shape(input_spec, **{**kw, "target": "samples"}, progress=progress_enabled())
    buffer = io.BytesIO()  # built in memory: a failing write then never leaves numpy's zip half-open
    np.savez(buffer, D=shape.D, samples=shape.sample_ids, scale=shape.scale, metric=shape.metric,
             backend=str(shape.backend), covering_radius=np.nan if shape.covering_radius is None
             else shape.covering_radius)
    write_bytes(Path(output), buffer.getvalue())
    summary = {"output": str(output), "n_points": shape.n_points, "metric": shape.metric,
               "backend": shape.backend, "scale": shape.scale, "covering_radius": shape.covering_radius,
               "samples": shape.sample_ids}
    if as_json:
        emit_json(summary)
    else:
        info(f"wrote {output}: {shape.n_points} samples, {shape.metric} distances ({shape.backend}), "
             f"diameter {shape.scale:.4g}")

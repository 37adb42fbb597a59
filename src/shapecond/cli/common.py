"""Options and helpers shared by the sub-commands.

``shape_options`` adds the options that turn an INPUT into a metric shape;
``build_shape`` does it; ``emit_json`` prints the one JSON object of ``--json``
(infinite values as the string "inf", missing ones as null).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from pathlib import Path

import click
import numpy as np

from ..errors import InputError
from ..shapes.geometry import Geometry
from ..shapes.io import load_input, read_landmarks, read_symmetry_map
from ..shapes.metric import MetricShape, from_distance_matrix, metric_shape

DEFAULT_POINTS = 400


def error(message: str):
    """Stop with one ``error: message`` line and exit status 2."""
    raise InputError(message)


def info(message: str) -> None:
    """A diagnostic line on stderr (stdout is kept for results)."""
    click.echo(message, err=True)


def progress_enabled() -> bool:
    return sys.stderr.isatty()


def shape_options(f):
    """Options that build the metric shape: --points, --metric, --geodesic-backend, ..."""
    options = [
        click.option("--points", "-n", "points", type=int, default=None,
                     help=f"Number of farthest-point samples N [default: {DEFAULT_POINTS}]."),
        click.option("--metric", type=click.Choice(["geodesic", "euclidean"]), default="geodesic",
                     show_default=True, help="Distance between points."),
        click.option("--geodesic-backend", type=click.Choice(["heat", "fmm", "exact"]), default="heat",
                     show_default=True, help="Geodesic solver (exact needs the 'exact' extra)."),
        click.option("--seed", type=int, default=0, show_default=True, help="Seed of every random choice."),
        click.option("--largest-component", is_flag=True, help="Keep only the largest connected component."),
        click.option("--no-cache", is_flag=True, help="Do not read or write the distance cache."),
        click.option("--target", type=click.Choice(["samples", "dense"]), default=None,
                     help="Where maps may send samples: other samples (the paper) or a denser FPS set "
                          "[default: dense for meshes, samples for a distance matrix]."),
        click.option("--target-factor", type=int, default=8, show_default=True,
                     help="Dense targets: M = factor x N points."),
        click.option("--symmetry-map", type=click.Path(dir_okay=False), default=None,
                     help="A .sym file (line i = 1-based id of the mirror of vertex i): sample in mirror pairs."),
    ]
    for option in reversed(options):
        f = option(f)
    return f


SHAPE_OPTION_NAMES = ("points", "metric", "geodesic_backend", "seed", "largest_component", "no_cache",
                      "target", "target_factor", "symmetry_map")


def pop_shape_options(kwargs: dict) -> dict:
    """Split the shape options out of a command's keyword arguments."""
    return {k: kwargs.pop(k) for k in SHAPE_OPTION_NAMES if k in kwargs}


def parse_ids(text) -> list[int]:
    """``"3,5,9"`` -> [3, 5, 9]; a path to an existing file reads its first column."""
    if text is None:
        return []
    if isinstance(text, (list, tuple)):
        return [int(v) for v in text]
    text = str(text).strip()
    if not text:
        return []
    if Path(text).is_file():
        return [int(v) for v in read_landmarks(text)]
    ids = []
    for tok in text.replace(" ", "").split(","):
        if not tok:
            continue
        try:
            ids.append(int(tok))
        except ValueError:
            raise InputError(f"{tok!r} is not a vertex id (expected e.g. 12,405,877 or a file of ids)") from None
    if any(v < 0 for v in ids):
        raise InputError("vertex ids must be non-negative")
    if len(set(ids)) != len(ids):
        raise InputError(f"landmark ids are repeated: {text}")
    return ids


def load_geometry_or_matrix(input_spec: str, largest_component: bool = False, symmetry_map=None):
    """The user's INPUT as a Geometry (with its symmetry map attached) or a distance matrix."""
    loaded = load_input(input_spec, largest_component=largest_component)
    if symmetry_map is not None:
        if not isinstance(loaded, Geometry):
            raise InputError("--symmetry-map needs a mesh or point cloud input")
        loaded = loaded.with_symmetry(read_symmetry_map(symmetry_map))
    return loaded


def build_shape(input_spec: str, landmarks=(), points=None, metric="geodesic", geodesic_backend="heat", seed=0,
                largest_component=False, no_cache=False, target=None, target_factor=8, symmetry_map=None,
                loaded=None, progress=None) -> MetricShape:
    """Turn INPUT and the shape options into a ``MetricShape``; landmarks (input ids) come first.

    ``progress``: show the sampling's progress bar (default: when stderr is a terminal).
    """
    if loaded is None:
        loaded = load_geometry_or_matrix(input_spec, largest_component, symmetry_map)
    ids = parse_ids(landmarks)
    if isinstance(loaded, np.ndarray):
        n = loaded.shape[0]
        if points is not None and points != n:
            raise InputError(f"--points does not apply to a distance matrix ({n} x {n}); it is used whole")
        if target == "dense":
            raise InputError("--target dense needs a mesh or point cloud, not a distance matrix")
        bad = [v for v in ids if v >= n]
        if bad:
            raise InputError(f"landmark {bad[0]} is out of range for a {n} x {n} distance matrix (rows 0..{n - 1})")
        return from_distance_matrix(loaded, landmarks=ids, name=Path(str(input_spec)).name)
    if target is None:
        target = "dense"
    n_points = DEFAULT_POINTS if points is None else points
    if n_points > loaded.n_vertices and points is None:
        n_points = loaded.n_vertices
    internal = loaded.to_internal(ids)
    return metric_shape(loaded, n_points=n_points, metric=metric, backend=geodesic_backend, seed=seed,
                        landmarks=internal, target=target, target_factor=target_factor, cache=not no_cache,
                        progress=progress_enabled() if progress is None else progress)


def jsonable(obj):
    """Python/JSON values: inf -> "inf", nan/None -> null, numpy -> Python, dataclasses -> dicts."""
    if hasattr(obj, "to_dict"):
        return jsonable(obj.to_dict())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return jsonable(dataclasses.asdict(obj))
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        if math.isnan(v):
            return None
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    if isinstance(obj, Path):
        return str(obj)
    return obj


def emit_json(obj) -> None:
    """Print one JSON object on stdout and nothing else."""
    click.echo(json.dumps(jsonable(obj), allow_nan=False))


def json_option(f):
    return click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")(f)


def fmt(value, digits: int = 4) -> str:
    """Human formatting of a score: inf as ∞, None as '-'."""
    if value is None:
        return "-"
    if isinstance(value, float) and math.isinf(value):
        return "inf"
    return f"{value:.{digits}g}" if isinstance(value, float) else str(value)

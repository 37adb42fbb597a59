"""The table of batch scoring: one row per shape, its columns, their types and meanings.

Every output format holds the same columns in the same order (Parquet types
below; CSV and JSON Lines write lists as JSON arrays, a missing value as an
empty cell / ``null``, and an infinite score as ``inf`` / ``"inf"``).  Values
come from the code paths of the single-shape commands: ``info``
(``shapes.io.describe_input``), ``score`` (``shapecond.api.score``),
``local`` (``deformation.local_score_of_geometry``) and ``landmarks``
(``selection.select_landmarks``) and ``match``
(``shapecond.api.collection.match_to_template``).  A row is identified by its file, the file's
content hash and the parameters (``KEY``): ``--resume`` skips a shape whose
key already has a row.
"""

from __future__ import annotations

import json
from dataclasses import dataclass


@dataclass(frozen=True)
class Column:
    name: str
    type: str          # string, int64, float64, list<int64>, list<float64>
    doc: str


COLUMNS = (
    # what was scored
    Column("file", "string", "absolute path of the shape file (or the demo: specification)"),
    Column("content_hash", "string", "SHA-256 of the file's bytes (.vert and .tri together for TOSCA pairs)"),
    Column("params", "string", "the parameters that shape the results, as sorted compact JSON"),
    Column("version", "string", "shapecond version of the worker that computed the row"),
    # shapecond info
    Column("kind", "string", "mesh, point cloud or distance matrix"),
    Column("vertices", "int64", "vertex count of the file (unreferenced vertices included)"),
    Column("faces", "int64", "face count (empty for point clouds and matrices)"),
    Column("components", "int64", "connected components of the mesh"),
    Column("problems", "string", "problems found by info, joined by '; ' (missing when none)"),
    # shapecond score
    Column("n_points", "int64", "samples N"),
    Column("n_targets", "int64", "targets M (M = N for bijections, M = factor x N for dense targets)"),
    Column("sigma_lower", "float64", "lower end of the global symmetry score bracket (Eq. 5)"),
    Column("sigma_upper", "float64", "upper end of the bracket (inf when no finite upper bound was computed)"),
    Column("sigma_hat", "float64", "size-free score sigma_lower x sqrt(N)"),
    Column("swap_floor", "float64", "score of the best single swap (the bracket is never below it)"),
    Column("resolution", "string", "resolution flag: converged, symmetric within resolution, symmetric, "
                                   "undecided (empty for bijections and matrices)"),
    Column("covering_radius", "float64", "covering radius of the targets, in units of the diameter"),
    Column("witness_moved", "float64", "fraction of the samples the witness map moves"),
    Column("witness_displacement", "float64", "RMS displacement sqrt(d2/N) of the witness, in units of "
                                             "the diameter"),
    # shapecond local (--what local)
    Column("local_score", "float64", "local symmetry score sqrt(2 / lambda_min) (inf with zero modes)"),
    Column("local_lambda_min", "float64", "smallest eigenvalue of the deformation energy's Hessian"),
    Column("local_zero_modes", "string", "names of the zero modes, joined by '; ' (missing when none)"),
    # shapecond landmarks (--what landmarks:K:METHOD)
    Column("landmark_method", "string", "landmark method"),
    Column("landmarks", "list<int64>", "the first K landmarks (file vertex ids), in order"),
    Column("landmark_scores", "list<float64>", "symmetry score after each landmark (local scores for "
                                                "cnbs-local)"),
    # accounting
    Column("seconds", "float64", "wall time of the shape on its worker, reading included"),
    Column("cpu_seconds", "float64", "CPU time of the worker process while it scored the shape (all its "
                                     "threads)"),
    Column("peak_memory_mib", "float64", "peak resident memory of the worker process while it scored "
                                         "the shape (MiB)"),
    Column("worker", "string", "host:pid of the process that computed the row"),
    Column("error", "string", "one-line message when the shape failed (empty otherwise)"),
)
# The scale-aware score δ(ε) of the score report's "scale" entry (shapecond.symmetry.scale).
SCALE_AWARE_COLUMNS: tuple = (
    Column("delta", "float64", "scale-aware score δ(ε): RMS displacement of the widest self-map whose "
                               "RMS distortion (and every landmark row's) stays within ε, in diameters"),
    Column("delta_epsilon", "float64", "the distortion level ε of δ (default: the median sample spacing)"),
    Column("delta_moved", "float64", "fraction of the samples the δ witness moves"),
)

# One template matched to the shape (--what match:TEMPLATE; api.collection.match_to_template).
MATCH_COLUMNS: tuple = (
    Column("match_template", "string", "absolute path of the template matched to the shape"),
    Column("match_direction", "string", "'template to shape': the map gives the shape's vertex id of each "
                                        "template vertex id; 'shape to template' (--both-directions) the "
                                        "other way; with --pairs 'first to second' or 'second to first' "
                                        "(the shapes of a listed line)"),
    Column("map_file", "string", "the map's file (maps/NAME.txt beside the table; one shape id a line)"),
    Column("landmark_pairs", "int64", "landmark pairs used: the labels the shape shares with the template"),
    Column("landmark_labels", "string", "those labels, in the template's order, joined by ' '"),
    Column("bar", "float64", "the map's error bar: mean error it may have, in sqrt(area) of the map's source "
                             "(the template, template to shape); above 0.05 the report says 'annotate more'"),
    Column("bar_epsilon", "float64", "the distortion level ε of the bar (sqrt(area))"),
    Column("bar_epsilon_hat", "float64", "ε̂, the map's own RMS distortion (sqrt(area))"),
    Column("suggest_source_id", "int64", "the next landmark to annotate: vertex id on the map's source "
                                         "(the template, template to shape)"),
    Column("suggest_image_id", "int64", "its provisional image under the map: vertex id on the map's target"),
    Column("suggest_bar_after", "float64", "the bar expected once that landmark is added"),
    Column("match_source", "string", "the map's source: the template, the shape, or a shape of a listed pair"),
    Column("match_target", "string", "the map's target"),
    Column("cycle_error", "float64", "with both directions: mean geodesic distance on the source's samples "
                                     "between each sample and its image under this map then the opposite "
                                     "one (source -> target -> source), sqrt(area) of the source; "
                                     "missing otherwise"),
)

ALL_COLUMNS = COLUMNS + SCALE_AWARE_COLUMNS + MATCH_COLUMNS
NAMES = tuple(c.name for c in ALL_COLUMNS)
TYPES = {c.name: c.type for c in ALL_COLUMNS}
KEY = ("file", "content_hash", "params")


def empty_row() -> dict:
    """A row with every column missing (None)."""
    return dict.fromkeys(NAMES)


def row_key(row: dict) -> tuple:
    return tuple(row[k] for k in KEY)


def coerce(value, type_: str):
    """A value read back from CSV or JSON as the column's Python type (None for missing)."""
    if value is None or value == "":
        return None
    if type_.startswith("list<"):
        items = json.loads(value) if isinstance(value, str) else value
        return [coerce(v, type_[5:-1]) for v in items]
    if type_ == "int64":
        return int(value)
    if type_ == "float64":
        return float(value)  # "inf" and "nan" included
    return str(value)


def coerce_row(raw: dict) -> dict:
    """A full row of column types from a dict read back from a file (unknown keys dropped)."""
    return {name: coerce(raw.get(name), TYPES[name]) for name in NAMES}


def arrow_schema():
    """The pyarrow schema of the Parquet table."""
    import pyarrow as pa

    base = {"string": pa.string(), "int64": pa.int64(), "float64": pa.float64()}
    fields = []
    for c in ALL_COLUMNS:
        t = pa.list_(base[c.type[5:-1]]) if c.type.startswith("list<") else base[c.type]
        fields.append(pa.field(c.name, t))
    return pa.schema(fields)

"""Results as plain JSON values: the one converter behind ``--json`` and every ``to_dict``;
and ``fmt``, the one way a number is printed for people (text output, titles, reports).

``inf`` becomes the string ``"inf"`` (``"-inf"``), NaN and None become ``null``,
numpy scalars and arrays become Python numbers and lists, dataclasses and
objects with ``to_dict`` become dicts, paths become strings.  The output passes
``json.dumps(..., allow_nan=False)``.

Examples
--------
>>> import math, numpy as np
>>> from shapecond.jsonable import jsonable
>>> jsonable({"sigma": math.inf, "witness": np.array([1, 0])})
{'sigma': 'inf', 'witness': [1, 0]}
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np


def jsonable(obj):
    """A JSON-ready copy of ``obj`` (see the module docstring)."""
    if hasattr(obj, "to_dict") and not isinstance(obj, type):
        return jsonable(obj.to_dict())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return jsonable({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)})
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        if math.isnan(v):
            return None
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    if isinstance(obj, np.generic):
        return jsonable(obj.item())
    if isinstance(obj, Path):
        return str(obj)
    return obj


def dumps(obj, indent: int | None = None) -> str:
    """``json.dumps`` of :func:`jsonable` (``obj``) with ``indent``, refusing NaN."""
    return json.dumps(jsonable(obj), allow_nan=False, indent=indent)


def fmt(value, digits: int = 4) -> str:
    """A number for people: ``digits`` significant digits, ``inf`` / ``-inf``, ``-`` for None or NaN."""
    if value is None:
        return "-"
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "-"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return f"{v:.{digits}g}"
    return str(value)

"""shapecond: how hard is a shape to match, why, and where to put landmarks.

Reproduces and extends Ovsjanikov, Huang and Guibas, *A Condition Number for
Non-Rigid Shape Matching*, SGP 2011.  Data flows one way::

    input -> metric shape -> scores -> landmarks -> matching -> evaluation

This package is the front door (``shapecond.api``): ``sc.load``, ``sc.info``,
``sc.metric_shape``, ``sc.score``, ``sc.local_score``, ``sc.landmarks``,
``sc.heatmap``, ``sc.kappa``, ``sc.match``, ``sc.match_collection``, ``sc.deformation_level``,
``sc.SymmetryProblem``, their result types, and ``sc.evaluate`` (the paper's evaluation, ``shapecond.evaluation``).
``sc.landmarks`` is the function; the landmark methods themselves are imported
from the subpackage as ``from shapecond.selection import ...``.
"""

from ._jit_cache import ensure_writable_cache

ensure_writable_cache()
del ensure_writable_cache

import importlib  # noqa: E402

from ._version import __version__  # noqa: E402
from .errors import InputError, OutputError, ShapecondError, TooLargeError  # noqa: E402

#: The front door's names (``shapecond.api``) and ``evaluate`` (``shapecond.evaluation``), imported on first use.
_API = ("DeformationLevel", "HeatMapResult", "KappaResult", "LandmarkResult", "LocalResult", "MatchResult",
        "ScoreResult", "SymmetryProblem", "deformation_level", "heatmap", "info", "kappa", "landmarks", "load", "local_score", "match",
        "match_collection", "metric_shape",
        "score")

__all__ = sorted(_API + ("InputError", "OutputError", "ShapecondError", "TooLargeError", "__version__", "evaluate"))


def __getattr__(name):
    if name in _API:
        value = getattr(importlib.import_module(".api", __name__), name)
    elif name == "evaluate":
        value = importlib.import_module(".evaluation", __name__).evaluate
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))

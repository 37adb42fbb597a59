"""shapecond: how hard is a shape to match, why, and where to put landmarks.

Reproduces and extends Ovsjanikov, Huang and Guibas, *A Condition Number for
Non-Rigid Shape Matching*, SGP 2011.  Data flows one way::

    input -> metric shape -> scores -> landmarks -> matching -> evaluation

This package is the front door (``shapecond.api``): ``sc.load``, ``sc.info``,
``sc.metric_shape``, ``sc.score``, ``sc.local_score``, ``sc.landmarks``,
``sc.heatmap``, ``sc.kappa``, ``sc.match``, ``sc.SymmetryProblem``, their result
types, and ``sc.evaluate`` (the paper's evaluation, ``shapecond.evaluation``).
``sc.landmarks`` is the function; the landmark methods themselves are imported
from the subpackage as ``from shapecond.landmarks import ...``.
"""

from ._jit_cache import ensure_writable_cache

ensure_writable_cache()
del ensure_writable_cache

from ._version import __version__  # noqa: E402
from .api import (HeatMapResult, KappaResult, LandmarkResult, LocalResult, MatchResult, ScoreResult,  # noqa: E402
                  SymmetryProblem, heatmap, info, kappa, landmarks, load, local_score, match, metric_shape, score)
from .errors import InputError, OutputError, ShapecondError, TooLargeError  # noqa: E402
from .evaluation import evaluate  # noqa: E402

__all__ = ["HeatMapResult", "InputError", "KappaResult", "LandmarkResult", "LocalResult", "MatchResult",
           "OutputError", "ScoreResult", "ShapecondError", "SymmetryProblem", "TooLargeError", "__version__",
           "evaluate", "heatmap", "info", "kappa", "landmarks", "load", "local_score", "match", "metric_shape",
           "score"]

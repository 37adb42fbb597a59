"""shapecond: how hard is a shape to match, why, and where to put landmarks.

Reproduces and extends Ovsjanikov, Huang and Guibas, *A Condition Number for
Non-Rigid Shape Matching*, SGP 2011.  Data flows one way::

    input -> metric shape -> scores -> landmarks -> matching -> evaluation

The Python interface is ``import shapecond as sc``: ``sc.load``,
``sc.metric_shape``, ``sc.score``, ``sc.local_score``, ``sc.landmarks``,
``sc.heatmap``, ``sc.match``, ``sc.evaluate`` and ``sc.SymmetryProblem``
(``shapecond.api``).  ``sc.landmarks`` is the function; the subpackage of the
landmark methods is imported as ``from shapecond.landmarks import ...``.
"""

from ._jit_cache import ensure_writable_cache

ensure_writable_cache()
del ensure_writable_cache

from importlib.metadata import PackageNotFoundError, version as _version  # noqa: E402

try:
    __version__ = _version("shapecond")
except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
    __version__ = "0+unknown"

from . import landmarks as _landmark_methods  # noqa: E402,F401  (loaded first: the name below is the function)
from .api import (HeatMapResult, MatchResult, SymmetryProblem, evaluate, heatmap,  # noqa: E402
                  landmarks, load, local_score, match, metric_shape, score)
from .errors import InputError, OutputError, TooLargeError  # noqa: E402

__all__ = ["HeatMapResult", "InputError", "MatchResult", "OutputError", "SymmetryProblem", "TooLargeError",
           "__version__", "evaluate", "heatmap", "landmarks", "load", "local_score", "match", "metric_shape",
           "score"]
